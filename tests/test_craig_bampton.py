"""Craig-Bampton reduction: exact statics on the boundary, convergence to the full model."""

from __future__ import annotations

import numpy as np
import pytest

from substruct.assembly.stack import Connection, PointRef, assemble
from substruct.models.craig_bampton import craig_bampton
from substruct.assembly.interfaces import node_dofs, tie_nodes
from substruct.models.discrete import free_free
from substruct.models.rod import rod_fe
from substruct.models.solid import BoxGrid, solid_box
from substruct.analysis.modes.dense import coupled_modes
from substruct.analysis.modes.sparse import null_space_modes

E, NU, RHO = 2.1e11, 0.3, 7850.0
L, B, H = 1.0, 0.1, 0.1
FACE = {"box": [[L / 2, 0, 0], [L / 2, B, H]]}


@pytest.fixture(scope="module")
def halves():
    a = solid_box("a", BoxGrid((L / 2, B, H), (10, 2, 2)), E, NU, RHO,
                  fixed=[{"box": [[0, 0, 0], [0, B, H]]}])
    b = solid_box("b", BoxGrid((L / 2, B, H), (10, 2, 2), origin=(L / 2, 0, 0)), E, NU, RHO)
    return a, b


def test_boundary_statics_are_exact(halves):
    """The reduced boundary stiffness is the Schur complement ``K_bb - K_bi K_ii^-1 K_ib``;
    the fixed-interface block is ``diag(omega^2)``; the boundary keeps its labels."""
    a, _ = halves
    bnd = node_dofs(a, FACE)
    red = craig_bampton(a, bnd, 6)
    K = a.K.toarray()
    inner = np.setdiff1d(np.arange(a.n_dof), bnd)
    schur = K[np.ix_(bnd, bnd)] - K[np.ix_(bnd, inner)] @ np.linalg.solve(
        K[np.ix_(inner, inner)], K[np.ix_(inner, bnd)])
    Kr = red.K.toarray()
    np.testing.assert_allclose(Kr[6:, 6:], schur, rtol=1e-9, atol=1e-9 * abs(schur).max())
    w2 = red.meta["omega_fixed_interface"] ** 2
    np.testing.assert_allclose(np.diag(Kr[:6, :6]), w2, rtol=1e-9)
    assert abs(Kr[:6, 6:]).max() < 1e-8 * abs(Kr).max()
    np.testing.assert_allclose(red.M.toarray()[:6, :6], np.eye(6), atol=1e-10)
    assert red.dof_labels[:6] == tuple(f"eta{j}" for j in range(1, 7))
    assert red.dof_labels[6:] == tuple(a.dof_labels[i] for i in bnd)
    assert red.kind == "craig-bampton" and red.meta["reduced_from"] == a.n_dof
    # a point on the boundary keeps its unit row
    row = red.row({"at": [L / 2, B, H], "component": "z"})
    assert row.nnz == 1 and row.data[0] == pytest.approx(1.0)


def test_sparse_and_dense_interior_solves_agree(halves):
    a, _ = halves
    bnd = node_dofs(a, FACE)
    dense = craig_bampton(a, bnd, 8)
    sparse = craig_bampton(a, bnd, 8, dense_limit=0)
    np.testing.assert_allclose(sparse.meta["omega_fixed_interface"],
                               dense.meta["omega_fixed_interface"], rtol=1e-9)
    np.testing.assert_allclose(sparse.K.toarray()[8:, 8:], dense.K.toarray()[8:, 8:],
                               rtol=1e-8, atol=1e-8 * abs(dense.K).max())


