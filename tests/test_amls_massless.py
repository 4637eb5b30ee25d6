"""AMLS with a singular mass and with free bodies: lumped-mass beams and bars (massless
rotations, Nastran's default mass of CBAR, CBEAM and shells), masses on offsets (singular
2 x 2 blocks without a zero row), and free-free models.

Every block's eigenproblem is solved in the inverse form :math:`M \\phi = \\mu K \\phi`
(substruct.linalg.amls_block.block_modes), definite on the right whatever the mass; a block
with no boundary (the root separator) shifted below zero so that a free body's pencil is
definite too.  What is asserted:

* every mode kept: the exact finite eigenvalues of the dense pencil, to the round-off of a
  beam's stiffness (``eps (L/h)^4``), the massless rows of ``K u`` at round-off;
* truncated: upper bounds of the exact ones (Rayleigh-Ritz), decreasing as the cut-off grows;
* a free-free lumped beam: its two rigid modes at 0 with their residual measured against
  ``|K| |u|``, the elastic ones exact;
* from case files: a clamped bar of CBARs with CONM2 point masses only, and the free-free
  shell cylinder of Nastran's test set (six rigid modes), against ``solver: sparse``; a
  massless coordinate held by a stiffness in the modal transient on the AMLS basis against
  the direct integration; a massless coordinate held by nothing refused (exit 2, one line).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp

from cli_helpers import assert_one_line_error, run
from substruct.case.loader import parse_case
from substruct.linalg.amls import amls_modes
from substruct.models.craig_bampton import craig_bampton
from substruct.run.runner import run_case
from substruct.substructure import Substructure

ROOT = Path(__file__).resolve().parent.parent
EPS = np.finfo(float).eps
CYLINDER = ROOT / "tests" / "data" / "nastran" / "cylinder" / "modal.bdf"
#: The round-off of the 40-element beams' eigenvalues, in either the reference or AMLS: ten
#: times ``eps (L / h)^4``, the relative size of a smooth mode's rounding in a beam's stiffness
ROUNDOFF = 10 * 40**4 * EPS


def beam(elements: int, clamped: bool = True, offset: float = 0.0
         ) -> tuple[sp.csr_array, sp.csr_array]:
    """A plane Euler-Bernoulli beam (deflection and rotation at each node), length 2, EI 1e4,
    its mass lumped on the deflections (rotations massless); with ``offset`` each node's mass
    sits that far along the beam from the node instead (a rank-one 2 x 2 block per node)."""
    h = 2.0 / elements
    n = 2 * (elements + 1)
    k = 1e4 / h**3 * np.array([[12, 6 * h, -12, 6 * h], [6 * h, 4 * h * h, -6 * h, 2 * h * h],
                               [-12, -6 * h, 12, -6 * h], [6 * h, 2 * h * h, -6 * h, 4 * h * h]])
    K = np.zeros((n, n))
    M = np.zeros((n, n))
    for e in range(elements):
        d = np.arange(2 * e, 2 * e + 4)
        K[np.ix_(d, d)] += k
    for i in range(elements + 1):
        a = np.array([1.0, offset])      # the mass's deflection: w + offset * theta
        M[2 * i:2 * i + 2, 2 * i:2 * i + 2] += h * np.outer(a, a)
    keep = np.arange(2 if clamped else 0, n)
    return (sp.csr_array(K[np.ix_(keep, keep)]), sp.csr_array(M[np.ix_(keep, keep)]))


def finite_eigenvalues(K: sp.csr_array, M: sp.csr_array) -> np.ndarray:
    """The finite eigenvalues, ascending, from the dense inverse pencil (shifted below zero
    so that it is definite for a free beam)."""
    sigma = -1.0
    mu = sla.eigh(M.toarray(), (K - sigma * M).toarray(), eigvals_only=True)
    mu = mu[mu > 1e-12 * mu.max()]
    return np.sort(sigma + 1.0 / mu)


@pytest.mark.parametrize("offset", [0.0, 0.004])
def test_every_mode_kept_is_exact(offset):
    K, M = beam(40, offset=offset)
    lam = finite_eigenvalues(K, M)
    assert lam.size == 40                           # one finite mode per mass
    w = float(np.sqrt(0.5 * (lam[14] + lam[15])))
    r = amls_modes(K, M, w, cutoff=1e6, leaf_size=12)
    assert r.lam.size == 15
    # round-off of a beam's stiffness, eps (L / h)^4 (5.7e-10; measured 9.7e-11 and 1.5e-10)
    assert np.max(np.abs(r.lam / lam[:15] - 1)) < ROUNDOFF
    assert np.allclose(r.U.T @ (M @ r.U), np.eye(15), atol=1e-10)
    if offset == 0.0:
        # the moment rows (massless rotations) are in equilibrium: K u there is round-off
        KU = K @ r.U
        assert np.max(np.abs(KU[1::2])) < 1e-8 * np.max(np.abs(KU))


def test_truncated_upper_bounds_decreasing_with_the_cutoff():
    K, M = beam(60)
    lam = finite_eigenvalues(K, M)
    w = float(np.sqrt(0.5 * (lam[9] + lam[10])))
    errors = []
    for cutoff in (2.0, 4.0, 8.0):
        r = amls_modes(K, M, w, cutoff=cutoff, leaf_size=12)
        k = r.lam.size
        rel = r.lam / lam[:k] - 1
        assert rel.min() > -1e-9                    # Rayleigh-Ritz: upper bounds
        errors.append(rel.max())
    # measured 3.5e-2, 1.9e-2, 8.3e-4
    assert errors[0] > errors[1] > errors[2] and errors[2] < 2e-3


def test_free_free_lumped_beam():
    K, M = beam(40, clamped=False)
    lam = finite_eigenvalues(K, M)
    assert np.all(np.abs(lam[:2]) < 1e-6 * lam[2])  # translation and rotation
    w = float(np.sqrt(0.5 * (lam[11] + lam[12])))
    r = amls_modes(K, M, w, cutoff=1e6, leaf_size=12)
    assert r.lam.size == 12
    assert np.all(r.lam[:2] == 0.0)
    assert np.allclose(r.lam[2:], lam[2:12], rtol=ROUNDOFF)     # measured 7.8e-10
    # the rigid modes' residual against |K| |u| (their K u is round-off): not 0/0
    assert r.residual.max() < 1e-8


def lumped_bar(clamped: bool) -> str:
    """Bulk data of a 2 m bar of 40 CBARs without density (MAT1 RHO blank), a 2 kg CONM2 at
    each grid but the root: the rotations have no mass."""
    lines = ["SOL 103", "CEND"] + (["SPC = 1"] if clamped else []) + [
        "BEGIN BULK", "MAT1,1,2.1+11,,.3", "PBAR,1,1,1.2-3,8.-7,4.-7,9.-7"]
    lines += [f"GRID,{100 + i},,{0.05 * i:.4f},0.,1." for i in range(41)]
    lines += [f"CBAR,{i + 1},1,{100 + i},{101 + i},0.,0.,1." for i in range(40)]
    lines += [f"CONM2,{1000 + i},{100 + i},,2." for i in range(1, 41)]
    if clamped:
        lines.append("SPC1,1,123456,100")
    return "\n".join(lines + ["ENDDATA", ""])


def modes_of(tmp_path: Path, bulk: Path, modes: str):
    text = f"""\
