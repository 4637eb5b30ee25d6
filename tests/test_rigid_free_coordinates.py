"""Rigid-body motions of coordinates with no stiffness at all, in the dense solver.

A node no element uses, or a free body made of rigid links and a point mass, has rows of
``K`` that are exactly zero.  The rigid motions ``null(K) & null(A)`` were found by one
decomposition of ``[D K D; A D]`` confirmed by strain energy; its round-off spread such a
motion over stiff coordinates, the energy test refused it, and the dense solver returned
zero frequencies with damping ratios of +-1 on an undamped clamped bar (an unused node), or
lost a floating body's rigid modes (an RBE2 pair with a CONM2).  Those coordinates are now
split off first (:func:`substruct.analysis.modes.roots.rigid_basis`).  Asserted:

* the basis against ``scipy.linalg.null_space`` of the stacked matrices, on small cases with
  free coordinates touched or not by the constraints;
* a clamped bar of CBARs with a floating body (two grids tied by RBE2, a CONM2 with inertia):
  six rigid modes and the bar's frequencies, by the three dense formulations and the sparse
  solver alike;
* the same bulk data with a grid that only a spring to ground holds, in x (``PARAM,AUTOSPC,NO``:
  its other five coordinates have neither mass nor stiffness), refused by the dense and
  sparse solvers, and a frame with a node no member uses, refused by the dense one.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla

from substruct.analysis.modes.roots import rigid_basis
from substruct.case.errors import CaseError
from substruct.case.loader import parse_case
from substruct.run.runner import run_case


def same_span(a: np.ndarray, b: np.ndarray) -> bool:
    if a.shape[1] != b.shape[1]:
        return False
    return bool(np.abs(np.linalg.svd(a.T @ b, compute_uv=False) - 1).max() < 1e-10)


def chain(n: int) -> np.ndarray:
    K = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    K[0, 0] = K[-1, -1] = 1.0
    return 1e6 * K


@pytest.mark.parametrize("case", ["untouched", "tied to each other", "tied to the chain"])
def test_the_basis_is_the_null_space(case):
    K = np.zeros((8, 8))
    K[:5, :5] = chain(5)                      # a free chain (one rigid motion), 3 loose
    A = {"untouched": np.zeros((0, 8)),
         "tied to each other": np.array([[0, 0, 0, 0, 0, 1.0, -1.0, 0]]),
         "tied to the chain": np.array([[0, 0, 0, 0, 1.0, -1.0, 0, 0],
                                        [0, 0, 0, 0, 0, 0, 1.0, -1.0]])}[case]
    reference = sla.null_space(np.vstack([K / 1e6, A]))
    assert same_span(rigid_basis(K, A), reference)


BAR = """SOL 103
CEND
SPC = 1
BEGIN BULK
MAT1,1,2.1+11,,.3,7850.
PBAR,1,1,1.2-3,8.-7,4.-7,9.-7
GRID,1,,0.0,0.,0.
GRID,2,,0.2,0.,0.
GRID,3,,0.4,0.,0.
GRID,4,,0.6,0.,0.
GRID,5,,0.8,0.,0.
GRID,6,,1.,0.,0.
GRID,7,,1.,.1,0.
CBAR,1,1,1,2,0.,0.,1.
CBAR,2,1,2,3,0.,0.,1.
CBAR,3,1,3,4,0.,0.,1.
CBAR,4,1,4,5,0.,0.,1.
SPC1,1,123456,1
RBE2,50,6,123456,7
CONM2,60,6,,5.
,1.,,1.,,,1.
{extra}ENDDATA
"""


def modes_of(tmp_path: Path, bulk: str, modes: str):
    (tmp_path / "part.bdf").write_text(bulk)
    text = f"""\
name: part
substructures:
  - {{name: part, type: nastran, file: part.bdf}}
analysis:
  modes: {modes}
