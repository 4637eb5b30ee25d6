"""Sparse coupled modes (null space, generalized inverse) and interfaces between FE solids.

Rung 3 of the verification ladder: the two sparse paths agree with each other and with the
dense ``coupled_modes`` to 1e-8; two halves tied node to node have the frequencies of the
monolithic mesh to 1e-8.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

import substruct.linalg.lanczos as lanczos
from substruct.assembly.stack import Connection, LinearConstraint, PointRef, assemble
from substruct.assembly.interfaces import InterfaceError, node_dofs, tie_nodes, tie_nonmatching
from substruct.models.discrete import free_free
from substruct.models.solid import (BoxGrid, RectangleGrid, solid_box, solid_from_mesh,
                                    solid_rectangle)
from substruct.analysis.checks import modes_agreement
from substruct.analysis.modes.dense import coupled_modes
from substruct.analysis.modes.sparse import (generalized_inverse_modes, null_space_modes,
                                             sparse_coupled_modes)
import substruct.linalg.factorize as fz
from substruct.linalg.nullspace import master_slave

E, NU, RHO = 2.1e11, 0.3, 7850.0
L, B, H = 1.0, 0.2, 0.2
FACE = {"box": [[L / 2, 0, 0], [L / 2, B, H]]}
CLAMP = [{"box": [[0, 0, 0], [0, B, H]]}]


def halves(div=(4, 2, 2), order=1, clamp=True):
    a = solid_box("a", BoxGrid((L / 2, B, H), div), E, NU, RHO, order=order,
                  fixed=CLAMP if clamp else ())
    b = solid_box("b", BoxGrid((L / 2, B, H), div, origin=(L / 2, 0, 0)), E, NU, RHO, order=order)
    return a, b


@pytest.fixture(scope="module")
def coupled():
    """Two tied halves, two absorbers (massless boundary DOFs), one multi-point constraint."""
    a, b = halves()
    t1 = free_free("t1", 5.0, 5.0 * (2 * np.pi * 150) ** 2)
    t2 = free_free("t2", 3.0, 3.0 * (2 * np.pi * 400) ** 2)
    cons = tie_nodes(a, b, FACE) + [
        Connection(PointRef("b", {"at": [L, B, H], "component": "y"}), PointRef("t1", "boundary")),
        Connection(PointRef("b", {"at": [L, 0, H], "component": "z"}), PointRef("t2", "boundary"))]
    mpc = LinearConstraint((
        (PointRef("b", {"at": [0.8, 0.1, 0.2], "component": "z"}), 1.0),
        (PointRef("b", {"at": [0.75, 0.05, 0.0], "component": "z"}), -2.0),   # interpolated
        (PointRef("a", {"at": [0.3, 0.13, 0.2], "component": "x"}), 0.5)), name="mpc")
    return assemble([a, b, t1, t2], cons, [mpc])


# ----------------------------------------------------------------------- master-slave basis


def test_master_slave_basis_redundant_rows_and_preference():
    rng = np.random.default_rng(1)
    n = 40
    A = sp.random_array((6, n), density=0.2, random_state=rng, format="csr")
    A = sp.csr_array(sp.vstack([A, A[[0]] * 2 - A[[3]], A[[2]]]))  # two redundant rows
    el = master_slave(A)
    assert el.rank == np.linalg.matrix_rank(A.toarray()) == 6
    assert sorted(el.dropped_rows.tolist()) == [6, 7]
    assert abs(A @ el.T).max() < 1e-12
    np.testing.assert_array_equal(el.T[el.masters].toarray(), np.eye(n - 6))
    # a tie u_3 - u_7: the preferred (e.g. massless) coordinate becomes the slave
    tie = sp.csr_array(([1.0, -1.0], ([0, 0], [3, 7])), shape=(1, n))
    prefer = np.zeros(n, bool)
    prefer[3] = True
    assert master_slave(tie, prefer=prefer).slaves.tolist() == [3]
    assert master_slave(tie).slaves.tolist() == [3] or master_slave(tie).slaves.tolist() == [7]


def test_master_slave_chain_of_ties():
    """u0 = u1 = u2 = u3 as a chain: one master left, every slave written in it."""
    rows = [[0, 1], [1, 2], [2, 3], [3, 0]]  # the last closes a loop: redundant
    A = sp.csr_array(([1.0, -1.0] * 4, (np.repeat(np.arange(4), 2), np.ravel(rows))),
                     shape=(4, 5))
    el = master_slave(A)
    assert el.rank == 3 and el.dropped_rows.tolist() == [3]
    assert abs(A @ el.T).max() < 1e-14
    assert el.T.shape == (5, 2)


# ---------------------------------------------------------------------- sparse vs dense


def test_sparse_paths_agree_with_dense_coupled_modes(coupled):
    asm = coupled
    k = 12
    dense = coupled_modes(asm.M, None, asm.K, asm.A, method="generalized-inverse", n_modes=k)
    ns = null_space_modes(asm.M, asm.K, asm.A, k)
    gi = generalized_inverse_modes(asm.M, asm.K, asm.A, k)
    gi_bare = generalized_inverse_modes(asm.M, asm.K, asm.A, k, project=False)
    for modes in (ns, gi, gi_bare):
        assert modes_agreement(modes, dense) < 1e-8
        assert modes.residual.max() < 1e-12
        # mass-normalized, M-orthogonal
        U = modes.shapes
        np.testing.assert_allclose(U.T @ (asm.M @ U), np.eye(k), atol=1e-9)
    assert modes_agreement(ns, gi) < 1e-8
    # the same shapes up to sign
    overlap = np.abs(ns.shapes.T @ (asm.M @ gi.shapes))
    np.testing.assert_allclose(np.diag(overlap), 1.0, atol=1e-6)


def test_redundant_rows_and_rigid_body_modes():
    """A free-free pair of halves: 6 rigid-body modes; duplicated ties change nothing."""
    a, b = halves(div=(2, 1, 1), clamp=False)
    ties = tie_nodes(a, b, FACE)
    once = assemble([a, b], ties)
    twice = assemble([a, b], ties + ties[:5])
    mono = solid_box("m", BoxGrid((L, B, H), (4, 1, 1)), E, NU, RHO)
    ref = null_space_modes(mono.M, mono.K, None, 10)
    for asm in (once, twice):
        for method in ("null-space", "generalized-inverse"):
            m = sparse_coupled_modes(asm.M, asm.K, asm.A, 10, method=method)
            assert np.all(m.omega[:6] < 1e-4 * m.omega[6])
            np.testing.assert_allclose(m.omega[6:], ref.omega[6:], rtol=1e-8)


def test_factorizations_and_eigsh_never_factorizes(coupled, monkeypatch):
    asm = coupled
    calls = []
    real = lanczos.spla.eigsh

    def spy(*args, **kwargs):
        assert kwargs.get("OPinv") is not None, "eigsh must not factorize by itself"
        calls.append(kwargs["sigma"])
        return real(*args, **kwargs)

    monkeypatch.setattr(lanczos.spla, "eigsh", spy)
    ref = null_space_modes(asm.M, asm.K, asm.A, 6)
    gi = generalized_inverse_modes(asm.M, asm.K, asm.A, 6)
    assert len(calls) == 2 and all(s < 0 for s in calls)
    seen = []

    def mine(A):
        seen.append(A.shape)
        return fz.factorizer("superlu")(A)

    custom = null_space_modes(asm.M, asm.K, asm.A, 6, factorization=mine)
    assert seen and modes_agreement(custom, ref) < 1e-10 and modes_agreement(gi, ref) < 1e-8
    lu = null_space_modes(asm.M, asm.K, asm.A, 6, factorization="superlu")
    assert modes_agreement(lu, ref) < 1e-10
    if fz.has_cholmod():
        chol = null_space_modes(asm.M, asm.K, asm.A, 6, factorization="cholmod")
        assert modes_agreement(chol, ref) < 1e-10
    monkeypatch.setattr(fz, "has_cholmod", lambda: False)
    with pytest.raises(ValueError, match="needs scikit-sparse"):
        fz.factorizer("cholmod")
    with pytest.raises(ValueError, match="unknown factorization"):
        null_space_modes(asm.M, asm.K, asm.A, 6, factorization="mumps")
    with pytest.raises(ValueError, match="saddle-point"):
        fz.factorizer("cholmod", spd=False)
    with pytest.raises(ValueError, match="unknown method"):
        sparse_coupled_modes(asm.M, asm.K, asm.A, 6, method="qr")


# ------------------------------------------------------------------------------- interfaces


@pytest.mark.parametrize("order", [1, 2])
def test_tied_halves_equal_the_monolithic_mesh(order):
    a, b = halves(div=(3, 2, 2), order=order)
    asm = assemble([a, b], tie_nodes(a, b, FACE))
    mono = solid_box("m", BoxGrid((L, B, H), (6, 2, 2)), E, NU, RHO, order=order, fixed=CLAMP)
    ref = null_space_modes(mono.M, mono.K, None, 10)
    tied = null_space_modes(asm.M, asm.K, asm.A, 10)
    np.testing.assert_allclose(tied.omega, ref.omega, rtol=1e-8)
    # P2: the midside nodes of the interface are tied too (9 + 12 + 4 nodes per face)
    per_node = 3
    nodes = (2 * 2 + 1) ** 2 if order == 2 else 9
    assert asm.A.shape[0] == per_node * nodes


def test_tie_by_named_set_from_mesh_files():
    meshes = Path(__file__).resolve().parents[1] / "meshes"
    left = solid_from_mesh("left", meshes / "box_beam_left.msh", E, NU, RHO, fixed=["clamp"])
    right = solid_from_mesh("right", meshes / "box_beam_right.msh", E, NU, RHO)
    ties = tie_nodes(left, right, "interface")
    assert len(ties) == 3 * len(left.meta["node_sets"]["interface"])
    fine = solid_from_mesh("fine", meshes / "box_beam_right_fine.msh", E, NU, RHO)
    with pytest.raises(InterfaceError, match=r"64 of 96 nodes of fine are unmatched; worst "
                                             r"distance 0\.014"):
        tie_nodes(left, fine, "interface")
    match = null_space_modes(*_mka(assemble([left, right], ties)), 4)
    nonmatch = null_space_modes(*_mka(assemble([left, fine],
                                                tie_nonmatching(left, fine, "interface"))), 4)
    np.testing.assert_allclose(nonmatch.omega, match.omega, rtol=5e-3)
    assert nonmatch.residual.max() < 1e-12


def _mka(asm):
    return asm.M, asm.K, asm.A


def test_nonmatching_equals_matching_when_nodes_coincide():
    """Interpolation at coincident nodes gives unit rows: the same frequencies to 1e-8."""
    a, b = halves(div=(3, 2, 2))
    m1 = null_space_modes(*_mka(assemble([a, b], tie_nodes(a, b, FACE))), 6)
    m2 = null_space_modes(*_mka(assemble([a, b], tie_nonmatching(a, b, FACE))), 6)
    np.testing.assert_allclose(m2.omega, m1.omega, rtol=1e-8)


def test_interface_errors_and_2d():
    a, b = halves(div=(2, 1, 1))
    shifted = solid_box("s", BoxGrid((L / 2, B, H), (2, 1, 1), origin=(L / 2, 0.01, 0)), E, NU,
                        RHO)
    plane = {"box": [[L / 2, -1, -1], [L / 2, 1, 1]]}
    with pytest.raises(InterfaceError, match="4 of 4 nodes of a and 4 of 4 nodes of s are "
                                             "unmatched; worst distance 0.01 "):
        tie_nodes(a, shifted, plane)
    with pytest.raises(InterfaceError, match="no node selected"):
        tie_nodes(a, b, {"box": [[5, 5, 5], [6, 6, 6]]})
    with pytest.raises(ValueError, match="node set"):
        tie_nodes(a, b, "interface")
    # supported on both sides: nothing to tie; one side supported: the other is held
    p = solid_rectangle("p", RectangleGrid((0.5, 0.1), (4, 2)), E, NU, RHO,
                        fixed=[{"box": [[0, 0], [0, .1]]}])
    q = solid_rectangle("q", RectangleGrid((0.5, 0.1), (4, 2), origin=(0.5, 0.0)), E, NU, RHO)
    ties = tie_nodes(p, q, {"box": [[0.5, 0], [0.5, 0.1]]})
    assert len(ties) == 2 * 3 and ties[0].a.where["component"] in ("x", "y")
    assert node_dofs(q, {"box": [[0.5, 0], [0.5, 0.1]]}).size == 6
