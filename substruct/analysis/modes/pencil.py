r"""Quadratic eigenproblems, dense: balancing, the companion pencil, QZ, Rayleigh refinement.

A root :math:`\lambda` and vector :math:`u` of

.. math::  (\lambda^2 M + \lambda C + K)\, u = 0

come from the first companion form (:func:`companion_pencil`) of the balanced problem
(:func:`fan_lin_van_dooren`), solved by the QZ algorithm (:func:`pencil_roots`).  QZ is only
normwise backward stable, so each kept root is then refined on the Rayleigh functional of its
own vector (:func:`rayleigh_root`), which is accurate componentwise: a low root beside a
stiffness of ``1e12``, a slow decay beside a zero root.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np
import scipy.linalg as sla

__all__ = [
    "Refine",
    "fan_lin_van_dooren",
    "companion_pencil",
    "pencil_roots",
    "quadratic_roots",
    "quadratic_forms",
    "rayleigh_root",
    "rayleigh_refiner",
]


class Refine(Protocol):
    """``refine(j, lambda_j) -> (root, better vector or None)``: the polish a formulation gives
    :func:`substruct.analysis.modes.roots.classify_roots` for the root of column ``j``."""

    def __call__(self, j: int, lam: complex, /) -> tuple[complex, np.ndarray | None]: ...


def fan_lin_van_dooren(m2: float, c2: float, k2: float) -> tuple[float, float]:
    r"""Scaling ``lambda = gamma mu`` and factor ``delta`` of ``lambda^2 M + lambda C + K``.

    .. math::  \gamma = \sqrt{\|K\| / \|M\|}, \qquad
               \delta = 2 / (\|K\| + \gamma \|C\|)

    (Fan, Lin and Van Dooren, SIAM J. Matrix Anal. Appl. 26, 2004).  The companion pencil of
    ``delta (gamma^2 mu^2 M + gamma mu C + K)`` has blocks of comparable norm, so that the
    backward error of the QZ algorithm is small relative to each coefficient (unscaled, masses
    of ``2e3`` beside stiffnesses of ``7e-4`` gave roots wrong by ``5e-7``).

    Args:
        m2, c2, k2: norms of ``M``, ``C``, ``K``.

    Returns:
        ``(gamma, delta)``; ``(1, 1 / max norm)`` when ``M`` or ``K`` is zero.
    """
    if m2 <= 0 or k2 <= 0:
        return 1.0, 1.0 / max(m2, c2, k2, 1e-300)
    gamma = float(np.sqrt(k2 / m2))
    return gamma, 2.0 / (k2 + c2 * gamma)


def companion_pencil(Mq: np.ndarray, Cq: np.ndarray, Kq: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray]:
    r"""First companion form of ``lambda^2 Mq + lambda Cq + Kq``:

    .. math::  \begin{bmatrix} -C_q & -K_q \\ I & 0 \end{bmatrix} v
               = \lambda \begin{bmatrix} M_q & 0 \\ 0 & I \end{bmatrix} v, \qquad
               v = \begin{bmatrix} \lambda u \\ u \end{bmatrix}.
    """
    n = Mq.shape[0]
    I, Z0 = np.eye(n), np.zeros((n, n))
    X = np.block([[-Cq, -Kq], [I, Z0]])
    Y = np.block([[Mq, Z0], [Z0, I]])
    return X, Y


def pencil_roots(X: np.ndarray, Y: np.ndarray, n: int,
                 gamma: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Finite-or-infinite roots ``gamma mu`` of ``X v = mu Y v`` (QZ) and the displacement parts
    of ``v`` (the second block of ``v = [mu u; u]``); an infinite root is ``inf``."""
    ab, V = sla.eig(X, Y, homogeneous_eigvals=True, check_finite=True)
    alpha, beta = ab
    with np.errstate(divide="ignore", invalid="ignore"):
        lam = np.where(np.abs(beta) > 0, gamma * alpha / np.where(beta == 0, 1, beta), np.inf)
    U = V[n:2 * n]
    return lam, U


