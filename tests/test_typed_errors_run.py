"""Typed errors in the run layer and the builder: only the typed input errors (the analysis'
:data:`~substruct.analysis.errors.INPUT_ERRORS`, its
:class:`~substruct.analysis.transient.initial.InitialStateError`, a singular FRF interface
found by factorizing it again, the case layer's readers) become bad input (exit 2, one line
naming the field); a plain ``ValueError`` from anywhere else (here: internals patched to
fail the way a bug does) is an internal error (exit 1, its traceback), never bad input.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
import yaml

import substruct.builder.model as builder_model
import substruct.run.frf_route as frf_route
import substruct.run.transient_run as transient_run

from cli_helpers import assert_one_line_error, run

DATA = Path(__file__).resolve().parent / "bad_cases" / "data"
BUG = "operands could not be broadcast together with shapes (3,) (4,)"

TRANSIENT = {
    "name": "two_masses",
    "substructures": [{"name": "m", "type": "matrices", "M": [[1.0, 0.0], [0.0, 2.0]],
                       "K": [[300.0, -100.0], [-100.0, 100.0]]}],
    "analysis": {"transient": {"t_end": 0.05, "dt": 0.01, "outputs": ["m@2"],
                               "loads": [{"point": "m@2", "shape": "ramp", "amplitude": 1.0,
                                          "duration": 0.02}]}},
    "output": {"pictures": False},
}

FRF = {
    "name": "measured_part",
    "substructures": [{"name": "P", "type": "matrices", "M": [[1.0]], "K": [[1000.0]]},
                      {"name": "meas", "type": "frf", "file": "frf_part.npz"}],
    "connections": [["P@q1", "meas@1:x"]],
    "analysis": {"frf": {"omega": [1.0, 2.0, 3.0], "inputs": ["meas@2:x"],
                         "outputs": ["meas@2:x"]}},
    "output": {"pictures": False},
}


def _case(tmp_path: Path, case: dict) -> Path:
    tmp_path.mkdir(parents=True, exist_ok=True)
    path = tmp_path / f"{case['name']}.yaml"
    path.write_text(yaml.safe_dump(case))
    if any(s.get("type") == "frf" for s in case["substructures"]):
        shutil.copy(DATA / "frf_part.npz", tmp_path / "frf_part.npz")
    return path


def _run(capsys, tmp_path, case):
    out = tmp_path / "out"
    code, stdout, stderr = run(capsys, "run", _case(tmp_path, case), "--out", out)
    return code, stdout, stderr, out


def _assert_internal(code, stdout, stderr, out):
    assert code == 1, stderr
    assert "Traceback" in stderr
    assert stderr.splitlines()[-1].startswith(f"substruct: internal error: ValueError: {BUG}")
    assert not out.exists() or not any(out.iterdir())


def _broken(*args, **kwargs):
    raise ValueError(BUG)


def test_the_cases_run(tmp_path, capsys):
    """The two cases the patched runs start from run as they are (exit 0)."""
    for case in (TRANSIENT, FRF):
        code, stdout, stderr, out = _run(capsys, tmp_path / case["name"], case)
        assert code == 0, stderr
        assert (out / f"{case['name']}.h5").is_file()


@pytest.mark.parametrize("module, name, case", [
    (transient_run, "transient", TRANSIENT),  # the analysis itself
    (transient_run, "step_pairs", TRANSIENT),  # the jumps of the loads
    (transient_run, "merge_pairs", TRANSIENT),
    (frf_route, "couple_selected", FRF),  # LM-FBS: the interface is regular, so a ValueError is a bug
    (builder_model, "assemble", TRANSIENT),  # the stacking of the parts
])
def test_a_plain_value_error_inside_is_an_internal_error(tmp_path, capsys, monkeypatch,
                                                         module, name, case):
    monkeypatch.setattr(module, name, _broken)
    _assert_internal(*_run(capsys, tmp_path, case))


def test_a_repeated_connection_to_an_frf_part_is_bad_input(tmp_path, capsys):
    """The same pair joined twice: B Y B^T has two equal rows, singular at every frequency."""
    case = dict(FRF, connections=[["P@q1", "meas@1:x"], ["meas@1:x", "P@q1"]])
    code, stdout, stderr, out = _run(capsys, tmp_path, case)
    assert_one_line_error(code, stdout, stderr, "measured_part.yaml: connections: the interface "
                          "receptance B Y B^T is singular at omega = 1 rad/s",
                          'got [["P@q1", "meas@1:x"], ["meas@1:x", "P@q1"]]')
    assert not out.exists() or not any(out.iterdir())


def test_the_singular_interface_is_found_by_factorizing_it(tmp_path):
    """:func:`singular_interface` names the first singular frequency, and none for a regular
    interface (so that a ValueError of the coupling is re-raised as a bug)."""
    from substruct.builder.frf_parts import split_frf_case
    from substruct.case.loader import load_case

    case = load_case(_case(tmp_path, FRF))
    split = split_frf_case(case)
    first = frf_route.FrfPart("model", split.parts[0].omega, ["P@q1"],
                              (1.0 / (1000.0 - split.parts[0].omega ** 2)).reshape(-1, 1, 1)
                              + 0j)
    pairs = [("model@P@q1", "meas@1:x")]  # stacked labels: "<part>@<label>"
    assert frf_route.singular_interface([first, *split.parts], pairs) is None
    assert frf_route.singular_interface([first, *split.parts], pairs * 2) == 1.0


MECHANISM = {  # m@2 has neither stiffness nor constraint: a mechanism under a held support
    "name": "mechanism",
    "substructures": [{"name": "m", "type": "matrices", "M": [[1.0, 0.0], [0.0, 1.0]],
                       "K": [[0.0, 0.0], [0.0, 0.0]]}],
    "constraints": [{"terms": {"m@1": 1.0}}],
    "analysis": {"transient": {"t_end": 0.05, "dt": 0.01, "outputs": ["m@2"],
                               "base": {"at": ["m@1"],
                                        "displacement": {"shape": "step", "amplitude": 0.01}}}},
    "output": {"pictures": False},
}
MASSLESS = {  # m@2 has no mass, no stiffness and no constraint
    "name": "massless",
    "substructures": [{"name": "m", "type": "matrices", "M": [[1.0, 0.0], [0.0, 0.0]],
                       "K": [[1.0, 0.0], [0.0, 0.0]]}],
    "analysis": {"transient": {"t_end": 0.05, "dt": 0.01, "outputs": ["m@2"],
                               "loads": [{"point": "m@1"}]}},
    "output": {"pictures": False},
}


@pytest.mark.parametrize("case, problem", [
    (MECHANISM, "the influence vector of the ground motion is not determined"),
    (MASSLESS, "a massless coordinate held neither by a constraint nor by a stiffness")])
def test_input_the_transient_analysis_refuses_stays_bad_input(tmp_path, capsys, case, problem):
    code, stdout, stderr, out = _run(capsys, tmp_path, case)
    assert_one_line_error(code, stdout, stderr, f"{case['name']}.yaml: analysis.transient: ",
                          problem)
    assert not out.exists() or not any(out.iterdir())