name: lumped
units: "N, m, kg, s"
substructures:
  - {{name: bar, type: nastran, file: {bulk}}}
analysis:
  modes: {modes}
output: {{pictures: false}}
"""
    return run_case(parse_case(text, "lumped.yaml", tmp_path)).modes


def test_clamped_bar_with_point_masses_from_bulk_data(tmp_path):
    bulk = tmp_path / "bar.bdf"
    bulk.write_text(lumped_bar(clamped=True))
    exact = modes_of(tmp_path, bulk, "{count: 12, solver: sparse}")
    r = modes_of(tmp_path, bulk, "{count: 12, solver: amls, tolerance: 1e-2, "
                                 "amls: {leaf_size: 40, iterations: 2}}")
    assert r.method == "null-space/amls" and len(r) == 12
    rel = (r.omega / exact.omega) ** 2 - 1
    assert rel.min() > -1e-10                       # upper bounds, to round-off
    # a Ritz value's error is of second order in its residual (largest 3.4e-4 measured)
    assert rel.max() < r.agreement["amls-residual"] ** 2 * 10


def test_free_free_shell_cylinder(tmp_path):
    """Nastran's free-free CQUAD4 cylinder (coupled mass, 1,836 coordinates): the six rigid
    modes at zero and the elastic ones as Lanczos gives them (the pairs of a circular shell's
    repeated modes included)."""
    exact = modes_of(tmp_path, CYLINDER, "{count: 20, solver: sparse}")
    r = modes_of(tmp_path, CYLINDER, "{count: 20, solver: amls, tolerance: 1e-2, "
                                     "amls: {leaf_size: 200, iterations: 2}}")
    assert len(r) == 20
    assert np.all(r.omega[:6] == 0.0) and np.all(exact.omega[:6] == 0.0)
    rel = (r.omega[6:] / exact.omega[6:]) ** 2 - 1
    assert rel.min() > -1e-10
    assert rel.max() < r.agreement["amls-residual"] ** 2 * 10   # measured 2.2e-4 residual


MASSLESS_TRANSIENT = """\
name: massless
substructures:
  - name: P
    type: matrices
    M: [[1, 0, 0], [0, 0, 0], [0, 0, 4]]
    K: [[20, -10, 0], [-10, 30, -20], [0, -20, 20]]
