"""The 8-grid CHEXA with bubble functions (MSC Nastran's default PSOLID: IN and ISOP blank),
against exact behaviour and closed forms.

* patch test on a distorted mesh: a linear displacement leaves no force at the inner grid and
  stores the closed-form energy of its constant strain; exactly six rigid-body modes;
* a slender cantilever with one element through the thickness: the first bending frequency
  is within 1.5 % of Euler-Bernoulli's, where full integration (IN 2, ISOP FULL) is far too
  high (measured with ten elements along a 10 x 1 x 0.5 beam: +0.33 % and +65.6 %);
* refining a stocky beam in every direction, both integrations go to one limit: their
  difference falls by about 4 (h^2) at each halving (measured 22.4 %, 6.3 %, 1.7 %), and the
  bubble element is the closer.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sl
from skfem import MeshHex
from skfem.io.meshio import to_meshio

from substruct.case.bdf import parse_bulk
from substruct.models.nastran import nastran_matrices

E, NU, RHO = 2.1e11, 0.3, 7850.0
FULL = "PSOLID,1,1,,2,,FULL"


def block_bdf(x: np.ndarray, y: np.ndarray, z: np.ndarray, psolid: str = "PSOLID,1,1",
              move=None) -> tuple[str, np.ndarray]:
    """A block of CHEXA on the tensor grid ``x, y, z`` (grids ``move``d if given)."""
    m = MeshHex.init_tensor(x, y, z)
    conn = to_meshio(m).cells[0].data  # meshio's corner order is Nastran's
    p = m.p.T.copy() if move is None else move(m.p.T.copy())
    lines = ["BEGIN BULK", "MAT1,1,2.1+11,,.3,7850.", psolid]
    lines += [f"GRID,{k + 1},,{float(a)!r},{float(b)!r},{float(c)!r}"
              for k, (a, b, c) in enumerate(p)]
    for e, c in enumerate(conn + 1):
        f = [str(v) for v in c]
        lines += [f"CHEXA,{e + 1},1," + ",".join(f[:6]), "," + ",".join(f[6:])]
    return "\n".join(lines + ["ENDDATA", ""]), p


def translations(text: str) -> tuple[np.ndarray, np.ndarray]:
    """``K`` and ``M`` of a file on the translations of its grids (3 per grid, in order)."""
    mats = nastran_matrices(parse_bulk(text, "b.bdf"))
    t = np.flatnonzero(np.arange(mats.K.shape[0]) % 6 < 3)
    return mats.K.toarray()[np.ix_(t, t)], mats.M.toarray()[np.ix_(t, t)]


def test_patch_test_and_rigid_modes_on_a_distorted_mesh():
    rng = np.random.default_rng(3)

    def move(p: np.ndarray) -> np.ndarray:  # every grid moved, the block made flat
        return (p + rng.uniform(-0.1, 0.1, p.shape)) * [1.0, 0.7, 0.4]

    g = np.linspace(0, 1, 3)
    text, p = block_bdf(g, g, g, move=move)
    K, M = translations(text)
    G = rng.normal(size=(3, 3))
    u = (p @ G.T + rng.normal(size=3)).ravel()
    f = (K @ u).reshape(-1, 3)
    inner = np.arange(len(p)) == 13  # the middle grid of the 3 x 3 x 3
    assert np.abs(f[inner]).max() < 1e-10 * np.abs(f).max()
    eps = (G + G.T) / 2
    mu, la = E / (2 * (1 + NU)), E * NU / ((1 + NU) * (1 - 2 * NU))
    volume = np.trace(M) / 3 / RHO  # lumped: rho V in equal shares on the translations
    energy = volume * (mu * np.sum(eps * eps) + la * np.trace(eps) ** 2 / 2)
    assert abs(0.5 * u @ K @ u / energy - 1) < 1e-12
    lam = np.linalg.eigvalsh(K)
    assert np.sum(np.abs(lam) < 1e-9 * lam.max()) == 6
    assert lam[6] > 1e-4 * lam.max()  # no zero-energy mode besides the rigid ones


def first_bending(text: str, L: float, b: float, h: float) -> float:
    """First bending frequency (rad/s) of the block clamped at ``x = 0``, on the lowest of
    the transverse modes (lumped mass)."""
    K, M = translations(text)
    n = K.shape[0] // 3
    x = np.array([float(ln.split(",")[3]) for ln in text.splitlines()
                  if ln.startswith("GRID")])
    assert x.size == n
    free = np.flatnonzero(np.repeat(x > 1e-12, 3))
    w2 = sl.eigh(K[np.ix_(free, free)], M[np.ix_(free, free)], eigvals_only=True,
                 subset_by_index=[0, 0])
    return float(np.sqrt(w2[0]))


def euler_bernoulli(L: float, b: float, h: float) -> float:
    """First cantilever frequency of the beam bending about its thinner side."""
    t = min(b, h)
    I, A = max(b, h) * t ** 3 / 12, b * h
    return 1.875104068711961 ** 2 * np.sqrt(E * I / (RHO * A * L ** 4))


def test_slender_cantilever_one_element_thick_is_close_to_euler_bernoulli():
    L, b, h = 10.0, 1.0, 0.5
    axes = (np.linspace(0, L, 11), np.linspace(0, b, 2), np.linspace(0, h, 2))
    ref = euler_bernoulli(L, b, h)
    bubble = first_bending(block_bdf(*axes)[0], L, b, h) / ref - 1
    full = first_bending(block_bdf(*axes, psolid=FULL)[0], L, b, h) / ref - 1
    # the bubble element's error is the lumped mass's and the 3D block's (O(1 %)), full
    # integration's the shear locking of h/L_e = 1/2 elements
    assert abs(bubble) < 0.015, bubble
    assert full > 0.2, full
    assert abs(full) > 10 * abs(bubble)


def test_both_integrations_converge_to_one_limit():
    L, b, h = 2.0, 0.5, 0.5
    diffs, errs_b, errs_f = [], [], []
    fine = None
    for n in (1, 2, 4):
        axes = (np.linspace(0, L, 4 * n + 1), np.linspace(0, b, n + 1),
                np.linspace(0, h, n + 1))
        wb = first_bending(block_bdf(*axes)[0], L, b, h)
        wf = first_bending(block_bdf(*axes, psolid=FULL)[0], L, b, h)
        diffs.append(abs(wf - wb) / wb)
        errs_b.append(wb)
        errs_f.append(wf)
        fine = wb
    assert diffs[1] < diffs[0] / 3 and diffs[2] < diffs[1] / 3, diffs
    # the bubble element is nearer the common limit at every size
    for wb, wf in zip(errs_b, errs_f):
        assert abs(wb - fine) < abs(wf - fine) or wb == fine
