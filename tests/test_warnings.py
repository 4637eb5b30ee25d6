"""No warning leaks out of a run, and an overflow is an error, never a table of ``inf``.

The shipped cases run with ``RuntimeWarning`` and ``ComplexWarning`` turned into errors (a
leaked warning is a computation that went wrong silently: an overflow, an ``inf - inf``, an
imaginary part dropped); a result that holds ``inf`` or ``NaN`` fails in one line (exit 1) with
nothing written.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest

import substruct
import substruct.analysis.api as api
from substruct.analysis.checks import require_finite
from substruct.analysis.errors import CheckError
from substruct.analysis.modes.pencil import rayleigh_root

from cli_helpers import run

CASES = Path(__file__).resolve().parents[1] / "cases"
STRICT = [pytest.mark.filterwarnings("error::RuntimeWarning"),
          pytest.mark.filterwarnings("error::numpy.exceptions.ComplexWarning")]
#: The shipped cases (each a few seconds: modes, receptances, transients).
SHIPPED = sorted(p.name for p in CASES.glob("*.yaml"))


@pytest.mark.parametrize("name", SHIPPED)
@STRICT[0]
@STRICT[1]
def test_the_shipped_cases_run_without_a_warning(name):
    start = time.perf_counter()
    result = substruct.run_case(substruct.load_case(CASES / name, ["output.pictures=false"]))
    assert any(x is not None for x in (result.modes, result.frf, result.transient, result.random))
    assert time.perf_counter() - start < 120  # quick cases only: this is a smoke test


@pytest.mark.parametrize("name", ["three_dof_frf.yaml", "box_beam_tmd.yaml"])
@STRICT[0]
@STRICT[1]
def test_the_command_with_pictures_leaks_no_warning(tmp_path, capsys, name):
    code, _, stderr = run(capsys, "run", CASES / name, "--out", tmp_path)
    assert code == 0, stderr
    assert "Warning" not in stderr and "warning" not in stderr
    assert list(tmp_path.glob("*.png"))


@STRICT[0]
def test_the_rayleigh_refinement_of_a_huge_root_does_not_overflow():
    """f(x) = x^2 - 1e200 x: a^2 x^2 overflows unscaled (1e400); the scaled Newton step keeps
    the root 1e200 to rounding and raises no RuntimeWarning."""
    root, kept = rayleigh_root(1e200 * (1 + 1e-9), 1.0, -1e200, 0.0)
    assert kept and root == pytest.approx(1e200, rel=4 * np.finfo(float).eps)
    assert rayleigh_root(np.inf, 1.0, 1.0, 1.0) == (np.inf, False)
    assert rayleigh_root(0.0, 1.0, 1.0, 0.0) == (0.0, False)


@STRICT[0]
@STRICT[1]
def test_roots_spanning_1e60_fail_a_check_without_a_warning():
    """Masses and stiffnesses of 1e-30 with a damper of 1: roots of -1e30 and -1e-30, beyond
    what the companion pencil carries in double precision; the formulations disagree, which is
    said in one line (CheckError), not in a stream of RuntimeWarnings."""
    sets = [f"parameters.{p}=1e-30" for p in ("k1", "k2", "k3", "m1", "m2", "m3")]
    case = substruct.load_case(CASES / "three_dof_frf.yaml",
                               sets + ["parameters.c=1.0", "output.pictures=false"])
    with pytest.raises(CheckError, match="modes: .* disagrees with"):
        substruct.run_case(case)


def test_require_finite_names_the_array_and_the_count():
    require_finite("frf", H=np.ones((2, 2), complex), empty=np.zeros(0))
    H = np.ones((3, 2, 3), complex)
    H[1, 0, 2] = np.inf
    H[2, 1, 1] = complex(np.nan, 0.0)
    with pytest.raises(CheckError, match=r"^frf: 2 of 18 values of H are inf or NaN"):
        require_finite("frf", H=H)


def test_an_overflow_in_the_receptances_is_one_line_exit_1_nothing_written(
        tmp_path, capsys, monkeypatch):
    real = api.receptance_of

    def overflow(*args, **kwargs):
        H = real(*args, **kwargs)
        H[0, 0, 0] = complex(np.inf, 0.0)
        return H
    monkeypatch.setattr(api, "receptance_of", overflow)
    out = tmp_path / "out"
    code, stdout, stderr = run(capsys, "run", CASES / "three_dof_frf.yaml", "--out", out,
                               "--set", "analysis.frf.check=[]", "--set",
                               "output.pictures=false")
    assert code == 1
    assert stderr.startswith("substruct: error: frf: 1 of ") and stderr.count("\n") == 1
    assert "inf or NaN" in stderr and "Traceback" not in stderr
    assert "inf" not in stdout  # no table of inf
    assert not out.exists() or not any(out.iterdir())


@pytest.mark.filterwarnings("error::RuntimeWarning")
def test_a_transient_whose_histories_overflow_is_one_line_exit_1_nothing_written(
        tmp_path, capsys):
    """exp(1000 t) stays finite as a load but its response and energy overflow: one line,
    exit 1, no RuntimeWarning printed first, nothing written."""
    text = (CASES.parent / "tests" / "bad_cases" / "transient_expression_overflow.yaml").read_text()
    case = tmp_path / "overflow.yaml"
    case.write_text(text.replace("exp(2000", "exp(1000"))
    out = tmp_path / "out"
    code, stdout, stderr = run(capsys, "run", case, "--out", out)
    assert code == 1, stderr
    assert stderr.startswith("substruct: error: transient: ") and stderr.count("\n") == 1
    assert "inf or NaN" in stderr and "Warning" not in stderr
    assert not out.exists() or not any(out.iterdir())
