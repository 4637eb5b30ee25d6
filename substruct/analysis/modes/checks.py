r"""Checks of sparse modes by the equations of the other formulations, at the cost of a few
products and one small solve: the modes come from the null-space form, the Lagrange (KKT) and
generalized-inverse forms verify them.

Given the roots and shapes :math:`(\lambda_j, u_j)` of
:math:`(\lambda^2 M + \lambda C + K) u = A^T \mu`, :math:`A u = 0` from the null-space form
``u = T p`` (undamped: :math:`\lambda = i\omega`, from :math:`T^T K T p = \omega^2 T^T M T p`;
damped: from the first-order pencil of :math:`T^T M T`, :math:`T^T C T`, :math:`T^T K T`):

**KKT residual** (:func:`kkt_residual`): the Lagrange equations in the full coordinates,

.. math::  (\lambda^2 M + \lambda C + K) u + A_k^T \mu = 0, \qquad A_k u = 0,

with :math:`\mu` from the small ``m x m`` least-squares system
:math:`(A_k A_k^T) \mu = -A_k (\lambda^2 M + \lambda C + K) u`; the figure is, over the modes,

.. math::  \max_j \max\Big(\frac{|(\lambda_j^2 M + \lambda_j C + K) u_j + A_k^T \mu_j|}
                               {|K u_j| + |\lambda_j| |C u_j| + |\lambda_j|^2 |M u_j|},\;
                          \frac{|A_k u_j|}{|u_j|}\Big)

(for a rigid-body mode, :math:`\lambda_j = 0`, the denominator is :math:`|K|_\infty |u_j|`:
``K u`` is round-off there).

**Generalized-inverse residual** (:func:`generalized_inverse_residual`): the paper's
acceleration of the constrained system (eqs 5 and 10) with :math:`M_d` the mass made definite
on massless coordinates (eq 6),

.. math::  \lambda^2 u = a + M_d^{-1} A^T S^+ (0 - A a), \qquad
           a = -M_d^{-1} \big(K + \lambda C - \lambda^2 (M_d - M)\big) u, \qquad
           S = A M_d^{-1} A^T,

figure :math:`\max_j |P a_j - \lambda_j^2 u_j| / (|\lambda_j|^2 |u_j| + |P a_j|)` (``|a|`` itself
holds the accelerations of the constraint forces and the stiff part of ``M_d^{-1} K``).  It needs
:math:`M_d^{-1} A^T`: sparse when ``M`` is diagonal (lumped), otherwise one factorization of
:math:`M_d` and ``m`` solves, which :func:`generalized_inverse_affordable` allows only for small
models and few rows.

Both are relative figures, compared with the analysis tolerance by the caller
(:func:`substruct.analysis.checks.require_agreement`).  Neither uses ``T``: an error in the
elimination, the reduced matrices or the eigensolver shows in them.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp

from substruct.linalg.factorize import factorizer
from substruct.linalg.scaling import massless_coordinates

__all__ = [
    "GI_CHECK_ROWS",
    "GI_CHECK_SIZE",
    "generalized_inverse_affordable",
    "generalized_inverse_residual",
    "kkt_residual",
]

#: Largest number of independent constraint rows for the generalized-inverse check with a
#: consistent (non-diagonal) mass: ``m`` solves with the factor of ``M_d``.
GI_CHECK_ROWS = 200
#: Largest number of coordinates for that check (one more factorization, of ``M_d``).
GI_CHECK_SIZE = 20_000


def _rigid_scale(K: sp.csr_array, U: np.ndarray, lam: np.ndarray) -> np.ndarray:
    r"""The denominator of a rigid-body mode (:math:`\lambda_j = 0`, where ``K u`` is round-off
    and the relative figure would be 0/0): :math:`|K|_\infty |u_j|`, a backward error; 0 for
    the other modes."""
    norm = float(abs(K).sum(axis=1).max(initial=0.0))
    return np.where(np.asarray(lam) == 0.0, norm * np.linalg.norm(U, axis=0), 0.0) + 1e-300


def _roots_and_shapes(eigenvalues: np.ndarray, U: np.ndarray,
                      C: sp.csr_array | None) -> tuple[np.ndarray, np.ndarray]:
    """``(lambda, U)``: complex roots and shapes; real shapes of an undamped model stay real
    (``lambda = i omega`` enters only through ``lambda^2 = -omega^2``)."""
    lam = np.asarray(eigenvalues, dtype=complex)
    if C is None and np.iscomplexobj(U) and not np.any(U.imag):
        U = U.real
    return lam, np.asarray(U)


def _solve_real(solve: Any, B: np.ndarray) -> np.ndarray:
    """A real factorization applied to a possibly complex right-hand side."""
    if np.iscomplexobj(B):
        return np.asarray(solve(B.real)) + 1j * np.asarray(solve(B.imag))
    return np.asarray(solve(B))


def kkt_residual(K: sp.csr_array, M: sp.csr_array, Ak: sp.csr_array, eigenvalues: np.ndarray,
                 U: np.ndarray, C: sp.csr_array | None = None) -> float:
    r"""The largest relative residual of the Lagrange equations
    :math:`(\lambda^2 M + \lambda C + K) u + A_k^T \mu = 0`, :math:`A_k u = 0` over the modes
    (roots ``eigenvalues``, complex; shapes the columns of ``U``), :math:`\mu` by least squares
    (module docstring).  ``Ak``: independent rows; ``C`` ``None`` for an undamped model."""
    if U.shape[1] == 0:
        return 0.0
    lam, U = _roots_and_shapes(eigenvalues, U, C)
    l2 = lam**2
    if C is None:  # lambda = i omega: lambda^2 real
        l2 = l2.real
    KU, MU = K @ U, M @ U
    R = KU + MU * l2
    cnorm = 0.0
    if C is not None:
        CU = C @ U
        R = R + CU * lam
        cnorm = np.abs(lam) * np.linalg.norm(CU, axis=0)
    if Ak.shape[0]:
        S = sp.csc_array(Ak @ Ak.T)
        mu = _solve_real(factorizer("superlu", spd=True)(S), -(Ak @ R))
        R = R + Ak.T @ mu.reshape(Ak.shape[0], -1)
        tie = np.linalg.norm(Ak @ U, axis=0) / np.maximum(np.linalg.norm(U, axis=0), 1e-300)
    else:
        tie = np.zeros(U.shape[1])
    denom = np.linalg.norm(KU, axis=0) + cnorm + np.abs(l2) * np.linalg.norm(MU, axis=0) + \
        _rigid_scale(K, U, lam)
    return float(max(np.max(np.linalg.norm(R, axis=0) / denom), np.max(tie)))


def _definite_mass(M: sp.csr_array) -> sp.csr_array:
    """``M_d``: ``M`` with the mean diagonal mass put on its massless coordinates (eq 6)."""
    massless = massless_coordinates(M)
    fill = float(np.mean(abs(M.diagonal()))) or 1.0
    return sp.csr_array(M + sp.diags_array(massless.astype(float) * fill))


def _is_diagonal(M: sp.csr_array) -> bool:
    coo = M.tocoo()
    return bool(np.all(coo.row[coo.data != 0] == coo.col[coo.data != 0]))


def generalized_inverse_affordable(M: sp.csr_array, rows: int) -> bool:
    """Whether :func:`generalized_inverse_residual` costs little next to the eigensolve: a
    diagonal mass, or at most :data:`GI_CHECK_SIZE` coordinates and :data:`GI_CHECK_ROWS`
    independent rows."""
    return _is_diagonal(M) or (M.shape[0] <= GI_CHECK_SIZE and rows <= GI_CHECK_ROWS)


def generalized_inverse_residual(K: sp.csr_array, M: sp.csr_array, Ak: sp.csr_array,
                                 eigenvalues: np.ndarray, U: np.ndarray,
                                 C: sp.csr_array | None = None) -> float:
    r"""The largest relative residual of the generalized-inverse acceleration (eqs 5, 10)
    :math:`\lambda^2 u = P a` over the modes (roots ``eigenvalues``, complex; shapes the
    columns of ``U``; module docstring).  ``Ak``: independent rows; ``S^+`` is the
    pseudo-inverse of eq 5; ``C`` ``None`` for an undamped model."""
    if U.shape[1] == 0:
        return 0.0
    lam, U = _roots_and_shapes(eigenvalues, U, C)
    l2 = lam**2
    if C is None:
        l2 = l2.real
    Md = _definite_mass(M)
    rhs = -(K @ U) + ((Md - M) @ U) * l2
    if C is not None:
        rhs = rhs - (C @ U) * lam
    m = Ak.shape[0]
    if _is_diagonal(Md):
        dinv = 1.0 / Md.diagonal()
        a = rhs * dinv[:, None]
        Y = sp.csr_array(sp.diags_array(dinv) @ Ak.T)
        correction = Y @ _pinv_solve(Ak @ Y, Ak @ a) if m else 0.0
    else:
        solve = factorizer("auto", spd=True)(sp.csc_array(Md))
        a = _solve_real(solve, rhs)
        if m:
            Yd = np.asarray(solve(Ak.T.toarray()))
            correction = Yd @ (np.linalg.pinv(Ak @ Yd) @ (Ak @ a))
        else:
            correction = 0.0
    Pa = a - correction
    R = Pa - U * l2
    denom = np.abs(l2) * np.linalg.norm(U, axis=0) + np.linalg.norm(Pa, axis=0) + \
        _rigid_scale(K, U, lam) / max(float(np.mean(abs(M.diagonal()))), 1e-300)
    return float(np.max(np.linalg.norm(R, axis=0) / denom))


def _pinv_solve(S: sp.sparray, b: np.ndarray) -> np.ndarray:
    """:math:`S^+ b` for the sparse ``S = A M_d^{-1} A^T`` of independent rows (SPD): a
    sparse factorization, or the dense pseudo-inverse for up to 2000 rows."""
    if S.shape[0] <= 2000:
        return np.linalg.pinv(np.asarray(sp.csr_array(S).toarray())) @ b
    return _solve_real(factorizer("superlu", spd=True)(sp.csc_array(S)), b)
