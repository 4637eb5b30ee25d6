"""``analysis.modes.solver: amls`` from a case file, against ``solver: sparse`` (shift-invert
Lanczos on the same null-space eliminated system).

The model: two solid boxes tied at x = 2 (an interface, so the constraint rows of A are
eliminated first), 768 free coordinates.  What is asserted:

* truncated AMLS (cut-off 5, no iteration): every eigenvalue an upper bound of the exact one,
  the largest relative error below 2e-3 (measured 1.2e-3; tests/test_amls.py measures below
  1e-3 at this cut-off on a clamped box of 16 x 4 x 4), and below the largest residual (a Ritz
  value's error is of second order in its residual);
* one subspace iteration: the lowest seven to 1e-8 (measured 1.6e-11), all twenty to 1e-5;
* a band with a max: every mode below it, as many as the exact ones;
* a residual above the case's tolerance fails the run (exit 1, one line), never a print;
* the summary names the strategy, its cut-off, the reduced coordinates and the residual.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cli_helpers import run
from substruct.analysis.errors import CheckError
from substruct.case.loader import parse_case
from substruct.run.runner import run_case

ROOT = Path(__file__).resolve().parent.parent
EPS = np.finfo(float).eps


def case(modes: str) -> str:
    return f"""\
name: two_boxes
substructures:
  - name: left
    type: solid
    box: {{lengths: [2.0, 0.5, 0.5], divisions: [8, 3, 3]}}
    E: 2.1e11
    nu: 0.3
    rho: 7850
    fixed: [xmin]
  - name: right
    type: solid
    box: {{lengths: [2.0, 0.5, 0.5], divisions: [8, 3, 3], origin: [2, 0, 0]}}
    E: 2.1e11
    nu: 0.3
    rho: 7850
interfaces:
  - {{name: a, between: [left, right], nodes: {{box: [[2, 0, 0], [2, 0.5, 0.5]]}}}}
analysis:
  modes: {modes}
