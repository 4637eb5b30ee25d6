r"""The three formulations of the receptance of a constrained system, one frequency sweep each.

A harmonic force :math:`F e^{i \omega t}` on ``M q'' + C q' + K q = F`` under ``A q = R F``
(paper eqs 11-15, the constraint read at displacement level) gives :math:`q = \hat H F`, with
the impedance (eq 13)

.. math::  Z(\omega) = K - \omega^2 M + i \omega C = H(\omega)^{-1}.

* :func:`generalized_inverse_sweep`: the paper's :math:`\hat H = G^{-1} D` (eq 15), by a bordered
  sparse solve that never forms ``G``;
* :func:`null_space_sweep`: :math:`q = N p + q_p`, ``A N = 0``, ``A q_p = R F`` (dense);
* :func:`kkt_sweep`: Lagrange multipliers,
  :math:`[Z, A_k^T; A_k, 0] [q; \lambda] = [F; R_k F]`.

They take the constraints as :func:`substruct.analysis.formulations.coupling.receptance` hands them over:
rows equilibrated (:func:`substruct.linalg.scaling.equilibrate`, ``D A q = D R F``), ``R``
consistent.  Each returns ``out[k] = O q(omega_k)`` for the force patterns ``E``, complex
``(n_omega, n_outputs, n_inputs)``.  Sparse matrices are factorized by the registry
(:func:`substruct.linalg.factorize.factorizer`, ``"complex-lu"``; the Lagrange-multiplier
saddle points by SuperLU with partial pivoting).
"""

from __future__ import annotations

from typing import TypeAlias

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from substruct.analysis.errors import AnalysisInputError
from substruct.analysis.formulations.projection import constraint_gain, split_mass
from substruct.linalg.constraints import IndependentRows, particular_solution
from substruct.linalg.dense import dense
from substruct.linalg.factorize import factorizer
from substruct.linalg.nullspace import null_space_basis
from substruct.linalg.scaling import mass_column_scale
from substruct.linalg.solve_type import Matrix

__all__ = [
    "DENSE_SWEEP",
    "generalized_inverse_sweep",
    "impedance",
    "inputs_matrix",
    "kkt_sweep",
    "null_space_sweep",
]

#: Bordered systems of at most this many rows are solved densely, every frequency of a call at
#: once (LAPACK ``gesv`` with partial pivoting, batched): a sparse factorization costs about
#: 1.5 ms a frequency in set-up alone, whatever the size (a 1-coordinate random response of
#: 20,000 frequencies took 32 s).
DENSE_SWEEP = 200


def _solve_refined(big: np.ndarray, rhs: np.ndarray, what: str,
                   omegas: np.ndarray) -> np.ndarray:
    """``big[k] x[k] = rhs[k]`` for every frequency ``k``, densely, with one step of iterative
    refinement; an exactly singular ``big[k]`` is reported at its frequency."""
    try:
        x = np.linalg.solve(big, rhs)
    except np.linalg.LinAlgError:
        for k in range(big.shape[0]):
            try:
                np.linalg.solve(big[k], rhs[k])
            except np.linalg.LinAlgError:
                raise AnalysisInputError(what.format(w=omegas[k])) from None
        raise
    return x + np.linalg.solve(big, rhs - big @ x)


def impedance(K: sp.sparray, M: sp.sparray, C: sp.sparray, omega: float) -> sp.csc_array:
    """``Z = K - w^2 M + i w C = H(w)^{-1}`` (eq 13), sparse complex."""
    return sp.csc_array(K.astype(complex) - omega**2 * M + 1j * omega * C)


def inputs_matrix(inputs: Matrix | None, n: int) -> np.ndarray:
    """The ``n x k`` force patterns ``E`` (the identity for ``None``, up to 5000 coordinates)."""
    if inputs is None:
        if n > 5000:
            raise ValueError(f"receptance of all {n} coordinates requested; name the inputs")
        return np.eye(n)
    return dense(inputs).reshape(n, -1)


