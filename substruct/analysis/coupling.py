r"""The generalized-inverse (Udwadia-Kalaba) coupler and the receptance of constrained systems.

Paper equations in the paper's order, each beside its code:

* eq (5), constrained acceleration, in the form that scales to sparse matrices,

  .. math::  M^{-1/2} (A M^{-1/2})^+ = M^{-1} A^T (A M^{-1} A^T)^+

  (``B^+ = B^T (B B^T)^+`` with ``B = A M^{-1/2}``): only solves with ``M`` and an ``m x m``
  pseudo-inverse are needed, never ``M^{1/2}``;
* eqs (6)-(10), semidefinite mass: ``M = M_d - M_o`` with ``M_o`` the identity on the massless
  coordinates (times the mean mass, see :class:`MassSplit`),
  ``M^* = [I - M_d^{-1} A^T (A M_d^{-1} A^T)^+ A] M_d^{-1}``;
* eqs (11)-(15), the receptance ``\hat H = G^{-1} D`` of a system under ``A q = R F``.

Two independent formulations check the receptance: null-space elimination ``q = N p + q_p`` and
Lagrange multipliers (the KKT system).  All three must agree (:func:`receptance_agreement`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, Sequence

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from substruct.linalg.constraints import (
    ConstraintError,
    check_consistent,
    dense,
    independent_rows,
    null_space_basis,
    particular_solution,
)

__all__ = [
    "METHODS",
    "ConstraintError",
    "MassSplit",
    "split_mass",
    "constraint_gain",
    "projected_inverse",
    "constrained_acceleration",
    "receptance_unconstrained",
    "paper_G_D",
    "receptance",
    "receptance_agreement",
]

Method = Literal["generalized-inverse", "null-space", "kkt"]
#: The three independent formulations of the coupled problem.
METHODS: tuple[str, ...] = ("generalized-inverse", "null-space", "kkt")


def _csr(mat: sp.sparray | np.ndarray | None, shape: tuple[int, int]) -> sp.csr_array:
    if mat is None:
        return sp.csr_array(shape, dtype=float)
    return sp.csr_array(mat)


@dataclass(frozen=True)
class MassSplit:
    r"""The split ``M = M_d - M_o`` of eq (7) and a factorization of ``M_d``.

    ``M_o`` is ``mu`` times the identity on the massless coordinates (zero rows of ``M``, eq 6)
    and zero elsewhere, so ``M_d = M + M_o`` is positive definite when ``M`` is positive definite
    on the coordinates that have mass.  The paper takes ``mu = 1``; any ``mu > 0`` gives the same
    constrained motion (eq 10 holds for every such split), and ``mu`` of the size of the masses
    keeps ``M_d`` as well conditioned as ``M_a``: with ``mu = 1`` and masses of ``1e3`` the
    condition number of ``M_d`` grows a thousandfold and so does the error of ``M^*``.
    """

    Md: sp.csc_array
    massless: np.ndarray
    _lu: spla.SuperLU
    mu: float = 1.0

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """``M_d^{-1} rhs``."""
        rhs = np.asarray(rhs)
        if np.iscomplexobj(rhs):
            return self._lu.solve(rhs.real) + 1j * self._lu.solve(rhs.imag)
        return self._lu.solve(rhs)

    @property
    def Mo(self) -> sp.csr_array:
        """``M_o`` of eq (7)."""
        return sp.diags_array(self.mu * self.massless.astype(float)).tocsr()


def split_mass(M: sp.sparray | np.ndarray) -> MassSplit:
    r"""Split a positive semidefinite mass matrix as in eq (7) and factorize ``M_d``.

    .. math::  M = M_d - M_o, \quad M_d = \begin{bmatrix} M_a & 0 \\ 0 & \mu I\end{bmatrix},
               \quad M_o = \begin{bmatrix} 0 & 0 \\ 0 & \mu I\end{bmatrix}, \quad
               \mu = \operatorname{mean} \operatorname{diag} M_a
    """
    M = sp.csr_array(M, dtype=float)
    massless = np.asarray(abs(M).sum(axis=1)).ravel() == 0.0
    diag = M.diagonal()[~massless]
    mu = float(np.mean(np.abs(diag))) if diag.size and np.any(diag) else 1.0
    Md = (M + sp.diags_array(mu * massless.astype(float))).tocsc()
    try:
        lu = spla.splu(Md, permc_spec="MMD_AT_PLUS_A")
    except RuntimeError as exc:  # exactly singular
        raise ValueError("mass matrix is singular on coordinates that have mass") from exc
    return MassSplit(Md=Md, massless=massless, _lu=lu, mu=mu)


def _pinv_sym(S: np.ndarray, rtol: float = 1e-11) -> np.ndarray:
    """Moore-Penrose inverse of a small symmetric positive semidefinite matrix."""
    if S.size == 0:
        return S.copy()
    return sla.pinvh((S + S.T) / 2, rtol=rtol)


def constraint_gain(M: sp.sparray | np.ndarray | MassSplit,
                    A: sp.sparray | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r"""The gain of the constraint correction in eq (5), in scalable form.

    .. math::  M^{-1/2} (A M^{-1/2})^+ = M^{-1} A^T S^+, \qquad S = A M^{-1} A^T

    With a semidefinite mass, ``M_d`` of eq (7) takes the place of ``M`` (eq 9).

    Returns:
        ``(Y, S_pinv)`` with ``Y = M_d^{-1} A^T`` (``n x m``) and ``S_pinv = S^+`` (``m x m``);
        the gain is ``Y @ S_pinv``.
    """
    ms = M if isinstance(M, MassSplit) else split_mass(M)
    At = dense(sp.csr_array(A).T) if sp.issparse(A) else np.asarray(A).T
    Y = ms.solve(At) if At.size else np.zeros_like(At)
    Y = Y.reshape(At.shape)
    S = (At.T @ Y) if At.size else np.zeros((At.shape[1], At.shape[1]))
    return Y, _pinv_sym(S)


def projected_inverse(M: sp.sparray | np.ndarray | MassSplit,
                      A: sp.sparray | np.ndarray) -> np.ndarray:
    r"""``M^*`` of eq (10), dense (for reduced models).

    .. math::  M^* = \left[I - M_d^{-1/2} (A M_d^{-1/2})^+ A\right] M_d^{-1}
                   = M_d^{-1} - Y S^+ Y^T

    ``I - Y S^+ A`` is the ``M_d``-orthogonal projector onto ``null(A)``.
    """
    ms = M if isinstance(M, MassSplit) else split_mass(M)
    n = ms.Md.shape[0]
    Y, Sp = constraint_gain(ms, A)
    Minv = ms.solve(np.eye(n))
    return Minv - Y @ Sp @ Y.T


def constrained_acceleration(M: sp.sparray | np.ndarray, A: sp.sparray | np.ndarray,
                             b: np.ndarray, force: np.ndarray) -> np.ndarray:
    r"""Acceleration of a constrained system, eq (5), or eq (10) with massless coordinates.

    ``force`` is ``P - C \dot q - K q``.  With ``a = M^{-1} force``:

    .. math::  \ddot q = a + M^{-1} A^T (A M^{-1} A^T)^+ (b - A a)          \quad (5)

    With a semidefinite ``M`` (eqs 7-10):

    .. math::  (I - M^* M_o)\, \ddot q = M_d^{-1} A^T (A M_d^{-1} A^T)^+ b + M^* force  \quad (10)

    ``M^* M_o`` has nonzero columns only at the ``s`` massless coordinates, so (10) is solved by
    one ``s x s`` dense system; no ``n x n`` matrix is formed.

    The correction of eq (5) is applied once more to the result,
    ``\ddot q \leftarrow \ddot q + M_d^{-1} A^T S^+ (b - A \ddot q)``: in exact arithmetic it
    adds nothing; in floating point it removes the part of the rounding error that violates the
    constraint, which ``cond(S)`` amplifies (``|A q'' - b| = 3e-10 |A||q''|`` for 6 constraints
    on 7 coordinates, ``1e-16`` after).
    """
    ms = split_mass(M)
    A = sp.csr_array(A)
    b = np.asarray(b, dtype=float).ravel()
    force = np.asarray(force, dtype=float).ravel()
    Y, Sp = constraint_gain(ms, A)

    def mstar(v: np.ndarray) -> np.ndarray:  # M^* v = M_d^{-1} v - Y S^+ Y^T v
        return ms.solve(v) - Y @ (Sp @ (Y.T @ v))

    rhs = Y @ (Sp @ b) + mstar(force)

    def refined(qdd: np.ndarray) -> np.ndarray:
        return qdd + Y @ (Sp @ (b - A @ qdd)) if A.shape[0] else qdd

    s = np.flatnonzero(ms.massless)
    if s.size == 0:
        return refined(rhs)
    E = np.zeros((ms.Md.shape[0], s.size))
    E[s, np.arange(s.size)] = 1.0
    cols = ms.mu * mstar(E)  # the columns of M^* M_o that are not zero
    lhs = np.eye(s.size) - cols[s]
    try:
        qs = np.linalg.solve(lhs, rhs[s])
    except np.linalg.LinAlgError as exc:
        raise ValueError("massless coordinates not determined by the constraints "
                         "(I - M* M_o is singular)") from exc
    return refined(rhs + cols @ qs)


def _impedance(K: sp.sparray, M: sp.sparray, C: sp.sparray, omega: float) -> sp.csc_array:
    """``Z = K - w^2 M + i w C = H(w)^{-1}`` (eq 13)."""
    return (K.astype(complex) - omega**2 * M + 1j * omega * C).tocsc()


def receptance_unconstrained(K: sp.sparray | np.ndarray, M: sp.sparray | np.ndarray,
                             C: sp.sparray | np.ndarray | None, omega: float) -> np.ndarray:
    r"""Receptance of the unconstrained system, eq (13), dense.

    .. math::  H(\omega) = (-\omega^2 M + i \omega C + K)^{-1}
    """
    K = sp.csr_array(K)
    Z = _impedance(K, sp.csr_array(M), _csr(C, K.shape), omega)
    return np.linalg.inv(dense(Z))


def paper_G_D(K: sp.sparray | np.ndarray, M: sp.sparray | np.ndarray,
              C: sp.sparray | np.ndarray | None, A: sp.sparray | np.ndarray, omega: float,
              R: sp.sparray | np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    r"""The matrices ``G`` and ``D`` of eq (15), dense (the paper prints ``G`` as "C").

    .. math::
        G &= -H^{-1} + M^{1/2} (A M^{-1/2})^+ A M^{-1} (H^{-1} + \omega^2 M) \\
        D &= M^{1/2} (A M^{-1/2})^+ (\omega^2 R + A M^{-1}) - I

    with ``M^{1/2} (A M^{-1/2})^+ = A^T (A M^{-1} A^T)^+``.  ``R`` ties the constraint to the
    force at displacement level, ``A q = R F`` (read so, the printed eq 40 is reproduced; see
    ``docs/verification.md``).  With massless coordinates ``M_d`` replaces ``M`` outside ``H``.
    """
    K = sp.csr_array(K, dtype=float)
    n = K.shape[0]
    ms = split_mass(M)
    Ad = dense(sp.csr_array(A))
    Rd = np.zeros(Ad.shape) if R is None else dense(sp.csr_array(R))
    Z = dense(_impedance(K, sp.csr_array(M), _csr(C, K.shape), omega))
    Y, Sp = constraint_gain(ms, Ad)
    AMinv = Y.T  # A M_d^{-1}
    Md = dense(ms.Md)
    G = -Z + Ad.T @ Sp @ AMinv @ (Z + omega**2 * Md)
    D = Ad.T @ Sp @ (omega**2 * Rd + AMinv) - np.eye(n)
    return G, D


def _inputs_matrix(inputs: sp.sparray | np.ndarray | None, n: int) -> np.ndarray:
    if inputs is None:
        if n > 5000:
            raise ValueError(f"receptance of all {n} coordinates requested; name the inputs")
        return np.eye(n)
    return dense(inputs).reshape(n, -1)


def _gi_sweep(K, M, C, A, R, omegas, E, O) -> np.ndarray:
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
    below) and makes ``omega = 0`` singular.  We take ``alpha = max(omega^2, |A M^{-1} Z| / |A|)``: the
    paper's value wherever it is not too small.
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
    for k, w in enumerate(omegas):
        if w <= 0:
            raise ValueError(f"the generalized-inverse receptance (eq 15) is singular at "
                             f"omega = {w}; use method 'kkt' or 'null-space' for statics")
        Z = _impedance(K, M, C, w)
        YtZ = (Z.T @ Y).T  # A M^-1 Z
        alpha = max(w**2, float(np.linalg.norm(YtZ)) / normA)
        beta = max(float(spla.norm(Z)), 1e-300) / normA
        W = Sp @ (YtZ + alpha * Ad)  # S^+ (A M^-1 Z + alpha A)
        DE = A.T @ (Sp @ (alpha * RE + YtE)) - E
        big = sp.block_array([[-Z, beta * A.T.astype(complex)],
                              [sp.csr_array(W / beta), -sp.eye_array(m, dtype=complex)]],
                             format="csc")
        rhs = np.vstack([DE, np.zeros((m, E.shape[1]))]).astype(complex)
        lu = spla.splu(big)
        xy = lu.solve(rhs)
        xy = xy + lu.solve(rhs - big @ xy)  # one step of iterative refinement
        out[k] = O @ xy[:n]
    return out


def _null_space_sweep(K, M, C, A, R, omegas, E, O, rows) -> np.ndarray:
    r"""Null-space elimination: ``q = N p + q_p``, ``A N = 0``, ``A q_p = R F``.

    .. math::  q = N (N^T Z N)^{-1} N^T (F - Z q_p) + q_p
    """
    N = null_space_basis(A)
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


def _kkt_sweep(K, M, C, A, R, omegas, E, O, rows) -> np.ndarray:
    r"""Lagrange multipliers: ``[Z, A_k^T; A_k, 0] [q; \lambda] = [F; R_k F]`` (independent rows)."""
    Ak = sp.csr_array(A)[rows.keep]
    r = Ak.shape[0]
    n = A.shape[1]
    RE = np.zeros((r, E.shape[1])) if R is None else (dense(sp.csr_array(R)) @ E)[rows.keep]
    out = np.empty((len(omegas), O.shape[0], E.shape[1]), dtype=complex)
    normA = max(float(spla.norm(Ak)), 1e-300) if r else 1.0
    for k, w in enumerate(omegas):
        Z = _impedance(K, M, C, w)
        # rows and multipliers scaled by beta = |Z| / |A|: blocks of one size, so that the
        # pivoting is not misled when a stiffness of 1e12 sits next to a constraint of 1
        beta = max(float(spla.norm(Z)), 1e-300) / normA
        big = sp.block_array([[Z, beta * Ak.T], [beta * Ak, None]], format="csc")
        rhs = np.vstack([E, beta * RE]).astype(complex)
        try:
            x = spla.splu(big.astype(complex)).solve(rhs)[:n]
        except RuntimeError as exc:
            raise ValueError(f"KKT system singular at omega = {w} (a constrained resonance "
                             "of an undamped system)") from exc
        out[k] = O @ x
    return out


def receptance(K: sp.sparray | np.ndarray, M: sp.sparray | np.ndarray,
               C: sp.sparray | np.ndarray | None, A: sp.sparray | np.ndarray,
               omegas: float | Sequence[float] | np.ndarray,
               R: sp.sparray | np.ndarray | None = None, method: str = "generalized-inverse",
               inputs: sp.sparray | np.ndarray | None = None,
               outputs: sp.sparray | np.ndarray | None = None,
               labels: list[str] | None = None) -> np.ndarray:
    r"""Receptance of a system under linear constraints ``A q = R F`` (eqs 11-15).

    .. math::  \hat q = \hat H(\omega) \bar F, \qquad \hat H = G^{-1} D \quad (15)

    Args:
        K, M, C: sparse ``n x n`` matrices (``C`` may be ``None``); ``M`` may have massless rows.
        A: ``m x n`` constraint matrix, any rank.
        omegas: one circular frequency (rad/s) or a sequence.
        R: ``m x n`` matrix tying the constraint to the force, ``A q = R F`` (``None``: ``A q = 0``).
        method: ``"generalized-inverse"`` (eq 15), ``"null-space"`` or ``"kkt"``.
        inputs: ``n x k`` force patterns (columns of ``F``); ``None`` for all coordinates.
        outputs: ``k_o x n`` rows giving the outputs; ``None`` for all coordinates.
        labels: constraint names used in error messages.

    Returns:
        ``(n_omega, k_o, k)`` complex array, or ``(k_o, k)`` for a scalar ``omega``.

    Raises:
        ConstraintError: if a redundant constraint row carries an inconsistent ``R``.
    """
    K = sp.csr_array(K, dtype=float)
    n = K.shape[0]
    M = sp.csr_array(M, dtype=float)
    C = _csr(C, (n, n)).astype(float)
    A = sp.csr_array(A, dtype=float).reshape(-1, n) if np.size(A) else sp.csr_array((0, n))
    scalar = np.ndim(omegas) == 0
    w = np.atleast_1d(np.asarray(omegas, dtype=float))
    E = _inputs_matrix(inputs, n)
    O = sp.eye_array(n).tocsr() if outputs is None else sp.csr_array(outputs).reshape(-1, n)
    rows = independent_rows(A)
    if R is not None:
        check_consistent(A, R, rows, labels)
    if method == "generalized-inverse":
        H = _gi_sweep(K, M, C, A, R, w, E, O)
    elif method == "null-space":
        H = _null_space_sweep(K, M, C, A, R, w, E, O, rows)
    elif method == "kkt":
        H = _kkt_sweep(K, M, C, A, R, w, E, O, rows)
    else:
        raise ValueError(f"unknown method {method!r}; expected one of {', '.join(METHODS)}")
    return H[0] if scalar else H


def receptance_agreement(K: sp.sparray | np.ndarray, M: sp.sparray | np.ndarray,
                         C: sp.sparray | np.ndarray | None, A: sp.sparray | np.ndarray,
                         omegas: float | Sequence[float] | np.ndarray,
                         R: sp.sparray | np.ndarray | None = None,
                         methods: Sequence[str] = METHODS, **kwargs) -> dict[str, float]:
    r"""Largest relative difference of each method's receptance from the first method's.

    .. math::  \delta = \max_\omega \|\hat H_{method} - \hat H_{ref}\|_\max / \|\hat H_{ref}\|_\max
    """
    results = {mth: receptance(K, M, C, A, omegas, R, method=mth, **kwargs) for mth in methods}
    ref = results[methods[0]]
    scale = np.abs(ref).reshape(np.shape(ref)[0] if np.ndim(ref) == 3 else 1, -1).max(axis=1)
    out = {}
    for mth, H in results.items():
        diff = np.abs(H - ref).reshape(scale.size, -1).max(axis=1)
        out[mth] = float(np.max(diff / np.where(scale > 0, scale, 1.0)))
    return out

