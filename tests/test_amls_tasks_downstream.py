"""The AMLS bases of the modal receptance, the random response and the modal transient
(``modal.solver: amls``) reduced as tasks: the same results bit for bit whether each tree
level runs in this process or on a 2-worker Dask LocalCluster (127.0.0.1); ``substruct run
--workers 2`` accepts a modal-receptance AMLS case and writes the in-process receptances, and
still refuses a case with neither an AMLS reduction nor a Monte Carlo study (exit 2, one line,
nothing written).

The model: the two tied boxes of ``tests/two_boxes.py`` (624 coordinates, leaves of at most
100, so each reduction is a tree of several levels).  The Dask runs are in one subprocess of
their own (Dask's threads stay out of pytest; one cluster for the three analyses), with one
BLAS thread in the subprocess and in the workers, as in ``tests/test_amls_tasks.py``.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from counting_tasks import COUNTING
from two_boxes import AMLS_TRANSIENT, two_boxes_case

ROOT = Path(__file__).resolve().parent.parent
ENV = {**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1",
       "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "MPLBACKEND": "Agg"}
POINTS = '["right@4,0.5,0.5:z", "left@1,0.5,0.5:y"]'
AMLS = "amls: {cutoff: 5, leaf_size: 100}"

CASES = {
    "frf": two_boxes_case("boxes_frf", f"""\
  frf:
    omega: {{start: 100, stop: 3000, num: 30}}
    inputs: ["right@4,0.5,0.5:z"]
    outputs: {POINTS}
    method: modal
    tolerance: 1e-2
    modal: {{solver: amls, cutoff: 3, {AMLS}}}
""", rayleigh="[2.0, 2.0e-6]"),
    "random": two_boxes_case("boxes_random", f"""\
  random:
    frequencies: {{start: 5, stop: 600, num: 60}}
    rms_tolerance: 1.0        # a coarse grid: the PSDs are compared bit for bit on it
    outputs: {POINTS}
    forces:
      - {{at: "right@4,0.5,0.5:z", psd: [[5, 1.0], [600, 1.0]]}}
      - {{at: "right@3,0.5,0.5:y", psd: [[5, 2.0], [600, 0.5]]}}
    method: modal
    tolerance: 1.0
    modal: {{solver: amls, cutoff: 3, {AMLS}}}
""", rayleigh="[5.0, 2.0e-5]"),
    "transient": two_boxes_case("boxes_transient", AMLS_TRANSIENT),
}

# each case run in this process, then through a 2-worker LocalCluster (its tasks counted, so
# a basis that did not go through them is seen); the results of both saved
SCRIPT = COUNTING + """
import sys
import numpy as np
from substruct.case.loader import load_case
from substruct.run.runner import run_case
from substruct.studies.study_backend import Backend, Session
out, paths = sys.argv[1], sys.argv[2:]
saved = {}
with Session(Backend(workers=2)) as s:
    for path in paths:
        where = Counting(s)
        case = load_case(path)
        for tag, tasks in (("serial", None), ("dask", where)):
            r = run_case(case, tasks=tasks)
            name = case.name
            if r.frf is not None:
                saved[f"{name}_{tag}_H"] = np.asarray(r.frf.H)
            if r.random is not None:
                saved[f"{name}_{tag}_psd"] = r.random.psd
                saved[f"{name}_{tag}_rms"] = r.random.rms
            if r.transient is not None:
                tr = r.transient
                for key in ("displacement", "velocity", "acceleration"):
                    saved[f"{name}_{tag}_{key}"] = getattr(tr, key)
        saved[f"{case.name}_calls"] = np.array(where.counts())
np.savez(out, **saved)
"""


def _write(tmp: Path, what: str) -> Path:
    path = tmp / f"{what}.yaml"
    path.write_text(CASES[what])
    return path


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """The three cases in process and on one 2-worker LocalCluster (one subprocess)."""
    tmp = tmp_path_factory.mktemp("amls_downstream")
    out = tmp / "runs.npz"
    done = subprocess.run([sys.executable, "-c", SCRIPT, str(out),
                           *(str(_write(tmp, w)) for w in CASES)],
                          capture_output=True, text=True, env=ENV, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    return dict(np.load(out))


def _same(runs, name: str, keys: tuple[str, ...]) -> None:
    # the blocks of a reduction went to the cluster, the separators fed by their children's
    # futures, and the expansion through its map
    maps, submits, chained = runs[f"{name}_calls"]
    assert maps >= 1 and submits >= 3 * 7 - 1 and chained >= 3 + 2 * 7 - 1, (maps, submits)
    for key in keys:
        a, b = runs[f"{name}_serial_{key}"], runs[f"{name}_dask_{key}"]
        assert a.shape == b.shape and a.size and np.all(np.isfinite(a)), key
        assert np.array_equal(a, b), (key, np.abs(a - b).max())


def test_modal_receptance_on_tasks_is_the_same_bits(runs):
    _same(runs, "boxes_frf", ("H",))


def test_random_response_on_tasks_is_the_same_bits(runs):
    _same(runs, "boxes_random", ("psd", "rms"))


def test_modal_transient_on_tasks_is_the_same_bits(runs):
    _same(runs, "boxes_transient", ("displacement", "velocity", "acceleration"))


def _cli(tmp_path: Path, case: Path, name: str):
    args = [sys.executable, "-m", "substruct.cli", "run", str(case), "--out",
            str(tmp_path / name), "--workers", "2"]
    return subprocess.run(args, capture_output=True, text=True, timeout=600,
                          env={**ENV, "SUBSTRUCT_PROGRESS": "1"}, cwd=tmp_path)


def test_run_with_workers_takes_a_modal_amls_receptance(tmp_path, runs):
    h5py = pytest.importorskip("h5py")
    done = _cli(tmp_path, _write(tmp_path, "frf"), "dask")
    assert done.returncode == 0, done.stderr[-3000:]
    assert "AMLS tasks on LocalCluster (2 workers)" in done.stderr
    with h5py.File(tmp_path / "dask" / "boxes_frf.h5", "r") as f:
        H = f["frf"]["H"][()]
    assert np.array_equal(H, runs["boxes_frf_serial_H"])


def test_run_with_workers_refuses_a_case_without_tasks(tmp_path):
    case = tmp_path / "direct.yaml"
    case.write_text(CASES["frf"].replace("method: modal", "method: kkt").replace(
        f"    modal: {{solver: amls, cutoff: 3, {AMLS}}}\n", ""))
    done = _cli(tmp_path, case, "direct")
    assert done.returncode == 2
    assert done.stderr.strip() == ("substruct: error: --workers: runs the blocks of an AMLS "
                                   "reduction or the samples of a virtual-point Monte Carlo "
                                   "study as tasks; the case has no virtual_points.monte_carlo"
                                   " and no solver: amls in analysis.modes or the modal block "
                                   "of analysis.frf, random or transient, got no modal "
                                   "analysis")
    assert not (tmp_path / "direct").exists()
