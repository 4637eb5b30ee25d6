r"""Checks of sparse modes by the equations of the other formulations, at the cost of a few
products and one small solve: the modes come from the null-space form, the Lagrange (KKT) and
generalized-inverse forms verify them.

Given the roots and shapes :math:`(\lambda_j, u_j)` of
:math:`(\lambda^2 M + \lambda C + K) u = A^T \mu`, :math:`A u = 0` from the null-space form
``u = T p`` (undamped: :math:`\lambda = i\omega`, from :math:`T^T K T p = \omega^2 T^T M T p`;
damped: from the first-order pencil of :math:`T^T M T`, :math:`T^T C T`, :math:`T^T K T`):

**KKT residual** (:func:`kkt_residual`): the Lagrange equations in the full coordinates,

.. math::  (\lambda^2 M + \lambda C + K) u + A_k^T \mu = 0, \qquad A_k u = 0,

Norms are chosen so that no figure depends on the units of the coordinates (a shell's rotations
in rad or mrad, its rotary inertia ``rho t^3 / 12`` some 1e-5 of its mass per area): with
:math:`W = \operatorname{diag}(M_d)^{-1/2}` (Jacobi weights, :math:`M_d` below), a force is
measured by :math:`|W f|`, a displacement by :math:`|W^{-1} u|`; a change of units
:math:`u = S u'` (``K, M, C, A`` into ``S K S, S M S, S C S, A S``) leaves every figure as it was.
:math:`\mu` comes from the small ``m x m`` least-squares system in that norm,
:math:`(A_k W^2 A_k^T) \mu = -A_k W^2 (\lambda^2 M + \lambda C + K) u` (solved after a Jacobi
scaling of its rows); the figure is, over the modes,

.. math::  \max_j \max\Big(\frac{|W((\lambda_j^2 M + \lambda_j C + K) u_j + A_k^T \mu_j)|}
                               {|W (K u_j + A_k^T \mu_j)| + |\lambda_j| |W C u_j|
                                + |\lambda_j|^2 |W M u_j|},\;
                          \frac{|\hat A_k u_j|}{|W^{-1} u_j|}\Big)

with :math:`\hat A_k` the rows of :math:`A_k` each divided by :math:`|a_i W|`: the Jacobi
approximation of the generalized-inverse figure below, whose denominator leaves out the
constraint forces as this one does (:math:`K u + A^T \mu` is the elastic force the modes
carry, not the tie forces, which would hide a wrong frequency; for a rigid-body
mode, :math:`\lambda_j = 0`, the denominator is :math:`|W K W|_\infty |W^{-1} u_j|`: ``K u`` is
round-off there).

**Generalized-inverse residual** (:func:`generalized_inverse_residual`): the paper's
acceleration of the constrained system (eqs 5 and 10) with :math:`M_d` the mass made definite
on massless coordinates (eq 6, a fill in the coordinate's own units:
:func:`substruct.linalg.scaling.definite_mass`),

.. math::  \lambda^2 u = a + M_d^{-1} A^T S^+ (0 - A a), \qquad
           a = -M_d^{-1} \big(K + \lambda C - \lambda^2 (M_d - M)\big) u, \qquad
           S = A M_d^{-1} A^T,

figure :math:`\max_j \|P a_j - \lambda_j^2 u_j\|_{M_d} / (|\lambda_j|^2 \|u_j\|_{M_d} +
\|P a_j\|_{M_d})`, :math:`\|x\|_{M_d} = (x^H M_d x)^{1/2}`.  ``P`` is the
:math:`M_d`-orthogonal projector onto ``null(A)`` and :math:`P M_d^{-1} K` is self-adjoint in
that inner product, so (undamped, no massless coordinate) the residual bounds the eigenvalue's
error: some :math:`\omega^2` of the constrained pencil lies within
:math:`\|P a - \lambda^2 u\|_M / \|u\|_M` of :math:`\omega_j^2`, and the figure held to the
tolerance bounds the relative error of :math:`\omega_j^2` by twice the tolerance.  (Equivalently
it is :math:`\min_\mu |M^{-1/2}((K - \omega^2 M) u + A^T \mu)|`: the Lagrange residual in the
exact :math:`M^{-1}` norm whose Jacobi approximation the KKT figure uses.)  The Euclidean norm
is no such bound and is not unit-free: it weighs the rotations, whose accelerations
:math:`M^{-1} K` multiplies the last bits of the shape by :math:`\omega_{max}^2 / \omega_j^2`
(DKQ plate of 1.4k coordinates: 5.7e-7 in the Euclidean norm, 1.0e-9 in the mass norm, the
same as the shape rounded to double precision gives; 10k: 1.5e-5 and 3.1e-8).  ``S^+`` is
applied after a Jacobi scaling of ``S``.  It needs :math:`M_d^{-1} A^T`: sparse when ``M`` is
diagonal (lumped), otherwise one factorization of :math:`M_d` and ``m`` solves, which
:func:`generalized_inverse_affordable` allows only for small models and few rows.

**Round-off.** A residual cannot be smaller than the one the rounding of the shape to double
precision gives it, :math:`\epsilon (|K| |u| + |\lambda| |C| |u| + |\lambda|^2 |M| |u|)`
coordinate by coordinate (the Oettli-Prager residual of a relative perturbation of one ``eps``
in every entry), which the stiff part of the model multiplies by up to
:math:`\omega_{max}^2 / \omega_j^2` and which grows as the mesh is refined (plate bending:
:math:`h^{-4}`).  Each figure is read net of :data:`ROUNDOFF_UNITS` times that floor (measured in
the figure's own norm; for the generalized-inverse figure through the same projected
acceleration, the signs of the floor at random with a fixed seed, as rounding gives them):
what is left is the part of the residual rounding cannot account for.  On the tied shell plate
the null-space modes sit at 0.8-0.9 of one unit (KKT, 1.4k and 10k coordinates) and the net
figures are 3e-13 / 2e-13 (1.4k), 9e-12 / 4e-11 (10k), 1.0e-8 (KKT, 99k, where the gross figure is
1.0e-6: the floor is the resolution of the check on that model).

Both are relative figures, compared with the analysis tolerance by the caller
(:func:`substruct.analysis.checks.require_agreement`).  Neither uses ``T``: an error in the
elimination, the reduced matrices or the eigensolver shows in them.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp

from substruct.linalg.definite import SingularPencil, definite_factorization
from substruct.linalg.factorize import factorizer
from substruct.linalg.scaling import definite_mass

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
#: The round-off a figure is read net of, in units of the residual a relative perturbation of
#: one ``eps`` in every entry of ``K``, ``M`` and ``C`` gives the shape (module docstring; the
#: null-space modes of the shell plate read 0.8-0.9 of one unit, 1.4k and 10k coordinates).
ROUNDOFF_UNITS = 2.0


def _weights(K: sp.csr_array, M: sp.csr_array) -> tuple[sp.csr_array, np.ndarray]:
    r"""``(M_d, w)``: the definite mass (:func:`substruct.linalg.scaling.definite_mass`) and the
    Jacobi weights :math:`w_i = (M_d)_{ii}^{-1/2}` of the coordinates: forces are measured in
    :math:`\|W f\|`, displacements in :math:`\|W^{-1} u\|` (``W = diag(w)``), both unchanged
    by a change of the coordinates' units."""
    Md = definite_mass(K, M)
    return Md, 1.0 / np.sqrt(np.abs(Md.diagonal()))


