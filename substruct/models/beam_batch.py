r"""The beam elements of :mod:`substruct.models.beam` computed all at once: every array carries
the element as its first axis, with the same shape functions, the same 5-point Gauss rule and
the same rotation :math:`T^T K T` (``T = diag(R, R, R, R)``), so each element's matrices are
those of :func:`~substruct.models.beam.beam_matrices` to round-off.  End releases are not
handled here: the caller computes the (few) released elements one at a time.

Per element ``e`` and bending plane, with :math:`\phi_e = 12 E I / (\kappa G A L_e^2)` (0 for
Euler-Bernoulli) and the Gauss points :math:`\xi_p`, weights :math:`w_p L_e / 2`:

.. math::  K_{b,e} = EI \sum_p w_p N_\theta'^T N_\theta' + \kappa G A \sum_p w_p
           \gamma^T \gamma, \quad \gamma = N_v' - N_\theta, \qquad
           M_{b,e} = \rho A \sum_p w_p N_v^T N_v + \rho I \sum_p w_p N_\theta^T N_\theta

(the module docstring of :mod:`substruct.models.beam` has ``N_v`` and ``N_\theta``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["BeamBatch", "beam_matrices_batch"]

_GAUSS_X, _GAUSS_W = np.polynomial.legendre.leggauss(5)


@dataclass(frozen=True)
class BeamBatch:
    """Elements' data, one entry per element: end positions ``xa``, ``xb`` and orientation
    vectors ``v`` (``(n, 3)``), material ``E, G, rho`` and section ``A, Iy, Iz, J, Ip, ky, kz``
    (``(n,)``), ``timoshenko`` (``(n,)`` bool)."""

    xa: np.ndarray
    xb: np.ndarray
    v: np.ndarray
    E: np.ndarray
    G: np.ndarray
    rho: np.ndarray
    A: np.ndarray
    Iy: np.ndarray
    Iz: np.ndarray
    J: np.ndarray
    Ip: np.ndarray
    ky: np.ndarray
    kz: np.ndarray
    timoshenko: np.ndarray


def _rotations(b: BeamBatch) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(R, L, ok)``: the rows ``e_x, e_y, e_z`` of each element's axes, its length, and
    whether :func:`~substruct.models.beam.rotation` would accept it."""
    d = b.xb - b.xa
    L = np.linalg.norm(d, axis=1)
    nv = np.linalg.norm(b.v, axis=1)
    ok = (L > 0) & np.isfinite(L) & (nv > 0) & np.isfinite(nv)
    Ls, nvs = np.where(ok, L, 1.0), np.where(ok, nv, 1.0)
    ex = d / Ls[:, None]
    ez = np.cross(ex, b.v / nvs[:, None])
    nz = np.linalg.norm(ez, axis=1)
    ok &= nz >= 1e-8
    ez = ez / np.where(ok, nz, 1.0)[:, None]
    return np.stack([ex, np.cross(ez, ex), ez], axis=1), L, ok