def generalized_inverse_sweep(K: sp.csr_array, M: sp.csr_array, C: sp.csr_array,
                              A: sp.csr_array, R: Matrix | None, omegas: np.ndarray,
                              E: np.ndarray, O: sp.sparray | np.ndarray) -> np.ndarray:
    r"""Eq (15) by a bordered sparse solve: ``G x = D f`` with ``G = -Z + A^T W``.

    .. math::  \begin{bmatrix} -Z & \beta A^T \\ W / \beta & -I \end{bmatrix}
               \begin{bmatrix} x \\ y \end{bmatrix}
               = \begin{bmatrix} D_\alpha f \\ 0 \end{bmatrix},
               \quad W = S^+ (A M^{-1} Z + \alpha A), \quad
               D_\alpha = A^T S^+ (\alpha R + A M^{-1}) - I

    so that ``G`` (dense in general) is never formed; ``beta = |Z| / |A|`` balances the blocks,
    and one step of iterative refinement with the same factors follows (SuperLU's threshold
    pivoting left ``|A H - R| = 2e-10 |A||H|`` on a 7-DOF case with 6 constraints; ``3e-13``
    after).

    The paper's ``G`` and ``D`` have ``alpha = omega^2``.  Any ``alpha != 0`` gives the same
    ``\hat H``: ``G_alpha = E G`` and ``D_alpha = E D`` with the invertible
    ``E = P^T + (alpha / omega^2) (I - P^T)``, ``P^T = I - A^T S^+ A M^{-1}``.  The constraint
    part of the solution obeys ``A x - R f = A M^{-1} r / alpha`` for a solve residual ``r``, so
    ``alpha = omega^2`` multiplies rounding errors by ``(omega_ref / omega)^2`` at low
    frequency (on a 3-DOF system with two constraints ``|A H| / |A||H|`` was ``1e-10`` at
    ``omega_ref / 16`` and ``6e-7`` at ``omega_ref / 1000``; ``4e-14`` with the ``alpha``
    below) and makes ``omega = 0`` singular.  We take
    ``alpha = max(omega^2, |A M^{-1} Z| / |A|)``: the paper's value wherever it is not too
    small.
    """
    ms = split_mass(M)
    A = sp.csr_array(A)
    m, n = A.shape
    Y, Sp = constraint_gain(ms, A)
    RE = np.zeros((m, E.shape[1])) if R is None else dense(sp.csr_array(R)) @ E
    YtE = Y.T @ E
    Ad = dense(A)
    normA = max(float(np.linalg.norm(Ad)), 1e-300)
    out = np.empty((len(omegas), O.shape[0], E.shape[1]), dtype=complex)
    for w in omegas:
        if w <= 0:
            raise AnalysisInputError(f"the generalized-inverse receptance (eq 15) is singular at "
                             f"omega = {w}; use method 'kkt' or 'null-space' for statics")
    if n + m <= DENSE_SWEEP:
        Kd, Md, Cd = dense(K), dense(M), dense(C)
        big = np.zeros((len(omegas), n + m, n + m), dtype=complex)
        rhs = np.zeros((len(omegas), n + m, E.shape[1]), dtype=complex)
        for k, w in enumerate(omegas):
            Zd = Kd - w**2 * Md + 1j * w * Cd
            YtZ = Y.T @ Zd
            alpha = max(w**2, float(np.linalg.norm(YtZ)) / normA)
            beta = max(float(np.linalg.norm(Zd)), 1e-300) / normA
            big[k, :n, :n] = -Zd
            big[k, :n, n:] = beta * Ad.T
            big[k, n:, :n] = Sp @ (YtZ + alpha * Ad) / beta
            big[k, n:, n:] = -np.eye(m)
            rhs[k, :n] = Ad.T @ (Sp @ (alpha * RE + YtE)) - E
        xy = _solve_refined(big, rhs, "the generalized-inverse system (eq 15) is singular at "
                            "omega = {w} (a resonance of an undamped system, or a motion with "
                            "neither mass nor stiffness)", omegas)
        for k in range(len(omegas)):
            out[k] = O @ xy[k, :n]
        return out
    for k, w in enumerate(omegas):
        Z = impedance(K, M, C, w)
        YtZ = (Z.T @ Y).T  # A M^-1 Z
        alpha = max(w**2, float(np.linalg.norm(YtZ)) / normA)
        beta = max(float(spla.norm(Z)), 1e-300) / normA
        W = Sp @ (YtZ + alpha * Ad)  # S^+ (A M^-1 Z + alpha A)
        DE = A.T @ (Sp @ (alpha * RE + YtE)) - E
        big = sp.block_array([[-Z, beta * A.T.astype(complex)],
                              [sp.csr_array(W / beta), -sp.eye_array(m, dtype=complex)]],
                             format="csc")
        rhs = np.vstack([DE, np.zeros((m, E.shape[1]))]).astype(complex)
        try:
            solve = factorizer("complex-lu")(big)
        except RuntimeError as exc:
            raise AnalysisInputError(f"the generalized-inverse system (eq 15) is singular at "
                                     f"omega = {w} (a resonance of an undamped system, or a "
                                     f"motion with neither mass nor stiffness)") from exc
        xy = solve(rhs)
        xy = xy + solve(rhs - big @ xy)  # one step of iterative refinement
        out[k] = O @ xy[:n]
    return out