def _stiffness_scale(K: sp.csr_array, w: np.ndarray) -> float:
    r""":math:`\|W K W\|_\infty`: the scale of :math:`M^{-1} K` (the denominator of a rigid-body
    mode, :math:`\lambda_j = 0`, where ``K u`` is round-off and a relative figure 0/0)."""
    WKW = sp.diags_array(w) @ abs(K) @ sp.diags_array(w)
    return float(sp.csr_array(WKW).sum(axis=1).max(initial=0.0))


def _rigid_scale(K: sp.csr_array, w: np.ndarray, size: np.ndarray, lam: np.ndarray
                 ) -> np.ndarray:
    """``|W K W|_inf * size_j`` for a rigid-body mode (``lam_j == 0``), 0 for the others (the
    scale computed only if there is one)."""
    rigid = np.asarray(lam) == 0.0
    if not rigid.any():
        return np.zeros(np.shape(size)) + 1e-300
    return np.where(rigid, _stiffness_scale(K, w) * size, 0.0) + 1e-300


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
    (roots ``eigenvalues``, complex; shapes the columns of ``U``), forces weighted by
    :math:`W = \operatorname{diag}(M_d)^{-1/2}` and :math:`\mu` by least squares in that norm
    (module docstring).  ``Ak``: independent rows; ``C`` ``None`` for an undamped model."""
    if U.shape[1] == 0:
        return 0.0
    lam, U = _roots_and_shapes(eigenvalues, U, C)
    l2 = lam**2
    if C is None:  # lambda = i omega: lambda^2 real
        l2 = l2.real
    _, w = _weights(K, M)
    KU, MU = K @ U, M @ U
    R = KU + MU * l2
    cnorm = 0.0
    if C is not None:
        CU = C @ U
        R = R + CU * lam
        cnorm = np.abs(lam) * np.linalg.norm(w[:, None] * CU, axis=0)
    size = np.linalg.norm(U / w[:, None], axis=0)
    if Ak.shape[0]:
        AW = sp.csr_array(Ak @ sp.diags_array(w))
        S = _jacobi(AW @ AW.T)
        mu = S.solve(-(AW @ (w[:, None] * R)))
        tied = Ak.T @ mu.reshape(Ak.shape[0], -1)
        R, KU = R + tied, KU + tied
        rows = np.sqrt(np.asarray(AW.multiply(AW).sum(axis=1))).ravel()
        tie = np.linalg.norm((Ak @ U) / rows[:, None], axis=0) / np.maximum(size, 1e-300)
    else:
        tie = np.zeros(U.shape[1])
    denom = np.linalg.norm(w[:, None] * KU, axis=0) + cnorm + \
        np.abs(l2) * np.linalg.norm(w[:, None] * MU, axis=0) + _rigid_scale(K, w, size, lam)
    floor = np.linalg.norm(w[:, None] * _roundoff(K, M, C, U, lam, l2), axis=0)
    return float(max(np.max(_net(np.linalg.norm(w[:, None] * R, axis=0), floor) / denom),
                     np.max(tie)))


def _roundoff(K: sp.csr_array, M: sp.csr_array, C: sp.csr_array | None, U: np.ndarray,
              lam: np.ndarray, l2: np.ndarray) -> np.ndarray:
    r""":math:`\epsilon (|K| |u_j| + |\lambda_j| |C| |u_j| + |\lambda_j|^2 |M| |u_j|)`: the
    largest residual force a relative perturbation of one ``eps`` in every entry of the
    matrices (or of the shape) gives, coordinate by coordinate (Oettli-Prager)."""
    aU = np.abs(U)
    F = abs(K) @ aU + (abs(M) @ aU) * np.abs(l2)
    if C is not None:
        F = F + (abs(C) @ aU) * np.abs(lam)
    return np.finfo(float).eps * F


def _net(residual: np.ndarray, floor: np.ndarray) -> np.ndarray:
    """The residual beyond :data:`ROUNDOFF_UNITS` times its round-off ``floor`` (never < 0)."""
    return np.maximum(residual - ROUNDOFF_UNITS * floor, 0.0)


class _jacobi:
    r"""Solves with an SPD ``S`` (``m x m``, independent constraint rows) after the symmetric
    Jacobi scaling :math:`s_i = S_{ii}^{-1/2}`: :math:`S^{-1} b = s (s S s)^{-1} s b`, so that
    no decision (the pseudo-inverse's cut-off of small singular values) depends on the rows'
    scale.  Dense pseudo-inverse up to 2000 rows, else a sparse factorization."""

    def __init__(self, S: sp.sparray | np.ndarray) -> None:
        Ss = sp.csr_array(S)
        d = np.abs(Ss.diagonal())
        self.s = 1.0 / np.sqrt(np.where(d > 0, d, 1.0))
        scaled = sp.csr_array(sp.diags_array(self.s) @ Ss @ sp.diags_array(self.s))
        if Ss.shape[0] <= 2000:
            pinv = np.linalg.pinv(np.asarray(scaled.toarray()), hermitian=True)
            self._solve = lambda b: pinv @ b
        else:
            fact = factorizer("superlu", spd=True)(sp.csc_array(scaled))
            self._solve = lambda b: _solve_real(fact, b)

    def solve(self, b: np.ndarray) -> np.ndarray:
        """``S^{-1} b`` (columns of ``b``)."""
        sb = b * self.s.reshape((-1,) + (1,) * (np.ndim(b) - 1))
        return np.asarray(self._solve(sb)) * self.s.reshape((-1,) + (1,) * (np.ndim(b) - 1))


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
    columns of ``U``), in the :math:`M_d`-norm (module docstring).  ``Ak``: independent rows;
    ``S^+`` is the pseudo-inverse of eq 5; ``C`` ``None`` for an undamped model.

    Raises:
        SingularPencil: ``M_d`` is singular (a combination of coordinates that have mass
            carries none, e.g. a point mass off its node without rotary inertia): eqs 5 and 10
            do not exist for the model, and the check cannot be made."""
    if U.shape[1] == 0:
        return 0.0
    lam, U = _roots_and_shapes(eigenvalues, U, C)
    l2 = lam**2
    if C is None:
        l2 = l2.real
    Md, w = _weights(K, M)
    rhs = -(K @ U) + ((Md - M) @ U) * l2
    if C is not None:
        rhs = rhs - (C @ U) * lam
    m = Ak.shape[0]
    if _is_diagonal(Md):
        dinv = 1.0 / Md.diagonal()
        a = rhs * dinv[:, None]
        Y = sp.csr_array(sp.diags_array(dinv) @ Ak.T)
        S = _jacobi(Ak @ Y) if m else None  # S = A M_d^-1 A^T, once for both projections
        correction = Y @ S.solve(Ak @ a) if S is not None else 0.0
    else:
        solve = definite_factorization(factorizer("auto", spd=True), sp.csc_array(Md))
        a = _solve_real(solve, rhs)
        if m:
            Yd = np.asarray(solve(Ak.T.toarray()))
            S = _jacobi(Ak @ Yd)
            correction = Yd @ S.solve(Ak @ a)
        else:
            S, correction = None, 0.0
    Pa = a - correction
    R = Pa - U * l2

    def norm(X: np.ndarray) -> np.ndarray:  # the M_d-norm of the columns
        return np.sqrt(np.abs(np.sum(X.conj() * (Md @ X), axis=0)))

    size = norm(U)
    denom = np.abs(l2) * size + norm(Pa) + _rigid_scale(K, w, size, lam)
    # the round-off: the same acceleration of a force of the size of _roundoff, signs at
    # random (a fixed seed), as the rounding of a shape gives them
    signs = np.where(np.random.default_rng(0).random(U.shape) < 0.5, -1.0, 1.0)
    F = _roundoff(K, M, C, U, lam, l2) * signs
    if _is_diagonal(Md):
        aF = F * dinv[:, None]
        PaF = aF - (Y @ S.solve(Ak @ aF) if S is not None else 0.0)
    else:
        aF = np.asarray(solve(F))
        PaF = aF - (Yd @ S.solve(Ak @ aF) if S is not None else 0.0)
    return float(np.max(_net(norm(R), norm(PaF)) / denom))
