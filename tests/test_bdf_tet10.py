"""The 10-grid CTETRA (quadratic tetrahedron), against an independent formulation, exact
behaviour and a converged cantilever.

* scikit-fem's ``ElementTetP2`` on the same tetrahedra gives the same ``K`` and coupled ``M``
  to round-off;
* patch test on a distorted mesh: a linear displacement leaves no force at any inner grid
  (corner or mid-side) and stores the closed-form energy of its constant strain; exactly six
  rigid-body modes; the mass is ``rho V``;
* a free 10 x 1 x 1 beam refined in every direction: the first bending frequency converges
  like ``h^4`` (differences of successive meshes fall by 10.5, more than 8 asserted) to
  Timoshenko's (the frame beam with Cowper's shear factor, 0.05 % from the finest mesh); the
  4-grid CTETRA on the same corners gives 2.6 times the converged frequency (locking);
* lumped mass, and a CTETRA with only some mid-side grids, are refused naming the card.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sl
import scipy.sparse as sp
import scipy.sparse.linalg as sla
from skfem import Basis, BilinearForm, ElementTetP2, ElementVector, MeshTet, asm
from skfem.helpers import dot
from skfem.models.elasticity import linear_elasticity

from substruct.case.bdf import parse_bulk
from substruct.case.bdf_fields import BdfError
from substruct.models.beam_batch import BeamBatch, beam_matrices_batch
from substruct.models.nastran import nastran_matrices
from substruct.models.nastran_tet10 import TET10_EDGES
from skfem_dofs import skfem_to_grids

E, NU, RHO = 2.1e11, 0.3, 7850.0
HEAD = ["BEGIN BULK", "MAT1,1,2.1+11,,.3,7850.", "PSOLID,1,1"]


def tet10_mesh(m: MeshTet) -> tuple[np.ndarray, np.ndarray]:
    """Grids (corners then one mid-side grid per edge, at its middle) and the 10 grids of each
    tetrahedron in Nastran's order."""
    p, t = m.p.T, m.t.T
    edges: dict[tuple[int, int], int] = {}
    pts = list(p)
    conn = []
    for tet in t:
        mids = []
        for a, b in TET10_EDGES:
            key = (min(tet[a], tet[b]), max(tet[a], tet[b]))
            if key not in edges:
                edges[key] = len(pts)
                pts.append((p[tet[a]] + p[tet[b]]) / 2)
            mids.append(edges[key])
        conn.append(list(tet) + mids)
    return np.array(pts), np.array(conn)


def bdf(pts: np.ndarray, conn: np.ndarray, extra: list[str]) -> str:
    lines = HEAD + extra + [f"GRID,{k + 1},,{x:.16f},{y:.16f},{z:.16f}"
                            for k, (x, y, z) in enumerate(pts)]
    for e, c in enumerate(conn + 1):
        f = [str(v) for v in c]
        lines += [f"CTETRA,{e + 1},1," + ",".join(f[:6]), "," + ",".join(f[6:])]
    return "\n".join(lines + ["ENDDATA", ""])


def translations(text: str) -> tuple[np.ndarray, np.ndarray]:
    mats = nastran_matrices(parse_bulk(text, "t10.bdf"))
    t = np.flatnonzero(np.arange(mats.K.shape[0]) % 6 < 3)
    return sp.csr_array(mats.K)[t][:, t], sp.csr_array(mats.M)[t][:, t]


def test_the_same_matrices_as_scikit_fems_quadratic_tetrahedron():
    m = MeshTet.init_tensor(np.linspace(0, 1, 3), np.linspace(0, 0.6, 2), np.linspace(0, .4, 3))
    pts, conn = tet10_mesh(m)
    K, M = translations(bdf(pts, conn, ["PARAM,COUPMASS,1"]))
    basis = Basis(m, ElementVector(ElementTetP2()), intorder=4)
    mu, lam = E / (2 * (1 + NU)), E * NU / ((1 + NU) * (1 - 2 * NU))
    Kr = asm(linear_elasticity(lam, mu), basis)
    Mr = asm(BilinearForm(lambda u, v, w: RHO * dot(u, v)), basis)
    P = skfem_to_grids(basis, pts, K.shape[0])
    for ours, ref in ((K, Kr), (M, Mr)):
        diff = abs(ours - P @ sp.csr_array(ref) @ P.T).max()
        assert diff <= 1e-13 * abs(ours).max(), diff


