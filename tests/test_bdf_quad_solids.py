"""The 20-grid CHEXA (serendipity hexahedron) and the 15-grid CPENTA (quadratic wedge), against
an independent formulation, exact behaviour and a converged beam.

* scikit-fem's ``ElementHexS2`` (its 20-node serendipity hexahedron) on the same distorted
  hexahedra, with the same 3 x 3 x 3 points, gives the same ``K`` and coupled ``M`` to
  round-off;
* patch test on a distorted mesh of CHEXA20 alone and of CHEXA20 and CPENTA15 sharing
  faces: a linear displacement leaves no force at any inner grid and stores the closed-form
  energy of its constant strain; exactly six rigid-body modes; the mass is ``rho V``;
* the wedge holds every quadratic field: its strain energy and kinetic energy equal the
  closed forms integrated independently (scikit-fem's quadratic tetrahedra on the same box);
* a free 10 x 1 x 1 beam of CHEXA20, and of CPENTA15, refined in every direction converges to
  Timoshenko's frequency at a measured rate;
* a curved element (a mid-side grid off its edge's middle) still passes the patch test, and
  one moved past the quarter point of its edge is refused naming the card;
* lumped mass, some mid-side grids, and PSOLID without IN 3 / ISOP FULL are refused naming
  the card and field.
"""

from __future__ import annotations

import meshio
import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as sla
from skfem import Basis, BilinearForm, ElementHexS2, ElementTetP2, ElementVector, Functional, \
    MeshTet, asm
from skfem.helpers import ddot, dot, sym_grad, trace
from skfem.io.meshio import from_meshio
from skfem.models.elasticity import linear_elasticity

from substruct.case.bdf import parse_bulk
from substruct.case.bdf_fields import BdfError
from substruct.models.nastran import nastran_matrices
from substruct.models.nastran_bubble import isotropic_D
from substruct.models.nastran_quad_solids import HEX20_EDGES, PENTA15_EDGES, penta15_matrices
from test_bdf_tet10 import timoshenko_free_free
from skfem_dofs import skfem_to_grids

E, NU, RHO = 2.1e11, 0.3, 7850.0
FULL = "PSOLID,1,1,,THREE,,FULL"
MU, LAM = E / (2 * (1 + NU)), E * NU / ((1 + NU) * (1 - 2 * NU))


def box_mesh(xs, ys, zs, wedge_columns=(), jiggle=0.0, seed=3):
    """Corners of a tensor grid (inner ones moved by up to ``jiggle``), hexahedra in Nastran's
    corner order, those of the ``(i, j)`` columns split into two wedges each (along the
    G1-G3 diagonal of the z-faces: conforming, the triangles stack along z); then one mid-side
    grid per edge at its middle.  Returns grids and the lists of 20- and 15-grid cells."""
    nx, ny, nz = len(xs), len(ys), len(zs)
    P = np.array([[x, y, z] for z in zs for y in ys for x in xs], dtype=float)
    inner = np.all((P > P.min(axis=0) + 1e-9) & (P < P.max(axis=0) - 1e-9), axis=1)
    h = min(np.diff(xs).min(), np.diff(ys).min(), np.diff(zs).min())
    P[inner] += np.random.default_rng(seed).uniform(-jiggle, jiggle, (inner.sum(), 3)) * h

    def v(i, j, k):
        return i + nx * (j + ny * k)

    hexes, wedges = [], []
    for k in range(nz - 1):
        for j in range(ny - 1):
            for i in range(nx - 1):
                c = [v(i, j, k), v(i + 1, j, k), v(i + 1, j + 1, k), v(i, j + 1, k)]
                c += [a + nx * ny for a in c]
                if (i, j) in wedge_columns:
                    wedges += [[c[0], c[1], c[2], c[4], c[5], c[6]],
                               [c[0], c[2], c[3], c[4], c[6], c[7]]]
                else:
                    hexes.append(c)
    pts = list(P)
    edges: dict[tuple[int, int], int] = {}

    def mids(cell, pairs):
        out = []
        for a, b in pairs:
            key = (min(cell[a], cell[b]), max(cell[a], cell[b]))
            if key not in edges:
                edges[key] = len(pts)
                pts.append((P[cell[a]] + P[cell[b]]) / 2)
            out.append(edges[key])
        return list(cell) + out

    h20 = [mids(c, HEX20_EDGES) for c in hexes]
    p15 = [mids(c, PENTA15_EDGES) for c in wedges]
    return np.array(pts), np.array(h20, dtype=int).reshape(-1, 20), \
        np.array(p15, dtype=int).reshape(-1, 15), np.array(hexes, dtype=int).reshape(-1, 8)


def card(name: str, eid: int, conn) -> list[str]:
    f = [str(g + 1) for g in conn]
    lines = [f"{name},{eid},1," + ",".join(f[:6])]
    for k in range(6, len(f), 8):
        lines.append("," + ",".join(f[k:k + 8]))
    return lines


