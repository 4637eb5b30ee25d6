"""Craig-Bampton with interface reduction: classical CB in the limit, conforming convergence
from above against the monolithic solve, parts independent of the assembly."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

from reference_reduced_coupling import couple_reduced, reduced_modes
from substruct.models.craig_bampton import craig_bampton
from substruct.models.interface_basis import interface_basis, polynomial_fields
from substruct.models.interface_box import (
    BoxCut,
    box_part,
    part_interfaces,
    reduce_box_part,
)
from substruct.models.interface_reduction import reduce_part, truncate_part

CUT = BoxCut((6.0, 1.0, 1.0), (24, 3, 3), 3)
N_MODES = 12


@pytest.fixture(scope="module")
def monolithic():
    box = CUT.whole()
    lam = sla.eigh(box.K.toarray(), box.M.toarray(), eigvals_only=True,
                   subset_by_index=[0, N_MODES - 1])
    return box, np.sqrt(lam)


def assembly_error(g: int, p: int | None, exact: np.ndarray) -> np.ndarray:
    parts = [reduce_box_part(CUT, k, g, p) for k in range(CUT.n_parts)]
    omega, _ = reduced_modes(couple_reduced(parts), N_MODES)
    return (omega - exact) / exact


def test_polynomial_fields_count_and_scale():
    """(p+1)(p+2)/2 orthonormal fields on a plane grid, rigid motions inside at p = 1, and the
    same span whatever the units and the node order."""
    y, z = np.meshgrid(np.linspace(0, 1, 5), np.linspace(0, 2, 6), indexing="ij")
    xyz = np.column_stack([np.full(y.size, 3.0), y.ravel(), z.ravel()])
    for p, m in [(0, 1), (1, 3), (2, 6), (3, 10)]:
        F = polynomial_fields(xyz, p)
        assert F.shape == (30, m)
        np.testing.assert_allclose(F.T @ F, np.eye(m), atol=1e-12)
    F = polynomial_fields(xyz, 1)
    # a rotation about x: u_y = -z, u_z = y lies in span(F) per component
    for field in (xyz[:, 2], xyz[:, 1]):
        assert np.linalg.norm(field - F @ (F.T @ field)) < 1e-12 * np.linalg.norm(field)
    perm = np.random.default_rng(1).permutation(30)
    G = polynomial_fields(1e-3 * xyz[perm], 3)
    F3 = polynomial_fields(xyz, 3)[perm]
    assert np.linalg.norm(G - F3 @ (F3.T @ G)) < 1e-10


def test_full_interface_basis_is_classical_craig_bampton():
    """R = I: the same reduced matrices as craig_bampton (columns reordered) to round-off."""
    sub = box_part(CUT, 1)
    faces = part_interfaces(CUT, 1, sub, None)
    red = reduce_part(sub, faces, 8)
    b = np.concatenate([f.dofs for f in faces])
    ref = craig_bampton(sub, b, 8)
    # craig_bampton orders the boundary ascending; ours in the interfaces' node order
    order = np.concatenate([np.arange(8), 8 + np.searchsorted(np.unique(b), b)])
    Kref, Mref = ref.K.toarray()[np.ix_(order, order)], ref.M.toarray()[np.ix_(order, order)]
    np.testing.assert_allclose(red.K, Kref, rtol=0, atol=1e-10 * abs(Kref).max())
    np.testing.assert_allclose(red.M, Mref, rtol=0, atol=1e-10 * abs(Mref).max())
    np.testing.assert_allclose(red.omega_fixed_interface, ref.meta["omega_fixed_interface"],
                               rtol=1e-12)


def test_full_basis_with_all_modes_is_the_monolithic_solve(monolithic):
    """g = every interior mode and R = I span the whole finite-element space."""
    _, exact = monolithic
    parts = []
    for k in range(CUT.n_parts):
        sub = box_part(CUT, k)
        faces = part_interfaces(CUT, k, sub, None)
        ni = sub.n_dof - sum(f.dofs.size for f in faces)
        parts.append(reduce_part(sub, faces, ni))
    omega, _ = reduced_modes(couple_reduced(parts), N_MODES)
    np.testing.assert_allclose(omega, exact, rtol=1e-9)


def test_converges_from_above_as_modes_and_degree_grow(monolithic):
    """Conforming Ritz space: every frequency above the monolithic one; the largest error of
    the 12 lowest falls as g grows (p = 4) and as p grows (g = 30; p = 3 adds only odd
    cross-section fields, which these modes hardly use)."""
    _, exact = monolithic
    by_g = [assembly_error(g, 4, exact) for g in (4, 8, 16, 30)]
    by_p = [assembly_error(30, p, exact) for p in (0, 1, 2, 4)]
    for err in by_g + by_p:
        assert err.min() > -1e-10
    worst_g = [e.max() for e in by_g]
    worst_p = [e.max() for e in by_p]
    assert all(b < a for a, b in zip(worst_g, worst_g[1:])), worst_g
    assert all(b < a for a, b in zip(worst_p, worst_p[1:])), worst_p
    assert worst_g[0] > 10 * worst_g[-1]
    assert worst_p[0] > 10 * worst_p[-1]
    assert worst_p[-1] < 1e-3


def test_parts_are_independent_of_the_assembly(monolithic):
    """The coupled matrices are T^T K T of the monolithic box with the parts' T placed on the
    global nodes (each part's energy is its own), and a part reduced alone is bit for bit the
    part reduced in the loop."""
    box, _ = monolithic
    parts = [reduce_box_part(CUT, k, 6, 2) for k in range(CUT.n_parts)]
    asm = couple_reduced(parts)
    alone = reduce_box_part(CUT, 1, 6, 2)
    assert np.array_equal(alone.K, parts[1].K) and np.array_equal(alone.M, parts[1].M)
    # global T: the monolithic coordinate of each part node, by position
    pts = box.geometry.points
    index = {tuple(np.round(x, 9)): i for i, x in enumerate(pts)}
    interp = box.geometry.interp.tocsr()
    T = np.zeros((box.n_dof, asm.K.shape[0]))
    for k, part in enumerate(parts):
        sub = box_part(CUT, k)
        Tk = part.recover(asm.maps[k])  # part DOFs x global reduced coordinates
        sp_interp = sub.geometry.interp.tocsr()
        for node, x in enumerate(sub.geometry.points):
            for c in range(3):
                row = sp_interp[[3 * node + c]]
                if row.nnz == 0:
                    continue
                gl = interp[[3 * index[tuple(np.round(x, 9))] + c]].indices[0]
                T[gl] = Tk[row.indices[0]]  # interface rows agree on both sides
    np.testing.assert_allclose(T.T @ (box.K @ T), asm.K, rtol=0,
                               atol=1e-9 * abs(asm.K).max())
    np.testing.assert_allclose(T.T @ (box.M @ T), asm.M, rtol=0,
                               atol=1e-9 * abs(asm.M).max())


def test_mismatched_interface_bases_are_refused():
    sub0, sub1 = box_part(CUT, 0), box_part(CUT, 1)
    x = CUT.x_at(CUT.cut_elements()[1])
    face = [[x, 0, 0], [x, 1, 1]]
    a = reduce_part(sub0, [interface_basis(sub0, "cut1", face, 1)], 4)
    b = reduce_part(sub1, [interface_basis(sub1, "cut1", face, 2)], 4)
    with pytest.raises(ValueError, match="cut1"):
        couple_reduced([a, b])


def test_truncated_part_is_the_part_reduced_smaller():
    """Fewer modes and a lower degree from an already reduced part: the matrices of the
    direct reduction, to round-off (nested modes, constraint modes linear in the basis).  A
    rectangular section, so that no two fixed-interface modes share a frequency."""
    flat = BoxCut((6.0, 1.0, 0.6), (24, 3, 2), 3)
    big = reduce_box_part(flat, 1, 10, 4)
    small = reduce_box_part(flat, 1, 6, 2)
    cut = truncate_part(big, 6, 2)
    assert cut.size == small.size
    np.testing.assert_allclose(cut.K, small.K, rtol=0, atol=1e-9 * abs(small.K).max())
    np.testing.assert_allclose(cut.M, small.M, rtol=0, atol=1e-9 * abs(small.M).max())
    np.testing.assert_allclose(cut.T, small.T, rtol=0, atol=1e-9 * abs(small.T).max())