def quadratic_roots(Mq: np.ndarray, Cq: np.ndarray,
                    Kq: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Roots and displacement vectors of ``lambda^2 Mq + lambda Cq + Kq``, by the balanced
    (:func:`fan_lin_van_dooren`) companion pencil (:func:`companion_pencil`)."""
    def norm(X: np.ndarray) -> float:
        return float(np.linalg.norm(X))

    gamma, delta = fan_lin_van_dooren(norm(Mq), norm(Cq), norm(Kq))
    X, Y = companion_pencil(delta * gamma**2 * Mq, delta * gamma * Cq, delta * Kq)
    return pencil_roots(X, Y, Mq.shape[0], gamma)


def quadratic_forms(U: np.ndarray, *mats: np.ndarray) -> list[np.ndarray]:
    """``u_j^T X u_j`` (transpose, not conjugate) for every column ``u_j`` of ``U`` and every
    real matrix ``X``."""
    out = []
    for X in mats:
        XU = X @ U.real + 1j * (X @ U.imag) if np.iscomplexobj(U) else X @ U
        out.append(np.sum(U * XU, axis=0))
    return out


def rayleigh_root(lam: complex, a: complex, b: complex, c: complex,
                  trust: float = 1e-3) -> tuple[complex, bool]:
    r"""A root refined by Newton steps on the Rayleigh functional of its computed vector.

    .. math::  f(\lambda) = u^T (\lambda^2 M + \lambda C + K) u + e(u)
               = a \lambda^2 + b \lambda + c = 0

    (``u^T``, not ``u^H``: ``M``, ``C``, ``K`` are real symmetric, the problem complex
    symmetric, and ``f`` is stationary at an eigenvector; see :func:`quadratic_forms`).  ``u``
    must satisfy ``A u = 0``, or ``e`` must carry the constraint term (``2 mu^T A u`` with the
    KKT multipliers).  The error is of second order in the error of ``u``, and ``u^T K u`` is
    accurate to rounding *componentwise*, while QZ on a linearization is only normwise backward
    stable: a root far below the largest one loses ``eps (|lambda|_max / |lambda|)^2`` of
    relative accuracy there (five digits for a stiffness of ``1e12`` beside ``1``, three for a
    slow decay next to a zero root).  The correction is kept only when it is small
    (``trust |lambda|``) and lowers ``|f|``.

    The iteration runs on :math:`y = \lambda / s`, :math:`s = |\lambda|`, with
    :math:`g(y) = f(s y) / s^2 = a y^2 + (b/s) y + c/s^2`: the same Newton steps, without the
    overflow of :math:`a \lambda^2` for a root of ``1e30`` (an infinite or zero ``lambda`` is
    returned as it is).

    Returns:
        ``(root, kept)``: the refined root and ``True``, or ``lam`` and ``False``.
    """
    s = abs(complex(lam))
    if not np.isfinite(s) or s == 0.0:
        return complex(lam), False
    b1, c2 = complex(b) / s, complex(c) / s / s

    def g(y: complex) -> complex:
        return (a * y + b1) * y + c2

    y0 = complex(lam) / s
    y = y0
    for _ in range(3):
        d = 2 * a * y + b1
        if d == 0 or not np.isfinite(d):
            break
        y = y - g(y) / d
    if np.isfinite(y) and abs(y - y0) <= trust and abs(g(y)) <= abs(g(y0)):
        return y * s, True
    return complex(lam), False


def rayleigh_refiner(U: np.ndarray, M: np.ndarray, C: np.ndarray, K: np.ndarray,
                     extra: np.ndarray | None = None) -> Refine:
    """``refine(j, lambda)``: :func:`rayleigh_root` on column ``j`` of ``U`` (``extra[j]``
    added to ``u^T K u``); the forms are computed once, on first use."""
    cache: list[np.ndarray] = []

    def refine(j: int, lam: complex) -> tuple[complex, np.ndarray | None]:
        if not cache:
            a, b, c = quadratic_forms(U, M, C, K)
            cache.extend([a, b, c if extra is None else c + extra])
        a, b, c = cache
        return rayleigh_root(lam, a[j], b[j], c[j])[0], None

    return refine
