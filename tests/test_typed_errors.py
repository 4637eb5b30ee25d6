"""Typed errors end to end, and a system whose constraints hold every coordinate.

Bad input is a :class:`~substruct.case.errors.CaseError` (exit 2) naming the case field; a
disagreement of the checks a :class:`~substruct.analysis.errors.CheckError` (exit 1, one line);
anything else, a plain ``ValueError`` from an analysis included, an internal error (exit 1 with
its traceback): a bug never passes as bad input.

Two 1-DOF parts tied together and grounded leave no free coordinate: the exact receptance is
zero and there is no mode.  The formulations then return rounding of zero, which is judged
against the compliance scale of the problem, never against ``max |H|`` (itself rounding).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
import yaml

import substruct
import substruct.analysis.api as api
import substruct.run.analyses as analyses
from substruct.analysis.checks import compliance_scale, receptance_difference
from substruct.analysis.errors import AnalysisInputError, CheckError

from cli_helpers import assert_one_line_error, run

CASES = Path(__file__).resolve().parents[1] / "cases"
EPS = np.finfo(float).eps
NO_PICTURES = ("--set", "output.pictures=false")

HELD = {
    "name": "tied_grounded",
    "substructures": [
        {"name": "P", "type": "matrices", "M": [[1.0]], "K": [[10.0]], "C": [[0.5]],
         "labels": ["q"]},
        {"name": "Q", "type": "matrices", "M": [[2.0]], "K": [[20.0]], "labels": ["q"]}],
    "constraints": [{"name": "tie", "terms": {"P@q": 1, "Q@q": -1}},
                    {"name": "ground", "terms": {"P@q": 1}}],
    "analysis": {
        "modes": {"count": 1, "method": "generalized-inverse", "check": ["null-space", "kkt"]},
        "frf": {"omega": [0.5, 2.0, 7.0], "inputs": ["P@q", "Q@q"], "outputs": ["P@q", "Q@q"],
                "method": "generalized-inverse", "check": ["null-space", "kkt"]}},
    "output": {"pictures": False},
}


def _run(capsys, tmp_path, case=CASES / "three_dof_frf.yaml", *extra):
    out = tmp_path / "out"
    code, stdout, stderr = run(capsys, "run", case, "--out", out, *NO_PICTURES, *extra)
    return code, stdout, stderr, out


# ------------------------------------------------------------------------- typed errors


@pytest.mark.parametrize("name", ["modes", "receptance_sweep"])
def test_a_plain_value_error_from_an_analysis_is_internal_not_bad_input(
        tmp_path, capsys, monkeypatch, name):
    def broken(*args, **kwargs):
        raise ValueError("operands could not be broadcast together")
    monkeypatch.setattr(analyses, name, broken)
    code, stdout, stderr, out = _run(capsys, tmp_path)
    assert code == 1, stderr
    assert "Traceback" in stderr
    assert stderr.splitlines()[-1].startswith(
        "substruct: internal error: ValueError: operands could not be broadcast together")
    assert stdout == ""
    assert not out.exists() or not any(out.iterdir())


@pytest.mark.parametrize("name, field", [("modes", "analysis.modes"),
                                         ("receptance_sweep", "analysis.frf")])
def test_an_analysis_input_error_is_bad_input_naming_the_field(tmp_path, capsys, monkeypatch,
                                                               name, field):
    def refuse(*args, **kwargs):
        raise AnalysisInputError("the receptance is singular at omega = 2 rad/s")
    monkeypatch.setattr(analyses, name, refuse)
    code, stdout, stderr, out = _run(capsys, tmp_path)
    assert_one_line_error(code, stdout, stderr, f"three_dof_frf.yaml: {field}: the receptance "
                          "is singular at omega = 2 rad/s")
    assert not out.exists() or not any(out.iterdir())


def test_a_singular_system_found_by_the_analysis_is_exit_2(tmp_path, capsys):
    """A real analysis-level refusal: eq 15 at omega = 0 on a model with a rigid-body motion
    (two free masses tied: no stiffness at all)."""
    case = {"name": "free", "substructures": [
        {"name": "P", "type": "matrices", "M": [[1.0]], "K": [[0.0]], "labels": ["q"]},
        {"name": "Q", "type": "matrices", "M": [[3.0]], "K": [[0.0]], "labels": ["q"]}],
        "constraints": [{"name": "tie", "terms": {"P@q": 1, "Q@q": -1}}],
        "analysis": {"frf": {"omega": [0.0], "inputs": ["P@q"], "outputs": ["Q@q"],
                             "method": "kkt"}}, "output": {"pictures": False}}
    path = tmp_path / "free.yaml"
    path.write_text(yaml.safe_dump(case))
    code, stdout, stderr, out = _run(capsys, tmp_path, path)
    assert_one_line_error(code, stdout, stderr, "free.yaml: analysis.frf:", "singular")
    assert not out.exists() or not any(out.iterdir())


def test_an_analysis_input_error_is_a_value_error_for_api_users():
    """``except ValueError`` in a user's script still catches bad input of the API."""
    assert issubclass(AnalysisInputError, ValueError)
    with pytest.raises(AnalysisInputError, match="singular at omega = 0"):
        api.receptance_sweep(np.diag([1.0, 0.0]), np.eye(2), None, None, [0.0],
                             np.eye(2), np.eye(2), method="generalized-inverse")


