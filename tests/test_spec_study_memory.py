"""A tracked study keeps the mode shapes of every sample (16 bytes a value, coordinates x
modes): once the case as written is built its size is known, and a study whose shapes would
not fit the memory available is refused in one line (exit 2) before any sample runs."""

from pathlib import Path

import pytest
import yaml

from cli_helpers import run
from substruct.case import fields
from substruct.case.errors import CaseError
from substruct.case.loader import load_case
from substruct.studies import study_run

#: A fixed-free rod of 1,000 P1 elements (1,000 coordinates), a million samples of EA
#: collecting and tracking 4 modes.
CASE = {
    "name": "rod_tracked",
    "units": "N, m, kg, s",
    "parameters": {"EA0": 1.0e6},
    "substructures": [{"name": "rod", "type": "rod", "length": 1.0, "EA": "EA0", "m": 1.0,
                       "support": "fixed-free",
                       "discretization": {"method": "fe", "elements": 1000}}],
    "analysis": {"modes": {"count": 4}},
    "study": {"grid": {"parameters": [{"parameter": "EA0", "start": 1.0e6, "stop": 2.0e6,
                                       "num": 1_000_000}]},
              "collect": {"frequencies": 4, "track": True}},
}
#: Bytes per sample: the parameter and time, the overhead, 3 x 4 reals, and the shapes.
PER_SAMPLE = 8 * 2 + 512 + 8 * 3 * 4 + 16 * 1000 * 4
NEED = 1_000_000 * PER_SAMPLE  # 64.6 GB


def write(tmp_path: Path) -> Path:
    path = tmp_path / "rod_tracked.yaml"
    path.write_text(yaml.safe_dump(CASE))
    return path


def test_the_estimate_counts_the_shapes(tmp_path):
    spec = load_case(write(tmp_path)).study
    assert spec.memory(0, 1000) == NEED
    assert spec.memory(0, 0) == 1_000_000 * (PER_SAMPLE - 16 * 1000 * 4)


def test_refused_before_any_sample(capsys, tmp_path, monkeypatch):
    """Available memory 50 GB (> the 4 GB floor, < 64.6 GB needed): one line naming
    study.collect.track, exit 2, no sample task made, nothing written."""
    monkeypatch.setattr(fields, "available_memory", lambda: 50e9)

    def no_samples(*args, **kwargs):
        raise AssertionError("samples made before the memory check")
    monkeypatch.setattr(study_run, "study_tasks", no_samples)
    path = write(tmp_path)
    out = tmp_path / "out"
    code, stdout, stderr = run(capsys, "study", path, "--out", out, "--no-pictures")
    assert code == 2 and stdout == "", stderr
    assert stderr.count("\n") == 1 and "Traceback" not in stderr
    assert stderr.startswith(f"substruct: error: {path}: study.collect.track: 1,000,000 "
                             "samples keeping the shapes of 4 modes over 1,000 coordinates "
                             "would need about 64.6 GB of memory, more than the 50 GB "
                             "available"), stderr
    assert not out.exists() or not any(out.iterdir())


def test_accepted_when_it_fits(tmp_path, monkeypatch):
    """The same study passes the check with 70 GB available (64.6 GB needed), and is refused
    with one byte less than it needs."""
    case = load_case(write(tmp_path))
    monkeypatch.setattr(fields, "available_memory", lambda: 70e9)
    study_run.check_tracked_memory(case, 1000)
    monkeypatch.setattr(fields, "available_memory", lambda: NEED - 1.0)
    with pytest.raises(CaseError, match="study.collect.track"):
        study_run.check_tracked_memory(case, 1000)
