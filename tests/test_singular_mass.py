"""A mass matrix singular in a combination of coordinates that all have mass.

The generalized-inverse formulation (eqs 7-10) splits off the massless coordinates (zero rows
of ``M``) and needs the rest positive definite.  A pinned CBAR end in skew axes with coupled
mass leaves a rotation about the pin's axis without mass, a combination of ``rx, ry, rz`` at
the grid, singular only to round-off (``2e-17`` of the mean mass): the factorization went
through and the pencil gave wrong roots with exit code 0 (here 7 of the 8 modes asked, the
elastic one lost; on a larger deck 10 of 14, residuals up to 7.2e-4 and the first elastic
frequency at 43,473 rad/s instead of 135.6).  Such a mass is now refused as an exactly
singular one was, and null-space and KKT, which need no inverse of ``M``, agree on its modes.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

import substruct
from substruct import cli
from substruct.analysis.formulations.projection import nearly_singular, split_mass
from substruct.linalg.factorize import factorizer

# Two CBARs along a skew line, the second pinned at its end B (PB = 5: the rotation about
# its element y axis), that end joined by an RBE2 to a third CBAR.  Free: six rigid-body
# modes and the hinge's.
PIN_BDF = """\
SOL 103
CEND
METHOD = 1
BEGIN BULK
EIGRL,1,,,8
PARAM,COUPMASS,1
MAT1,1,2.1+11,8.1+10,,7850.
PBAR,1,1,3.-3,2.-6,5.-6,1.-6
GRID,1,,0.,0.,0.
GRID,2,,.6,.5,.3
GRID,3,,1.2,1.,.6
GRID,4,,1.2,1.,.6
GRID,5,,2.,1.,.6
CBAR,1,1,1,2,0.,0.,1.
CBAR,2,1,2,3,0.,0.,1.,,+
+,,5
CBAR,3,1,4,5,0.,1.,0.
RBE2,10,4,123456,3
ENDDATA
"""


def test_generalized_inverse_refuses_a_pinned_end_in_skew_axes(tmp_path, capsys):
    (tmp_path / "pin.bdf").write_text(PIN_BDF)
    code = cli.main(["run", str(tmp_path / "pin.bdf"), "--out", str(tmp_path / "out"),
                     "--quiet"])
    err = capsys.readouterr().err
    assert code == 2
    assert "mass matrix is singular on coordinates that have mass" in err
    assert "method null-space or kkt" in err and err.count("\n") == 1
    assert not (tmp_path / "out" / "pin.h5").exists()


def test_null_space_and_kkt_agree_on_the_pinned_deck(tmp_path):
    (tmp_path / "pin.bdf").write_text(PIN_BDF)
    (tmp_path / "pin.yaml").write_text(
        "name: pin\nsubstructures:\n  - {name: p, type: nastran, file: pin.bdf}\n"
        "analysis: {modes: {count: 8, method: null-space, check: [kkt]}}\n")
    modes = substruct.run_case(substruct.load_case(tmp_path / "pin.yaml")).modes
    omega = np.asarray(modes.omega).real
    # six rigid-body modes and the hinge at zero, then the first elastic mode
    assert np.all(omega[:7] < 1e-6 * omega[7]) and omega[7] > 100.0
    assert modes.agreement["kkt"] < 1e-9


def skew_mass(scale: float, singular: bool) -> sp.csc_array:
    """A 6 x 6 mass, ``scale`` times a fixed one: the rigid-body mass of a point mass at an
    offset (rank 3, no row zero) plus, when not ``singular``, an inertia of 1e-3 of ``m |x|^2``
    (a small one that is still mass)."""
    x = np.array([0.3, -1.2, 0.7])
    S = np.array([[0, -x[2], x[1]], [x[2], 0, -x[0]], [-x[1], x[0], 0]])
    M = np.block([[np.eye(3), -S], [S, -S @ S]])
    if not singular:
        M[3:, 3:] += 1e-3 * (x @ x) * np.eye(3)
    return sp.csc_array(scale * M)


@pytest.mark.parametrize("scale", [1e-12, 1.0, 1e12])
def test_the_decision_does_not_depend_on_the_units(scale):
    for singular in (True, False):
        M = skew_mass(scale, singular)
        # eigenvalues of the scaled matrix: 0 (to round-off) and 1e-3 relative
        ev = np.linalg.eigvalsh(M.toarray() / scale)
        assert (abs(ev[0]) < 1e-14) if singular else (ev[0] > 1e-4)
        try:
            factor = factorizer("superlu", spd=False)(M)
        except RuntimeError:  # exactly singular: split_mass refuses it before
            assert singular
            continue
        assert nearly_singular(M, factor) is singular


def test_a_regular_mass_with_massless_rows_is_split_as_before():
    M = sp.csc_array(np.diag([2.0, 0.0, 1e-6, 3.0]))
    ms = split_mass(M)
    assert list(ms.massless) == [False, True, False, False]
    assert np.allclose(ms.solve(np.ones(4)) * ms.Md.diagonal(), 1.0, rtol=1e-14)