analysis:
  transient:
    t_end: 0.5
    dt: 0.01
    outputs: [P@q1, P@q2]
    loads: [{point: P@q1, shape: step, amplitude: 1.0}]
    check: [modal]
    modal: {solver: amls}
output: {pictures: false}
"""


def test_modal_transient_with_a_massless_coordinate():
    """The middle coordinate has no mass, only stiffness: two finite modes; the modal
    transient on their AMLS basis (with the static correction of the infinite one) is the
    direct integration's to round-off."""
    r = run_case(parse_case(MASSLESS_TRANSIENT, "m.yaml", ROOT)).transient
    assert r is not None
    (name, value), = r.agreement.items()
    assert name == "modal" and value < 1e-10       # measured 1.9e-14


def test_a_massless_coordinate_held_by_nothing_is_refused(tmp_path, capsys):
    path = tmp_path / "m.yaml"
    path.write_text("name: m\nsubstructures:\n  - {name: P, type: matrices, "
                    "M: [[1, 0], [0, 0]], K: [[20, 0], [0, 0]]}\n"
                    "analysis:\n  modes: {count: 1, solver: amls}\n")
    code, out, err = run(capsys, "run", path, "--out", tmp_path / "out")
    assert_one_line_error(code, out, err, "singular model", "no mass, no stiffness")


def test_craig_bampton_of_a_lumped_beam():
    """The fixed-interface modes of an interior with massless rotations (the same inverse
    pencil densely, shift-invert Lanczos on a singular mass): with every finite one kept the
    reduced model has the full model's finite eigenvalues, with 20 the two solves agree;
    asking for more than the interior has masses is refused."""
    K, M = beam(40)
    n = K.shape[0]
    sub = Substructure("beam", M, K, sp.csr_array((n, n)), tuple(f"q{i}" for i in range(n)),
                       lambda point: sp.csr_array((1, n)))
    tip = [n - 2, n - 1]
    lam = finite_eigenvalues(K, M)
    red = craig_bampton(sub, tip, 39)
    assert red.n_dof == 41
    assert np.allclose(finite_eigenvalues(red.K, red.M), lam, rtol=ROUNDOFF)
    # 20 modes: the dense and the Lanczos interior solves span the same space
    dense, lanczos = (finite_eigenvalues(r.K, r.M) for r in
                      (craig_bampton(sub, tip, 20, dense_limit=d) for d in (1500, 0)))
    assert np.allclose(dense, lanczos, rtol=ROUNDOFF)
    assert np.all(dense[:15] >= lam[:15] * (1 - ROUNDOFF))     # upper bounds
    with pytest.raises(ValueError, match="40 fixed-interface modes asked of an interior with "
                                         "39 of them"):
        craig_bampton(sub, tip, 40)
