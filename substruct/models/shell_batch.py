r"""The flat shell element matrices of :mod:`substruct.models.shell` for many elements at once.

Every quantity of the per-element function :func:`substruct.models.shell.shell_matrices` is
computed for a stack of ``m`` elements of the same shape (3 or 4 corners) and properties,
with the same quadrature: arrays carry a leading element axis and the products are
``numpy.einsum`` over it.  With corners ``X`` ``(m, n, 3)``:

* axes :math:`R_e` (rows :math:`e_x, e_y, e_z`) and plane corners ``xy`` ``(m, n, 2)``;
* bending (DKT/DKQ): the discrete Kirchhoff maps :math:`T_b, T_w` side by side, then
  :math:`K_b = \sum_q w_q \det J_q\, B_q^T D_b B_q` and
  :math:`M_b = \sum_q w_q \det J_q (\mu N_w^T N_w + r N_\beta^T N_\beta)`; or, with a
  transverse shear stiffness, MITC4/MITC3 (:mod:`substruct.models.mindlin_plate`, batched
  there);
* membrane (CST/QM6, the incompatible modes condensed by a batched solve) and the drilling
  penalty :math:`\gamma t \sum_q w_q \det J_q\, g_q g_q^T`;
* global axes blockwise: :math:`K^{(ab)} = R^T K_{loc}^{(ab)} R` for each pair of corners;
* the rigid offsets of a warped quadrilateral's nodes to its mean plane, :math:`W^T K W`
  (:func:`substruct.models.shell.warp_offsets`).

The per-element function stays the reference; the two agree to round-off.  An element that
the per-element function refuses is refused with its message: on any failed check the batch
runs the per-element function on the first failing element.
"""

from __future__ import annotations

import numpy as np

from substruct.models.mindlin_plate import mindlin_matrices_batch
from substruct.models.plate_bending import corner_shapes, plane_stress, tabulated
from substruct.models.shell import (
    DRILL_PENALTY, MAX_WARP, SHELL_MASSES, ShellTerms, shell_matrices, warp_offsets,
)

__all__ = ["shell_matrices_batch"]


def _inv2(J: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Determinants ``(m,)`` and inverses ``(m, 2, 2)`` of a stack of 2 x 2 matrices."""
    det = J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0]
    inv = np.empty_like(J)
    inv[:, 0, 0], inv[:, 1, 1] = J[:, 1, 1], J[:, 0, 0]
    inv[:, 0, 1], inv[:, 1, 0] = -J[:, 0, 1], -J[:, 1, 0]
    return det, inv / det[:, None, None]


def _axes(X: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(R, xy, ok)``: axes, plane corners and the elements passing the axis checks."""
    m, n = X.shape[:2]
    if n == 3:
        ez = np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0])
    else:
        ez = np.cross(X[:, 2] - X[:, 0], X[:, 3] - X[:, 1])
    size = np.linalg.norm(X[:, 1:] - X[:, :1], axis=2).max(axis=1)
    nz = np.linalg.norm(ez, axis=1)
    ok = nz > 1e-12 * size**2
    ez = ez / np.where(ok, nz, 1.0)[:, None]
    c = X.mean(axis=1)
    if n == 4:
        diag = np.minimum(np.linalg.norm(X[:, 2] - X[:, 0], axis=1),
                          np.linalg.norm(X[:, 3] - X[:, 1], axis=1))
        warp = np.abs(np.einsum("mkc,mc->mk", X - c[:, None], ez)).max(axis=1) / \
            np.where(diag > 0, diag, 1.0)
        ok &= ~(warp > MAX_WARP)
    d = X[:, 1] - X[:, 0]
    ex = d - np.einsum("mc,mc->m", d, ez)[:, None] * ez
    nx = np.linalg.norm(ex, axis=1)
    ok &= nx > 0
    ex = ex / np.where(nx > 0, nx, 1.0)[:, None]
    R = np.stack([ex, np.cross(ez, ex), ez], axis=1)
    xy = np.einsum("mkc,mic->mki", X - c[:, None], R[:, :2])
    if n == 4:  # the corner Jacobians, as shell_axes: a collapsed or folded corner
        e1 = np.roll(xy, -1, axis=1) - xy
        e2 = np.roll(xy, 1, axis=1) - xy
        corner = e1[..., 0] * e2[..., 1] - e1[..., 1] * e2[..., 0]
        ok &= np.all(corner > 1e-12 * size[:, None] ** 2, axis=1)
    return R, xy, ok