output: {{pictures: false}}
"""
    return run_case(parse_case(text, "part.yaml", tmp_path)).modes


def test_a_floating_body_keeps_its_six_rigid_modes(tmp_path):
    bulk = BAR.format(extra="")
    sparse = modes_of(tmp_path, bulk, "{count: 8, solver: sparse}")
    assert np.all(sparse.omega[:6] == 0) and np.all(sparse.omega[6:] > 100)
    for method in ("generalized-inverse", "null-space", "kkt"):
        dense = modes_of(tmp_path, bulk, "{count: 8, solver: dense, method: %s}" % method)
        assert np.all(dense.omega[:6] == 0), method
        assert np.allclose(dense.omega[6:], sparse.omega[6:], rtol=1e-10), method
        assert np.allclose(np.asarray(dense.damping_ratio), 0.0, atol=1e-12)


@pytest.mark.parametrize("solver", ["dense", "sparse"])
def test_a_node_with_neither_mass_nor_stiffness_is_refused(tmp_path, solver):
    bulk = BAR.format(extra="PARAM,AUTOSPC,NO\nGRID,8,,1.,0.,.1\nCELAS2,70,1.,8,1\n")
    with pytest.raises(CaseError, match="singular model: a motion with no mass"):
        modes_of(tmp_path, bulk, "{count: 8, solver: %s}" % solver)


FRAME = """\
name: frame
substructures:
  - name: f
    type: frame
    nodes: {1: [0, 0, 0], 2: [1, 0, 0], 3: [2, 0, 0], 7: [5, 5, 5]}
    materials: {steel: {E: 2.1e11, G: 8.1e10, rho: 7850}}
    sections: {s: {A: 1.0e-3, Iy: 1.0e-6, Iz: 2.0e-6, J: 1.5e-6}}
    members: [{nodes: [1, 2], section: s, material: steel, orientation: [0, 0, 1]},
              {nodes: [2, 3], section: s, material: steel, orientation: [0, 0, 1]}]
    supports: {1: "123456"}
analysis:
  modes: {count: 4, solver: dense}
output: {pictures: false}
"""


def test_a_frame_node_no_member_uses_is_refused(tmp_path):
    with pytest.raises(CaseError, match="singular model"):
        run_case(parse_case(FRAME, "frame.yaml", tmp_path))


def test_a_rigid_mode_with_a_negative_omega2_of_the_inputs_rounding_is_reported_at_zero():
    """A supplier's reduced matrices hold ``K u = 0`` for their rigid-body motions only to their
    own rounding, and ``omega^2`` may come out negative, which no stiffness gives: a free-free
    chain of 12 unit masses and springs of 1e6 whose stiffness gets ``eps 1 1^T / n`` has its
    rigid-body motion at ``omega^2 = eps``, above the energy test's rounding level
    (:data:`~substruct.analysis.modes.roots.RIGID_ENERGY_TOL`: 1.4e-13 of ``|u|^T |K| |u|``)
    and, for ``|eps|`` below ``1e-12 tr K / tr M`` (1.8e-6): ``eps = -5e-7`` is reported at 0,
    one entry (a real pair of damping ratios +1 and -1 before), by the three dense
    formulations and the sparse solver alike; ``eps = +5e-7`` is a soft mode the matrices
    describe (as a unit spring in series with a 1e12 one, ``test_awkward_models``) and keeps
    its frequency, ``sqrt(eps)``.  The elastic modes are the chain's to ``eps`` over their
    size."""
    from substruct.analysis.api import modes
    from substruct.analysis.system import ConstrainedSystem, ModesOptions

    n = 12
    K = np.zeros((n, n))
    for i in range(n - 1):
        K[np.ix_([i, i + 1], [i, i + 1])] += 1e6 * np.array([[1.0, -1.0], [-1.0, 1.0]])
    M = np.eye(n)
    exact = sla.eigh(K, M, eigvals_only=True)
    for eps in (-5e-7, 5e-7):
        Kp = K + eps * np.ones((n, n)) / n
        for method in ("generalized-inverse", "null-space", "kkt"):
            res = modes(ConstrainedSystem.of(M, None, Kp, None), 4,
                        options=ModesOptions(method=method, solver="dense"))
            assert np.abs(res.damping_ratio).max() < 1e-9, method   # round-off of the pencils
            if eps < 0:
                assert res.omega[0] == 0.0 and res.damping_ratio[0] == 0.0, method
            else:
                assert abs(res.omega[0] / np.sqrt(eps) - 1) < 1e-2, (method, res.omega[0])
            u = res.shapes[:, 0]          # the chain's rigid motion, all coordinates alike
            assert abs(abs(u.sum()) / (np.linalg.norm(u) * np.sqrt(n)) - 1) < 1e-9, method
            np.testing.assert_allclose(res.omega[1:] ** 2, exact[1:4], rtol=1e-10)
        if eps < 0:
            sparse = modes(ConstrainedSystem.of(M, None, Kp, None), 4,
                           options=ModesOptions(solver="sparse"))
            assert sparse.omega[0] == 0.0
            np.testing.assert_allclose(sparse.omega[1:], res.omega[1:], rtol=1e-10)