def test_patch_test_rigid_modes_and_mass_on_a_distorted_mesh():
    rng = np.random.default_rng(7)
    m = MeshTet.init_tensor(*(np.linspace(0, 1, 4),) * 3)
    inner = np.all((m.p > 1e-9) & (m.p < 1 - 1e-9), axis=0)
    m = MeshTet(m.p + np.where(inner, rng.uniform(-0.08, 0.08, m.p.shape), 0.0), m.t)
    pts, conn = tet10_mesh(m)  # mid-side grids at the middles: straight edges
    K, M = translations(bdf(pts, conn, ["PARAM,COUPMASS,1"]))
    K, M = K.toarray(), M.toarray()
    G, c = rng.normal(size=(3, 3)), rng.normal(size=3)
    u = (pts @ G.T + c).ravel()
    f = (K @ u).reshape(-1, 3)
    within = np.all((pts > 1e-9) & (pts < 1 - 1e-9), axis=1)
    assert within.sum() > 20
    assert np.abs(f[within]).max() < 1e-10 * np.abs(f).max()
    eps = (G + G.T) / 2
    mu, la = E / (2 * (1 + NU)), E * NU / ((1 + NU) * (1 - 2 * NU))
    assert abs(0.5 * u @ K @ u / (mu * np.sum(eps * eps) + la * np.trace(eps) ** 2 / 2) - 1) \
        < 1e-12  # the unit cube: V = 1
    lam = np.linalg.eigvalsh(K)
    assert np.sum(np.abs(lam) < 1e-9 * lam.max()) == 6
    ones = np.tile([0.0, 1.0, 0.0], len(pts))
    assert abs(ones @ M @ ones / RHO - 1) < 1e-12


def first_bending(n: int, quadratic: bool) -> float:
    """First elastic frequency (rad/s) of a free 10 x 1 x 1 beam of 5n x n x n cubes of six
    tetrahedra (COUPMASS); free, so that no clamped edge limits the convergence rate."""
    m = MeshTet.init_tensor(np.linspace(0, 10, 5 * n + 1), *(np.linspace(0, 1, n + 1),) * 2)
    pts, conn = tet10_mesh(m)
    if not quadratic:
        pts, conn = pts[:m.p.shape[1]], conn[:, :4]
    text = bdf(pts, conn, ["PARAM,COUPMASS,1"])
    if not quadratic:  # the corners' cards: no continuation lines
        text = "\n".join(ln for ln in text.splitlines() if not ln.startswith(","))
    K, M = translations(text)
    lam = np.sort(sla.eigsh(sp.csc_array(K), k=7, M=sp.csc_array(M), sigma=-1.0,
                            which="LM")[0])
    return float(np.sqrt(lam[6]))  # after the six rigid-body modes


def timoshenko_free_free(L: float, h: float, n: int = 100) -> float:
    """First bending frequency (rad/s) of the free L x h x h beam as ``n`` Timoshenko frame
    elements (Cowper's shear factor of a square section, rotary inertia, consistent mass)."""
    G, k, I = E / (2 * (1 + NU)), 10 * (1 + NU) / (12 + 11 * NU), h ** 4 / 12
    x = np.linspace(0, L, n + 1)
    one = np.ones(n)
    b = BeamBatch(xa=np.c_[x[:-1], 0 * one, 0 * one], xb=np.c_[x[1:], 0 * one, 0 * one],
                  v=np.tile([0.0, 1.0, 0.0], (n, 1)), E=E * one, G=G * one, rho=RHO * one,
                  A=h * h * one, Iy=I * one, Iz=I * one, J=2 * I * one, Ip=2 * I * one,
                  ky=k * one, kz=k * one, timoshenko=np.ones(n, dtype=bool))
    Ke, Me, _ = beam_matrices_batch(b)
    K, M = np.zeros((6 * n + 6,) * 2), np.zeros((6 * n + 6,) * 2)
    for e in range(n):
        d = slice(6 * e, 6 * e + 12)
        K[d, d] += Ke[e]
        M[d, d] += Me[e]
    return float(np.sqrt(sl.eigh(K, M, eigvals_only=True, subset_by_index=[6, 6])[0]))


def test_a_free_beam_converges_like_h4_to_timoshenkos_frequency():
    """Measured: 326.73, 323.21, 322.87 rad/s (differences falling by 10.5), Timoshenko's
    322.72 (0.05 % below the finest), Euler-Bernoulli's 3.5 % above it."""
    L, h = 10.0, 1.0
    w = [first_bending(n, True) for n in (1, 2, 4)]
    d1, d2 = w[0] - w[1], w[1] - w[2]
    assert d1 > 0 and d2 > 0 and d1 / d2 > 8, (w, d1 / d2)
    # the finest mesh is within twice its last change of the beam theory
    assert abs(w[2] / timoshenko_free_free(L, h) - 1) < 2 * d2 / w[2], w
    eb = 4.730040744862704 ** 2 * np.sqrt(E * h ** 4 / 12 / (RHO * h * h)) / L ** 2
    assert eb > 1.03 * w[2]  # the shear and rotary inertia a slender-beam formula leaves out
    assert first_bending(1, False) > 2 * w[0]  # the 4-grid CTETRA on the same corners locks


def test_lumped_mass_and_some_mid_side_grids_are_refused():
    m = MeshTet.init_tensor(*(np.linspace(0, 1, 2),) * 3)
    pts, conn = tet10_mesh(m)
    with pytest.raises(BdfError, match="CTETRA 1: .*needs coupled mass"):
        nastran_matrices(parse_bulk(bdf(pts, conn, []), "t10.bdf"))
    text = bdf(pts, conn, ["PARAM,COUPMASS,1"]).splitlines()
    k = next(i for i, ln in enumerate(text) if ln.startswith("CTETRA,1,"))
    text[k + 1] = "," + ",".join(text[k + 1].split(",")[1:3])  # G9, G10 left blank
    with pytest.raises(BdfError, match="CTETRA 1: G9: .*all six mid-side grids"):
        parse_bulk("\n".join(text), "t10.bdf")