def _bending(L: np.ndarray, EI: np.ndarray, kGA: np.ndarray, rhoA: np.ndarray,
             rhoI: np.ndarray, timo: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Bending stiffness and consistent mass ``(n, 4, 4)`` (module docstring)."""
    phi = np.where(timo, 12.0 * EI / np.where(timo, kGA, 1.0) / (L * L), 0.0)[:, None]
    s = (1.0 / (1.0 + phi))
    Lc = L[:, None]
    xi = ((_GAUSS_X + 1.0) / 2.0)[None, :]
    w = _GAUSS_W[None, :] * Lc / 2.0
    one = np.ones_like(phi * xi)
    Nv = s[:, None] * np.stack([2 * xi**3 - 3 * xi**2 - phi * xi + 1 + phi,
                                Lc * (xi**3 - (2 + phi / 2) * xi**2 + (1 + phi / 2) * xi),
                                -2 * xi**3 + 3 * xi**2 + phi * xi,
                                Lc * (xi**3 - (1 - phi / 2) * xi**2 - phi / 2 * xi)], axis=1)
    dNv = (s / Lc)[:, None] * np.stack([6 * xi**2 - 6 * xi - phi * one,
                                        Lc * (3 * xi**2 - (4 + phi) * xi + (1 + phi / 2) * one),
                                        -6 * xi**2 + 6 * xi + phi * one,
                                        Lc * (3 * xi**2 - (2 - phi) * xi - phi / 2 * one)],
                                       axis=1)
    Nt = s[:, None] * np.stack([6 / Lc * (xi**2 - xi), 3 * xi**2 - (4 + phi) * xi + 1 + phi,
                                -6 / Lc * (xi**2 - xi), 3 * xi**2 - (2 - phi) * xi], axis=1)
    dNt = (s / Lc)[:, None] * np.stack([6 / Lc * (2 * xi - 1) * one, 6 * xi - (4 + phi) * one,
                                        -6 / Lc * (2 * xi - 1) * one, 6 * xi - (2 - phi) * one],
                                       axis=1)
    K = EI[:, None, None] * np.einsum("nap,np,nbp->nab", dNt, w, dNt)
    gamma = dNv - Nt
    K = K + np.where(timo, kGA, 0.0)[:, None, None] * np.einsum("nap,np,nbp->nab", gamma, w,
                                                                 gamma)
    M = rhoA[:, None, None] * np.einsum("nap,np,nbp->nab", Nv, w, Nv) + \
        rhoI[:, None, None] * np.einsum("nap,np,nbp->nab", Nt, w, Nt)
    return (K + K.transpose(0, 2, 1)) / 2, (M + M.transpose(0, 2, 1)) / 2


def beam_matrices_batch(b: BeamBatch, mass: str = "consistent"
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""Global stiffness and mass ``(n, 12, 12)`` of the elements of ``b`` (module docstring),
    and ``ok`` ``(n,)``: ``False`` for an element :func:`~substruct.models.beam.rotation`
    refuses (no length, an orientation along the axis), whose matrices are then meaningless
    (the caller computes it alone to get the message)."""
    R, L, ok = _rotations(b)
    L = np.where(ok, L, 1.0)
    n = L.size
    timo = np.asarray(b.timoshenko, dtype=bool)
    K = np.zeros((n, 12, 12))
    M = np.zeros((n, 12, 12))
    lumped = mass == "lumped"
    bar = np.array([[1.0, -1.0], [-1.0, 1.0]])
    pair = np.eye(2) / 2 if lumped else np.array([[2.0, 1.0], [1.0, 2.0]]) / 6.0
    for dof, stiff, inertia in ((0, b.E * b.A, b.rho * b.A), (3, b.G * b.J, b.rho * b.Ip)):
        idx = np.ix_([dof, dof + 6], [dof, dof + 6])
        K[(slice(None),) + idx] = (stiff / L)[:, None, None] * bar
        M[(slice(None),) + idx] = (inertia * L)[:, None, None] * pair
    for v, t, I, kappa, sign in ((1, 5, b.Iz, b.ky, 1.0), (2, 4, b.Iy, b.kz, -1.0)):
        Kb, Mb = _bending(L, b.E * I, kappa * b.G * b.A, b.rho * b.A,
                          np.where(timo, b.rho * I, 0.0), timo)
        D = np.array([1.0, sign, 1.0, sign])
        idx = np.ix_([v, t, v + 6, t + 6], [v, t, v + 6, t + 6])
        K[(slice(None),) + idx] = Kb * D[:, None] * D[None, :]
        if not lumped:
            M[(slice(None),) + idx] = Mb * D[:, None] * D[None, :]
        else:
            rot = b.rho * b.A * L**3 / 24.0 + np.where(timo, b.rho * I * L / 2.0, 0.0)
            half = b.rho * b.A * L / 2.0
            diag = np.zeros((n, 4, 4))
            diag[:, [0, 2], [0, 2]] = half[:, None]
            diag[:, [1, 3], [1, 3]] = rot[:, None]
            M[(slice(None),) + idx] = diag
    Kr, Mr = K.reshape(n, 4, 3, 4, 3), M.reshape(n, 4, 3, 4, 3)
    Kg = np.einsum("nji,najbk,nkl->naibl", R, Kr, R, optimize=True).reshape(n, 12, 12)
    Mg = np.einsum("nji,najbk,nkl->naibl", R, Mr, R, optimize=True).reshape(n, 12, 12)
    return Kg, Mg, ok