def null_space_sweep(K: sp.csr_array, M: sp.csr_array, C: sp.csr_array, A: sp.csr_array,
                     R: Matrix | None, omegas: np.ndarray, E: np.ndarray,
                     O: sp.sparray | np.ndarray, rows: IndependentRows) -> np.ndarray:
    r"""Null-space elimination: ``q = N p + q_p``, ``A N = 0``, ``A q_p = R F``, dense.

    .. math::  q = N (N^T Z N)^{-1} N^T (F - Z q_p) + q_p

    ``N`` from :func:`substruct.linalg.nullspace.null_space_basis` (rank decided on mass-scaled
    columns, as ``rows``), ``q_p`` the minimum-norm particular solution.
    """
    N = null_space_basis(A, col_scale=mass_column_scale(M)) if A.shape[0] else \
        np.eye(A.shape[1])
    Kd, Md, Cd = dense(K), dense(M), dense(C)
    m = A.shape[0]
    RE = np.zeros((m, E.shape[1])) if R is None else dense(sp.csr_array(R)) @ E
    Qp = particular_solution(A, RE, rows) if m else np.zeros_like(E)
    Od = dense(O)
    out = np.empty((len(omegas), Od.shape[0], E.shape[1]), dtype=complex)
    for k, w in enumerate(omegas):
        Z = Kd - w**2 * Md + 1j * w * Cd
        Zr = N.T @ Z @ N
        p = np.linalg.solve(Zr, N.T @ (E - Z @ Qp))
        out[k] = Od @ (N @ p + Qp)
    return out


def kkt_sweep(K: sp.csr_array, M: sp.csr_array, C: sp.csr_array, A: sp.csr_array,
              R: Matrix | None, omegas: np.ndarray, E: np.ndarray, O: sp.sparray | np.ndarray,
              rows: IndependentRows) -> np.ndarray:
    r"""Lagrange multipliers on the independent rows ``A_k``:

    .. math::  \begin{bmatrix} Z & \beta A_k^T \\ \beta A_k & 0 \end{bmatrix}
               \begin{bmatrix} q \\ \lambda / \beta \end{bmatrix}
               = \begin{bmatrix} F \\ \beta R_k F \end{bmatrix},

    rows and multipliers scaled by ``beta = |Z| / |A_k|``: blocks of one size, so that the
    pivoting is not misled when a stiffness of ``1e12`` sits next to a constraint of ``1``.
    """
    Ak = sp.csr_array(A)[rows.keep]
    r = Ak.shape[0]
    n = A.shape[1]
    RE = np.zeros((r, E.shape[1])) if R is None else (dense(sp.csr_array(R)) @ E)[rows.keep]
    out = np.empty((len(omegas), O.shape[0], E.shape[1]), dtype=complex)
    normA = max(float(spla.norm(Ak)), 1e-300) if r else 1.0
    if n + r <= DENSE_SWEEP:
        Kd, Md, Cd, Akd = dense(K), dense(M), dense(C), dense(Ak)
        big = np.zeros((len(omegas), n + r, n + r), dtype=complex)
        rhs = np.zeros((len(omegas), n + r, E.shape[1]), dtype=complex)
        for k, w in enumerate(omegas):
            Zd = Kd - w**2 * Md + 1j * w * Cd
            beta = max(float(np.linalg.norm(Zd)), 1e-300) / normA
            big[k, :n, :n] = Zd
            big[k, :n, n:] = beta * Akd.T
            big[k, n:, :n] = beta * Akd
            rhs[k, :n] = E
            rhs[k, n:] = beta * RE
        x = _solve_refined(big, rhs, "KKT system singular at omega = {w} (a constrained "
                           "resonance of an undamped system)", omegas)
        for k in range(len(omegas)):
            out[k] = O @ x[k, :n]
        return out
    for k, w in enumerate(omegas):
        Z = impedance(K, M, C, w)
        beta = max(float(spla.norm(Z)), 1e-300) / normA
        big = sp.block_array([[Z, beta * Ak.T], [beta * Ak, None]], format="csc")
        rhs = np.vstack([E, beta * RE]).astype(complex)
        try:
            # SuperLU (partial pivoting), as for the real saddle points: PARDISO perturbs
            # pivots of the zero block at some frequencies, and a perturbed factorization is
            # refused (substruct.linalg.pardiso), so it would fall back there anyway
            solve = factorizer("superlu")(big.astype(complex))
            x = solve(rhs)
            x = (x + solve(rhs - big @ x))[:n]  # one step of iterative refinement
        except RuntimeError as exc:
            raise AnalysisInputError(f"KKT system singular at omega = {w} (a constrained resonance "
                             "of an undamped system)") from exc
        out[k] = O @ x
    return out