def bdf(pts, h20, p15, extra=("PARAM,COUPMASS,1",), psolid=FULL) -> str:
    lines = ["BEGIN BULK", "MAT1,1,2.1+11,,.3,7850.", psolid, *extra]
    lines += [f"GRID,{k + 1},,{x:.16f},{y:.16f},{z:.16f}" for k, (x, y, z) in enumerate(pts)]
    for e, c in enumerate(h20):
        lines += card("CHEXA", e + 1, c)
    for e, c in enumerate(p15):
        lines += card("CPENTA", 1000 + e, c)
    return "\n".join(lines + ["ENDDATA", ""])


def translations(text: str) -> tuple[sp.csr_array, sp.csr_array]:
    mats = nastran_matrices(parse_bulk(text, "q.bdf"))
    t = np.flatnonzero(np.arange(mats.K.shape[0]) % 6 < 3)
    return sp.csr_array(mats.K)[t][:, t], sp.csr_array(mats.M)[t][:, t]


def test_the_same_matrices_as_scikit_fems_serendipity_hexahedron():
    pts, h20, _, corners = box_mesh(np.linspace(0, 1, 3), np.linspace(0, .6, 3),
                                    np.linspace(0, .4, 3), jiggle=0.15)
    K, M = translations(bdf(pts, h20, []))
    nc = corners.max() + 1
    mesh = from_meshio(meshio.Mesh(pts[:nc], [("hexahedron", corners)]))
    basis = Basis(mesh, ElementVector(ElementHexS2()), intorder=5)  # 3 x 3 x 3 Gauss points
    assert basis.X.shape[1] == 27
    Kr = asm(linear_elasticity(LAM, MU), basis)
    Mr = asm(BilinearForm(lambda u, v, w: RHO * dot(u, v)), basis)
    P = skfem_to_grids(basis, pts, K.shape[0])
    for ours, ref in ((K, Kr), (M, Mr)):
        diff = abs(ours - P @ sp.csr_array(ref) @ P.T).max()
        assert diff <= 1e-12 * abs(ours).max(), diff


@pytest.mark.parametrize("columns", [(), ((0, 1), (1, 1), (2, 0))])
def test_patch_test_rigid_modes_and_mass_on_a_distorted_mesh(columns):
    """CHEXA20 alone, then with three columns of CPENTA15 sharing their faces."""
    ax = np.linspace(0, 1, 4)
    pts, h20, p15, _ = box_mesh(ax, ax, ax, wedge_columns=columns, jiggle=0.2)
    assert len(p15) == 6 * len(columns)
    K, M = translations(bdf(pts, h20, p15))
    K, M = K.toarray(), M.toarray()
    rng = np.random.default_rng(11)
    G, c = rng.normal(size=(3, 3)), rng.normal(size=3)
    u = (pts @ G.T + c).ravel()
    f = (K @ u).reshape(-1, 3)
    within = np.all((pts > 1e-9) & (pts < 1 - 1e-9), axis=1)
    assert within.sum() >= 44  # 8 inner corners and 36 inner edges
    assert np.abs(f[within]).max() < 1e-10 * np.abs(f).max()
    eps = (G + G.T) / 2
    assert abs(0.5 * u @ K @ u / (MU * np.sum(eps * eps) + LAM * np.trace(eps) ** 2 / 2) - 1) \
        < 1e-12  # the unit cube: V = 1
    lam = np.linalg.eigvalsh(K)
    assert np.sum(np.abs(lam) < 1e-9 * lam.max()) == 6
    ones = np.tile([0.0, 0.0, 1.0], len(pts))
    assert abs(ones @ M @ ones / RHO - 1) < 1e-12


def test_the_wedge_holds_quadratic_fields_with_their_exact_energies():
    """Straight prisms (constant Jacobian in z, sheared triangles): for a quadratic
    displacement the element's strain and kinetic energies are the integrals, computed by
    scikit-fem's quadratic tetrahedra on a tetrahedral mesh of the same box."""
    ax = np.linspace(0, 1, 3)
    cols = tuple((i, j) for i in range(2) for j in range(2))
    pts, h20, p15, _ = box_mesh(ax, ax, ax, wedge_columns=cols)
    assert len(h20) == 0
    K, M = translations(bdf(pts, h20, p15))
    rng = np.random.default_rng(5)
    A = rng.normal(size=(3, 10))

    def field(x):
        x, y, z = x
        mono = [np.ones_like(x), x, y, z, x * x, y * y, z * z, x * y, y * z, z * x]
        return np.einsum("ck,k...->c...", A, np.array(mono))

    u = field(pts.T).T.ravel()
    m = MeshTet.init_tensor(*(np.linspace(0, 1, 3),) * 3)
    basis = Basis(m, ElementVector(ElementTetP2()), intorder=4)
    U = basis.interpolate(basis.project(field))  # exact: P2 holds the field

    @Functional
    def strain(w):
        e = sym_grad(w["u"])
        return MU * ddot(e, e) + LAM * trace(e) ** 2 / 2

    @Functional
    def kinetic(w):
        return RHO * dot(w["u"], w["u"]) / 2

    for ours, ref in ((0.5 * u @ (K @ u), strain.assemble(basis, u=U)),
                      (0.5 * u @ (M @ u), kinetic.assemble(basis, u=U))):
        assert abs(ours / ref - 1) < 1e-12, (ours, ref)