def _kirchhoff_maps(xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Batched :func:`substruct.models.plate_bending.kirchhoff_maps`."""
    m, n = xy.shape[:2]
    Tb = np.zeros((m, 4 * n, 3 * n))
    Tw = np.zeros((m, 2 * n, 3 * n))
    for i in range(n):
        Tb[:, 2 * i, 3 * i + 2] = 1.0
        Tb[:, 2 * i + 1, 3 * i + 1] = -1.0
        Tw[:, i, 3 * i] = 1.0
    eye = np.eye(2)
    for i in range(n):
        j = (i + 1) % n
        d = xy[:, j] - xy[:, i]
        l = np.hypot(d[:, 0], d[:, 1])
        t = d / l[:, None]
        k = n + i
        bsum = Tb[:, 2 * i:2 * i + 2] + Tb[:, 2 * j:2 * j + 2]
        P = 0.5 * eye - 0.75 * np.einsum("ma,mb->mab", t, t)
        Tb[:, 2 * k:2 * k + 2] = np.einsum("mab,mbc->mac", P, bsum)
        Tb[:, 2 * k:2 * k + 2, 3 * j] += -1.5 / l[:, None] * t
        Tb[:, 2 * k:2 * k + 2, 3 * i] -= -1.5 / l[:, None] * t
        db = Tb[:, 2 * j:2 * j + 2] - Tb[:, 2 * i:2 * i + 2]
        Tw[:, k] = (Tw[:, i] + Tw[:, j]) / 2 + l[:, None] / 8 * np.einsum("ma,mac->mc", t, db)
    return Tb, Tw


def _btdb(w: np.ndarray, B1: np.ndarray, D: np.ndarray, B2: np.ndarray) -> np.ndarray:
    """``w_e B1_e^T D B2_e`` for each element ``e`` (batched matrix products)."""
    return w[:, None, None] * (B1.transpose(0, 2, 1) @ (D @ B2))


def _strain(dx: np.ndarray) -> np.ndarray:
    """``(m, 3, 2k)`` strains of node-by-node pairs from derivatives ``(m, 2, k)``."""
    m, _, k = dx.shape
    B = np.zeros((m, 3, 2 * k))
    B[:, 0, 0::2] = dx[:, 0]
    B[:, 1, 1::2] = dx[:, 1]
    B[:, 2, 0::2] = dx[:, 1]
    B[:, 2, 1::2] = dx[:, 0]
    return B


def _bending(xy: np.ndarray, Db: np.ndarray, mu: float, rot: float,
             consistent: bool) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
    """Batched DKT/DKQ stiffness and consistent mass, and the elements with ``det J > 0``."""
    m, n = xy.shape[:2]
    Tb, Tw = _kirchhoff_maps(xy)
    K = np.zeros((m, 3 * n, 3 * n))
    ok = np.ones(m, dtype=bool)
    for _, wq, _, dN, _, dQ in tabulated(n, "stiffness"):
        det, inv = _inv2(np.einsum("ak,mkb->mab", dN, xy))
        ok &= det > 0
        B = np.einsum("mak,mkc->mac", _strain(np.einsum("mab,bk->mak", inv, dQ)), Tb)
        K += _btdb(wq * det, B, Db, B)
    if not consistent:
        return (K + K.transpose(0, 2, 1)) / 2, None, ok
    points = tabulated(n, "mass")
    Q = np.array([N for _, _, _, _, N, _ in points])  # (q, 2n) quadratic shapes
    W = np.stack([wq * _inv2(np.einsum("ak,mkb->mab", dN, xy))[0]
                  for _, wq, _, dN, _, _ in points], axis=1)  # (m, q)
    Nw = Q @ Tw  # (m, q, 3n)
    Nb = np.concatenate([Q @ Tb[:, 0::2], Q @ Tb[:, 1::2]], axis=1)  # (m, 2q, 3n)
    M = (mu * W[:, :, None] * Nw).transpose(0, 2, 1) @ Nw
    if rot:
        M += (rot * np.concatenate([W, W], axis=1)[:, :, None] * Nb).transpose(0, 2, 1) @ Nb
    return (K + K.transpose(0, 2, 1)) / 2, (M + M.transpose(0, 2, 1)) / 2, ok


def _membrane(xy: np.ndarray, E: float, nu: float, t: float) -> tuple[np.ndarray, np.ndarray]:
    """Batched :func:`substruct.models.shell.membrane_matrices` and the elements with
    ``det J > 0``."""
    m, n = xy.shape[:2]
    C = plane_stress(E, nu) * t
    gamma = DRILL_PENALTY * E / (2 * (1 + nu)) * t
    uv = np.concatenate([[3 * k, 3 * k + 1] for k in range(n)])
    rz = 3 * np.arange(n) + 2
    K = np.zeros((m, 3 * n, 3 * n))
    det0, inv0 = _inv2(np.einsum(
        "ak,mkb->mab", corner_shapes(n, np.zeros(2) if n == 4 else np.full(2, 1 / 3))[1], xy))
    Kcc = np.zeros((m, 2 * n, 2 * n))
    Kci, Kii = np.zeros((m, 2 * n, 4)), np.zeros((m, 4, 4))
    ok = np.ones(m, dtype=bool)
    for p, wq, N, dN, _, _ in tabulated(n, "stiffness"):
        det, inv = _inv2(np.einsum("ak,mkb->mab", dN, xy))
        ok &= det > 0
        dx = np.einsum("mab,bk->mak", inv, dN)
        B = _strain(dx)
        w = wq * det
        Kcc += _btdb(w, B, C, B)
        if n == 4:
            dP = np.array([[-2 * p[0], 0.0], [0.0, -2 * p[1]]])
            Bi = _strain((det0 / det)[:, None, None] * np.einsum("mab,bk->mak", inv0, dP))
            Kci += _btdb(w, B, C, Bi)
            Kii += _btdb(w, Bi, C, Bi)
        g = np.zeros((m, 3 * n))
        g[:, rz] = N
        g[:, uv[0::2]] += 0.5 * dx[:, 1]
        g[:, uv[1::2]] -= 0.5 * dx[:, 0]
        K += (w * gamma)[:, None, None] * (g[:, :, None] * g[:, None, :])
    if n == 4:
        good = ok & (det0 > 0)
        Kii[~good] = np.eye(4)
        Kcc = Kcc - Kci @ np.linalg.solve(Kii, Kci.transpose(0, 2, 1))
    K[:, uv[:, None], uv[None, :]] += Kcc
    return (K + K.transpose(0, 2, 1)) / 2, ok


def _membrane_mass(xy: np.ndarray, mu: float, rot: float) -> np.ndarray:
    m, n = xy.shape[:2]
    M = np.zeros((m, 3 * n, 3 * n))
    for _, wq, N, dN, _, _ in tabulated(n, "mass"):
        det = _inv2(np.einsum("ak,mkb->mab", dN, xy))[0]
        mm = (wq * det)[:, None, None] * np.outer(N, N)
        for c, scale in ((0, mu), (1, mu), (2, rot)):
            M[:, c::3, c::3] += scale * mm
    return M


def _area(xy: np.ndarray) -> np.ndarray:
    x, y = xy[..., 0], xy[..., 1]
    return 0.5 * (np.einsum("mk,mk->m", x, np.roll(y, -1, axis=1))
                  - np.einsum("mk,mk->m", y, np.roll(x, -1, axis=1)))


def _to_global(K: np.ndarray, R: np.ndarray) -> np.ndarray:
    """:math:`T^T K T` with ``T = diag(R, ..., R)``, blockwise."""
    m, s = K.shape[:2]
    k = s // 3
    K5 = K.reshape(m, k, 3, k, 3)
    KR = sum(K5[:, :, :, :, j, None] * R[:, None, None, None, j, :] for j in range(3))
    Kg = sum(R[:, None, i, :, None, None] * KR[:, :, i, None, :, :] for i in range(3))
    return np.asarray(Kg).reshape(m, s, s)


def shell_matrices_batch(X: np.ndarray, E: float, nu: float, t: float, rho: float,
                         mass: str = "consistent", nsm: float = 0.0, *,
                         terms: ShellTerms = ShellTerms()) -> tuple[np.ndarray, np.ndarray]:
    r"""Stiffness and mass ``(m, 6n, 6n)`` in global axes of ``m`` flat shell elements with
    corners ``X`` ``(m, n, 3)`` and one set of properties: element ``e`` is
    ``shell_matrices(X[e], E, nu, t, rho, mass, nsm, terms=terms)`` (module docstring).

    Raises:
        ValueError: as :func:`substruct.models.shell.shell_matrices`, for the first element
            it refuses (that element's message).
    """
    X = np.asarray(X, dtype=float)
    if X.ndim != 3 or X.shape[1] not in (3, 4) or X.shape[2] != 3:
        raise ValueError(f"shell elements are (m, 3 or 4, 3) corners, got {X.shape}")
    m, n = X.shape[:2]
    if m == 0:
        return np.zeros((0, 6 * n, 6 * n)), np.zeros((0, 6 * n, 6 * n))
    if mass not in SHELL_MASSES or not (E > 0 and t > 0 and rho >= 0 and nsm >= 0
                                        and -1 < nu < 0.5):
        shell_matrices(X[0], E, nu, t, rho, mass, nsm, terms=terms)  # raises its message
    mu, rot = rho * t + nsm, (rho * t**3 / 12 if terms.rotary else 0.0)
    Eb, nub = terms.bending_material if terms.bending_material is not None else (E, nu)
    with np.errstate(divide="ignore", invalid="ignore"):
        R, xy, ok = _axes(X)
        area = _area(xy)
        ok &= area > 0
        consistent = mass == "consistent"
        bend = 1.0
        if terms.shear is None:
            Kb, Mb, okb = _bending(xy, plane_stress(Eb, nub) * t**3 / 12, mu, rot, consistent)
            bend = terms.bend
        elif terms.shear > 0:
            Kb, Mb, okb = mindlin_matrices_batch(
                xy, plane_stress(Eb, nub) * (terms.bend * t**3 / 12), terms.shear, t, mu, rot,
                consistent)
        else:
            okb = np.zeros(m, dtype=bool)
        ok &= okb
        if terms.membrane:
            Km, okm = _membrane(xy, E, nu, t)
            ok &= okm
    if not ok.all():
        e = int(np.flatnonzero(~ok)[0])
        shell_matrices(X[e], E, nu, t, rho, mass, nsm, terms=terms)  # raises its message
        raise AssertionError(f"element {e} failed a batched check but not its own")
    s = 3 * n
    memb = np.concatenate([[6 * k, 6 * k + 1, 6 * k + 5] for k in range(n)])
    bent = np.concatenate([[6 * k + 2, 6 * k + 3, 6 * k + 4] for k in range(n)])
    K = np.zeros((m, 2 * s, 2 * s))
    if terms.bending:
        K[:, bent[:, None], bent[None, :]] = Kb * bend
    if terms.membrane:
        K[:, memb[:, None], memb[None, :]] = Km
    M = np.zeros((m, 2 * s, 2 * s))
    if consistent:
        assert Mb is not None
        M[:, memb[:, None], memb[None, :]] = _membrane_mass(xy, mu, rot)
        M[:, bent[:, None], bent[None, :]] = Mb
    else:
        diag = np.tile([mu / n] * 3 + [rot / n] * 3, n)
        M[:, np.arange(2 * s), np.arange(2 * s)] = area[:, None] * diag
    W = warp_offsets(X, R[:, 2])
    return np.einsum("mji,mjk,mkl->mil", W, _to_global(K, R), W), _to_global(M, R)