def test_coupled_craig_bampton_converges_to_full_model(halves):
    """Two CB-reduced halves tied at the interface (plus an absorber at the tip, attached
    to a boundary DOF) converge to the full coupled model as fixed-interface modes are added.

    Measured relative errors of the lowest 8 frequencies: 0.12 (2 modes), 0.10 (5),
    3.5e-4 (10), 5.3e-5 (20), 1.5e-5 (40) without the absorber.
    """
    a, b = halves
    tip = {"box": [[L, 0, 0], [L, B, H]]}
    absorber = free_free("t", 0.5, 0.5 * (2 * np.pi * 90.0) ** 2)

    def connections(sa, sb):
        return tie_nodes(sa, sb, FACE) + [Connection(
            PointRef("b", {"at": [L, B, H], "component": "y"}), PointRef("t", "boundary"))]

    full = assemble([a, b, absorber], connections(a, b))
    ref = null_space_modes(full.M, full.K, full.A, 8).omega
    errors = []
    for g in (2, 5, 10, 20, 40):
        ra = craig_bampton(a, node_dofs(a, FACE), g)
        rb = craig_bampton(b, np.union1d(node_dofs(b, FACE), node_dofs(b, tip)), g)
        asm = assemble([ra, rb, absorber], connections(ra, rb))
        omega = coupled_modes(asm.M, None, asm.K, asm.A, method="null-space",
                              n_modes=8).omega
        assert np.all(omega >= ref * (1 - 1e-10))  # a Ritz reduction: from above
        errors.append(float(np.max(omega / ref - 1)))
    assert all(e2 <= e1 for e1, e2 in zip(errors, errors[1:]))
    assert errors[-1] < 1e-4 and errors[0] > 10 * errors[-1]


def test_fe_rods_tied_and_reduced():
    """Two FE rod segments (P2, 20 elements each) tied at the joint, each reduced with the
    joint as its only boundary DOF: the lowest 4 frequencies converge to the unreduced
    coupled model, which matches the uniform rod's closed form."""
    left = rod_fe("left", 1.0, 200.0, 1.0, 20, support="fixed-free", order=2)
    right = rod_fe("right", 1.0, 200.0, 1.0, 20, support="free-free", order=2)
    ties = [Connection(PointRef("left", 1.0), PointRef("right", 0.0))]
    ref = null_space_modes(*_mka(assemble([left, right], ties)), 4).omega
    errors = []
    for g in (2, 4, 10):
        rl = craig_bampton(left, [left.row(1.0).indices[0]], g)
        rr = craig_bampton(right, [right.row(0.0).indices[0]], g)
        asm = assemble([rl, rr], ties)
        omega = coupled_modes(asm.M, None, asm.K, asm.A, method="null-space").omega[:4]
        errors.append(float(np.max(omega / ref - 1)))
    # measured: 1.5e-2, 1.5e-3, 9.5e-5
    assert errors[0] > 5 * errors[1] > 25 * errors[2] and errors[2] < 2e-4
    exact = (2 * np.arange(1, 5) - 1) * np.pi * np.sqrt(200.0) / (2 * 2.0)
    np.testing.assert_allclose(ref, exact, rtol=1e-5)


def test_every_fixed_interface_mode_kept_is_the_full_model():
    """With every fixed-interface mode kept (``n_modes`` = the interior's size) the basis
    spans the whole space: the coupled frequencies are the unreduced model's to 1e-10 (a
    few ulps of the eigenvalue solve), the ones above the lowest included."""
    left = rod_fe("left", 1.0, 200.0, 1.0, 8, support="fixed-free", order=2)
    right = rod_fe("right", 1.0, 200.0, 1.0, 8, support="free-free", order=2)
    ties = [Connection(PointRef("left", 1.0), PointRef("right", 0.0))]
    ref = null_space_modes(*_mka(assemble([left, right], ties)), 12).omega
    bl, br = [left.row(1.0).indices[0]], [right.row(0.0).indices[0]]
    rl = craig_bampton(left, bl, left.n_dof - 1)
    rr = craig_bampton(right, br, right.n_dof - 1)
    assert rl.n_dof == left.n_dof and rr.n_dof == right.n_dof
    omega = null_space_modes(*_mka(assemble([rl, rr], ties)), 12).omega
    np.testing.assert_allclose(omega, ref, rtol=1e-10)
    with pytest.raises(ValueError, match="n_modes"):
        craig_bampton(left, bl, left.n_dof)


def _mka(asm):
    return asm.M, asm.K, asm.A


def test_errors(halves):
    a, _ = halves
    bnd = node_dofs(a, FACE)
    with pytest.raises(ValueError, match="at least one boundary"):
        craig_bampton(a, [], 3)
    with pytest.raises(ValueError, match="n_modes"):
        craig_bampton(a, bnd, a.n_dof)
    free = solid_box("f", BoxGrid((1, 1, 1), (2, 2, 2)), E, NU, RHO)
    one_node = node_dofs(free, {"box": [[0, 0, 0], [0, 0, 0]]})
    with pytest.raises(ValueError, match="do not hold the interior"):
        craig_bampton(free, one_node, 3)
    with pytest.raises(ValueError, match="do not hold the interior"):
        craig_bampton(free, one_node, 3, dense_limit=0)