# ------------------------------------------------- a system with no free coordinate


def test_a_fully_constrained_system_runs_with_zero_receptances_and_no_mode():
    result = substruct.run_case(substruct.load_case(HELD))
    assert len(result.modes.omega) == 0
    assert "no free coordinate: the constraints hold all 2 coordinates" in result.modes.solver
    frf = result.frf
    assert frf.H.shape == (3, 2, 2) and not np.any(frf.H)  # exactly zero
    # every figure is rounding of zero against h0: a few c n eps, far below the tolerance
    assert set(frf.agreement) == {"null-space", "kkt", "exact-zero"}
    assert max(frf.agreement.values()) <= 64 * 2 * EPS, frf.agreement


@pytest.mark.parametrize("method", ["generalized-inverse", "null-space", "kkt", "modal"])
@pytest.mark.parametrize("scale", [1e-25, 1.0, 1e25])
def test_the_zero_receptance_holds_at_any_scale_and_method(method, scale):
    """Scaling K, M, C by ``scale`` scales h0 by ``1/scale``: the figures do not move."""
    case = yaml.safe_load(yaml.safe_dump(HELD))
    for part in case["substructures"]:
        for key in ("M", "K", "C"):
            if key in part:
                part[key] = [[v * scale for v in row] for row in part[key]]
    case["analysis"]["frf"]["method"] = method
    case["analysis"]["frf"]["check"] = [m for m in ("generalized-inverse", "null-space", "kkt")
                                        if m != method]
    frf = substruct.run_case(substruct.load_case(case)).frf
    assert not np.any(frf.H)
    assert max(frf.agreement.values()) <= 64 * 2 * EPS, frf.agreement


def test_the_fully_constrained_case_on_the_command_line(tmp_path, capsys):
    path = tmp_path / "held.yaml"
    path.write_text(yaml.safe_dump(HELD))
    code, stdout, stderr, out = _run(capsys, tmp_path, path)
    assert code == 0, stderr
    assert "no mode: no free coordinate: the constraints hold all 2 coordinates" in stdout
    assert "no free coordinate: the constraints hold every coordinate, every receptance is " \
           "exactly zero" in stdout
    assert (out / "tied_grounded.h5").exists()


def test_a_main_formulation_off_zero_beyond_the_scale_still_fails(monkeypatch):
    """The absolute comparison is not a pass for everything: a main formulation that returns
    1e-3 h0 where the exact answer is zero fails its exact-zero figure."""
    K, M = np.diag([10.0, 20.0]), np.diag([1.0, 2.0])
    A = np.array([[1.0, -1.0], [1.0, 0.0]])
    w = np.array([1.0, 2.0])
    E, O = np.eye(2), np.eye(2)
    h0 = compliance_scale(K, M, None, w, E, O)
    assert h0 == pytest.approx(1.0 / (20.0 + 2.0))  # |K|_inf + w^2 |M|_inf at the lowest w
    real = api.receptance_of

    def off(system, w, method, *args, **kw):
        H = real(system, w, method, *args, **kw)
        return H + 1e-3 * h0 if method == "generalized-inverse" else H
    monkeypatch.setattr(api, "receptance_of", off)
    with pytest.raises(CheckError, match=r"frf: .* disagrees with generalized-inverse by "
                                         r"1\.0e-03"):
        api.receptance_sweep(K, M, None, A, w, E, O, method="generalized-inverse",
                             checks=["kkt"], tolerance=1e-6)


def test_compliance_scale_follows_the_data():
    K = sp.csr_array(np.array([[2.0, -1.0], [-1.0, 1.0]]))
    M, C = sp.eye_array(2), 0.1 * sp.eye_array(2)
    E, O = np.array([[1.0], [0.0]]), np.array([[0.0, 1.0]])
    w = np.array([3.0, 0.5])
    h0 = compliance_scale(K, M, C, w, E, O)
    assert h0 == pytest.approx(1.0 / (3.0 + 0.25 + 0.05))  # the most compliant frequency
    assert compliance_scale(7 * K, 7 * M, 7 * C, w, E, O) == pytest.approx(h0 / 7)
    assert compliance_scale(K, M, C, w, 5 * E, 3 * O) == pytest.approx(15 * h0)
    # without a floor the figure is relative, as before
    H = np.full((1, 1, 1), 2.0)
    assert receptance_difference(H * (1 + 1e-3), H) == pytest.approx(1e-3)
    assert receptance_difference(H * (1 + 1e-3), H, floor=1e-9) == pytest.approx(1e-3)