output: {{pictures: false}}
"""


def solve(modes: str):
    return run_case(parse_case(case(modes), "two.yaml", ROOT)).modes


@pytest.fixture(scope="module")
def exact():
    return solve("{count: 20, solver: sparse}")


def test_truncated_amls_within_the_cutoff_error(exact):
    r = solve("{count: 20, solver: amls, tolerance: 0.5, "
              "amls: {cutoff: 5, leaf_size: 100, iterations: 0}}")
    assert len(r) == 20 and r.method == "null-space/amls"
    rel = (r.omega / exact.omega) ** 2 - 1
    assert rel.min() > -1e3 * EPS                      # Ritz values are upper bounds
    assert 1e3 * EPS < rel.max() < 2e-3                # truncated, within the cut-off's error
    assert rel.max() <= r.agreement["amls-residual"]
    assert r.residual.max() < 1e-12                    # A u = 0 by the elimination
    assert r.solver.startswith("amls (cut-off 5")


def test_one_iteration_to_1e8(exact):
    r = solve("{count: 20, solver: amls, tolerance: 0.05, check: [null-space], "
              "amls: {cutoff: 5, leaf_size: 100, iterations: 1}}")
    rel = (r.omega / exact.omega) ** 2 - 1
    assert np.max(np.abs(rel[:7])) < 1e-8
    assert np.max(np.abs(rel)) < 1e-5
    # the shift-invert check of the lowest modes, relative in omega
    assert r.agreement["null-space/sparse"] < 1e-8
    assert "1 iteration(s)" in r.solver


def test_band_max_gives_every_mode_below_it(exact):
    top = 0.5 * (exact.omega[11] + exact.omega[12])
    r = solve(f"{{count: 50, solver: amls, tolerance: 0.05, band: {{max: {top}}}, "
              f"amls: {{leaf_size: 100, iterations: 1}}}}")
    assert len(r) == 12
    # the mode at the band's top: error x (lambda_j / lambda_p+1)^2 <= 1/16 after one
    # iteration (Ritz vectors up to twice the top), from about 1e-3: below 1e-4 in omega
    assert np.all(r.omega >= exact.omega[:12] * (1 - 1e-12))
    assert np.allclose(r.omega, exact.omega[:12], rtol=1e-4)
    assert np.allclose(r.omega[:5], exact.omega[:5], rtol=1e-8)


def test_residual_beyond_tolerance_is_a_check_error():
    with pytest.raises(CheckError, match="amls-residual"):
        solve("{count: 10, solver: amls, amls: {leaf_size: 100}}")


def test_summary_and_exit_codes(tmp_path, capsys):
    path = tmp_path / "two.yaml"
    path.write_text(case("{count: 8, solver: amls, tolerance: 0.05, amls: {leaf_size: 100, iterations: 1}}"))
    code, out, err = run(capsys, "run", path, "--out", tmp_path / "ok")
    assert code == 0, err
    assert "8 physical mode(s), null-space/amls" in out
    assert "solver: amls (cut-off 5" in out and "reduced coordinates of 768" in out
    assert "amls-residual" in out
    path.write_text(case("{count: 8, solver: amls, amls: {leaf_size: 100}}"))
    code, out, err = run(capsys, "run", path, "--out", tmp_path / "bad")
    assert code == 1 and "amls-residual" in err and "tolerance" in err
    assert len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "bad").exists() or not any((tmp_path / "bad").iterdir())


def test_ritz_ratio_is_used_and_checked(exact, tmp_path, capsys):
    """``amls.ritz_ratio``: fewer Ritz vectors iterated (1.2 x the wanted frequency against the
    default 2 x) give larger errors after the same two steps, still upper bounds; given
    without iterations, or above the cut-off, it is refused (exit 2, one line)."""
    rel = {}
    for ratio in (1.2, None):
        extra = "" if ratio is None else f", ritz_ratio: {ratio}"
        r = solve("{count: 20, solver: amls, tolerance: 0.05, "
                  f"amls: {{cutoff: 3, leaf_size: 100, iterations: 2{extra}}}}}")
        rel[ratio] = (r.omega / exact.omega) ** 2 - 1
        # upper bounds, to the round-off of the two solves (2e-12 measured on the lowest)
        assert rel[ratio].min() > -1e-10
    assert rel[1.2].max() > 10 * rel[None].max()       # measured 9.3e-7 against 1.4e-8
    for bad, says in (("{iterations: 0, ritz_ratio: 1.5}", "iterations is 0"),
                      ("{cutoff: 3, iterations: 1, ritz_ratio: 4}", "at most the cut-off 3")):
        path = tmp_path / "bad.yaml"
        path.write_text(case(f"{{count: 8, solver: amls, amls: {bad}}}"))
        code, out, err = run(capsys, "run", path, "--out", tmp_path / "out")
        assert code == 2 and "analysis.modes.amls.ritz_ratio" in err and says in err, err
        assert len(err.strip().splitlines()) == 1
        assert not (tmp_path / "out").exists()


def test_a_model_with_fewer_finite_modes_than_asked_gives_them_all():
    """The tapered rod of ``cases/tapered_rod.yaml`` (10 coordinates, 5 constraint rows) has
    5 finite modes (6 without eq 52): with ``count: 6`` AMLS grows the wanted frequency until
    every block keeps every mode and every reduced pair lies below it, and reports them all,
    as the sparse solver does (it failed with 'AMLS found fewer than 6 modes')."""
    text = (ROOT / "cases" / "tapered_rod.yaml").read_text()
    got = {}
    for solver in ("sparse", "amls"):
        edited = text.replace("  modes:\n", f"  modes:\n    solver: {solver}\n", 1)
        res = run_case(parse_case(edited, "tapered_rod.yaml", ROOT / "cases"))
        got[solver] = [res.modes, *res.variants.values()]
    for sparse, amls in zip(got["sparse"], got["amls"]):
        assert len(amls) == len(sparse) in (5, 6)
        np.testing.assert_allclose(amls.omega, sparse.omega, rtol=1e-10)


def test_a_mass_singular_in_a_combination_gives_every_finite_mode():
    """A mass singular in a combination of coordinates (``q1 - q2`` carries none, no zero
    row): 2 finite modes of 3 coordinates.  With ``count: 3`` AMLS grew the wanted frequency
    for 40 passes and failed ('AMLS found fewer than 3 modes below 1.93e+11 rad/s'); beyond
    1/eps of the stiffness's scale an eigenvalue is an infinite one, and it reports the two,
    the finite eigenvalues of the pencil (``M x = mu K x``, ``lambda = 1 / mu``, ``mu > 0``)."""
    text = """\
name: singular_combination
substructures:
  - name: P
    type: matrices
    M: [[1, 1, 0], [1, 1, 0], [0, 0, 1]]
    K: [[20, -10, 0], [-10, 30, -20], [0, -20, 40]]
analysis:
  modes: {count: 3, solver: amls}
output: {pictures: false}
"""
    r = run_case(parse_case(text, "singular.yaml", ROOT)).modes
    M = np.array([[1.0, 1, 0], [1, 1, 0], [0, 0, 1]])
    K = np.array([[20.0, -10, 0], [-10, 30, -20], [0, -20, 40]])
    mu = np.linalg.eigvalsh(np.linalg.solve(np.linalg.cholesky(K), np.linalg.solve(
        np.linalg.cholesky(K), M).T))
    finite = np.sort(1.0 / mu[mu > 1e-12 * mu.max()])
    assert len(r) == 2
    np.testing.assert_allclose(r.omega ** 2, finite, rtol=1e-12)