def first_bending(n: int, wedges: bool) -> float:
    """First elastic frequency (rad/s) of a free 10 x 1 x 1 beam of 5n x n x n CHEXA20, or of
    the same hexahedra each cut into two CPENTA15 (triangles across the beam's width)."""
    cols = tuple((i, j) for i in range(5 * n) for j in range(n)) if wedges else ()
    pts, h20, p15, _ = box_mesh(np.linspace(0, 10, 5 * n + 1), *(np.linspace(0, 1, n + 1),) * 2,
                                wedge_columns=cols)
    K, M = translations(bdf(pts, h20, p15))
    lam = np.sort(sla.eigsh(sp.csc_array(K), k=7, M=sp.csc_array(M), sigma=-1.0,
                            which="LM")[0])
    return float(np.sqrt(lam[6]))  # after the six rigid-body modes


@pytest.mark.parametrize("wedges", [False, True])
def test_a_free_beam_converges_to_timoshenkos_frequency(wedges):
    """Measured: CHEXA20 325.447, 323.030, 322.854 rad/s (differences falling by 13.7);
    CPENTA15 325.342, 323.026, 322.854 (by 13.4); Timoshenko's 322.724, 0.04 % below the
    finest of either."""
    w = [first_bending(n, wedges) for n in (1, 2, 4)]
    d1, d2 = w[0] - w[1], w[1] - w[2]
    assert d1 > 0 and d2 > 0 and d1 / d2 > 8, (w, d1 / d2)
    # the finest mesh is within twice its last change of the beam theory
    assert abs(w[2] / timoshenko_free_free(10.0, 1.0) - 1) < 2 * d2 / w[2], w


def test_a_curved_element_is_integrated_and_an_inverted_one_refused():
    """A mid-side grid moved along its edge to 0.3 of it keeps the element valid (the patch test
    still holds: a linear field is in the isoparametric space); at 0.2, past the quarter point,
    the Jacobian changes sign at the corner and the card is named (the wedge alike)."""
    ax = np.linspace(0, 1, 3)
    pts, h20, p15, _ = box_mesh(ax, ax, ax, wedge_columns=((1, 1),))
    g = h20[0][8]  # G9 of the first CHEXA, on its edge 1-2 (inside the box)
    a, b = pts[h20[0][0]], pts[h20[0][1]]
    moved = pts.copy()
    moved[g] = a + 0.3 * (b - a)
    K, _ = translations(bdf(moved, h20, p15))
    u = (moved @ np.diag([1.0, -0.5, 0.25])).ravel()
    f = (K @ u).reshape(-1, 3)
    within = np.all((moved > 1e-9) & (moved < 1 - 1e-9), axis=1)
    assert np.abs(f[within]).max() < 1e-10 * np.abs(f).max()
    moved[g] = a + 0.2 * (b - a)
    with pytest.raises(BdfError, match="CHEXA 1: .*Jacobian vanishes or changes sign"):
        nastran_matrices(parse_bulk(bdf(moved, h20, p15), "q.bdf"))
    X = pts[p15[0]].copy()
    D = isotropic_D(E, NU)
    for t, ok in ((0.3, True), (0.2, False)):
        X[6] = X[0] + t * (X[1] - X[0])  # G7 on the wedge's edge 1-2
        if ok:
            penta15_matrices(X[None], D, RHO)
        else:
            with pytest.raises(ValueError, match="Jacobian"):
                penta15_matrices(X[None], D, RHO)


def test_lumped_mass_some_mid_side_grids_and_reduced_integration_are_refused():
    ax = np.linspace(0, 1, 2)
    pts, h20, p15, _ = box_mesh(ax, ax, ax, wedge_columns=((0, 0),))
    with pytest.raises(BdfError, match="CPENTA 1000: .*15-grid CPENTA needs coupled mass"):
        nastran_matrices(parse_bulk(bdf(pts, h20, p15, extra=()), "q.bdf"))
    for psolid, field in (("PSOLID,1,1", "IN"), ("PSOLID,1,1,,3", "ISOP"),
                          ("PSOLID,1,1,,2,,FULL", "IN")):
        with pytest.raises(BdfError, match=f"PSOLID 1: {field}: .*full 3 x 3 x 3"):
            parse_bulk(bdf(pts, h20, p15, psolid=psolid), "q.bdf")
    pts, h20, _, _ = box_mesh(ax, ax, ax)
    text = bdf(pts, h20, []).splitlines()
    k = next(i for i, ln in enumerate(text) if ln.startswith("CHEXA,1,"))
    text[k + 2] = "," + ",".join(text[k + 2].split(",")[1:4])  # G18 - G20 left blank
    with pytest.raises(BdfError, match="CHEXA 1: G18: .*all twelve mid-side grids G9-G20"):
        parse_bulk("\n".join(text), "q.bdf")
