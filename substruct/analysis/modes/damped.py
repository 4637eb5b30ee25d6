r"""Coupled modes of large damped models (any ``C``: Rayleigh, discrete dashpots,
non-proportional), with no dense ``n x n`` matrix.

:func:`damped_sparse_modes` linearizes the quadratic problem
:math:`(\lambda^2 M + \lambda C + K) u = A^T \mu`, :math:`A u = 0`, to a first-order pencil and
runs ``eigs`` (Arnoldi) in shift-invert mode about a small negative real shift, with one SuperLU
factorization (on the null-space form of the symmetric :math:`\sigma^2 M_r + \sigma C_r + K_r`
of the reduced size, :func:`_quadratic_operator`): either on the null-space form :math:`u = T p` (``T`` from
:func:`substruct.linalg.nullspace.master_slave`) or on the Lagrange (KKT) form with multipliers,
an independent check.  The roots are reported as :func:`substruct.analysis.modes.dense.coupled_modes` reports
them (complex ``lambda``, ``omega = |lambda|``, ``damping_ratio = -Re lambda / |lambda|``,
complex shapes).  :func:`substruct.analysis.modes.sparse.sparse_coupled_modes` dispatches here when
``C`` has nonzeros.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from substruct.analysis.errors import singular_model
from substruct.analysis.modes.krylov import (
    check_inputs,
    constraint_residuals,
    eliminate,
    free_coordinates,
    krylov_size,
)
from substruct.analysis.modes.pencil import rayleigh_root
from substruct.analysis.results import Modes
from substruct.analysis.modes.roots import REAL_TOL
from substruct.linalg.factorize import factorizer
from substruct.linalg.nullspace import Elimination
from substruct.vocabulary import KKT, NULL_SPACE

__all__ = ["damped_sparse_modes", "DAMPED_SHIFT", "ZERO_ROOT"]


def _factorize(kind: str, B: sp.csc_array) -> Callable[[np.ndarray], np.ndarray]:
    """``factorizer(kind, spd=False)(B)``; an exactly singular shifted pencil (SuperLU's zero
    pivot: a motion with neither mass, damping nor stiffness) refused as bad input."""
    try:
        return factorizer(kind, spd=False)(B)
    except RuntimeError as exc:
        if "singular" not in str(exc):
            raise
        raise singular_model("the shifted pencil is singular") from None


def _quadratic_operator(Mr: sp.csr_array, Cr: sp.csr_array, Kr: sp.csr_array,
                        sigma: float) -> Callable[[np.ndarray], np.ndarray]:
    r""":math:`x \mapsto (\mathcal{A} - \sigma \mathcal{B})^{-1} \mathcal{B} x` of the
    null-space first-order pencil (:func:`damped_sparse_modes`) by one factorization of the
    symmetric :math:`Q(\sigma) = \sigma^2 M_r + \sigma C_r + K_r` of the reduced size ``r``
    (SuperLU in symmetric mode with threshold pivots: ``Q`` may be indefinite), instead of an
    unsymmetric LU of the ``2r`` pencil, whose fill on a 3D mesh grows far faster: with
    :math:`x = [x_1; x_2]`,

    .. math::  y_1 = -Q(\sigma)^{-1} \big(M_r x_2 + (C_r + \sigma M_r) x_1\big), \qquad
               y_2 = x_1 + \sigma y_1 .
    """
    r = Kr.shape[0]
    solve = _factorize("saddle", sp.csc_array(sigma**2 * Mr + sigma * Cr + Kr))
    D = sp.csr_array(Cr + sigma * Mr)

    def apply(x: np.ndarray) -> np.ndarray:
        x = np.asarray(x).ravel()
        y1 = -np.asarray(solve(Mr @ x[r:] + D @ x[:r])).ravel()
        return np.concatenate([y1, x[:r] + sigma * y1])
    return apply


def _scaled_shift_invert(Ab: sp.sparray, Bb: sp.sparray, k: int, sigma: float,
                         ncv: int | None, finite: int,
                         operator: Callable[[np.ndarray], np.ndarray] | None = None
                         ) -> tuple[np.ndarray, np.ndarray]:
    r"""Roots :math:`\mu` nearest ``sigma`` of :math:`A_b x = \mu B_b x` (real, ``B_b`` possibly
    singular), by ``eigs`` on :math:`x \mapsto (A_b - \sigma B_b)^{-1} B_b x` (SuperLU):
    :math:`\mu = \sigma + 1/\nu`.  Infinite roots are ``nu = 0`` and are never returned as
    converged nonzero ``nu``; a returned ``nu`` near 0 gives a huge ``mu``, dropped later.
    ``operator``, if given, applies :math:`(A_b - \sigma B_b)^{-1} B_b` (the structured solve
    of :func:`_quadratic_operator`).  The Arnoldi basis is capped by ``finite``, the dimension
    of the space the operator spans
    (:func:`substruct.analysis.modes.krylov.krylov_size`); pencils too small for it (``k`` too
    close to that dimension) are solved densely."""
    N = Ab.shape[0]
    try:
        size = krylov_size(k, min(finite, N), ncv, margin=2)
    except ValueError:
        size = 0
    if not size:
        ab, V = sla.eig(Ab.toarray(), Bb.toarray(), homogeneous_eigvals=True)
        alpha, beta = ab
        fin = np.abs(beta) > 1e-14 * np.abs(alpha)
        return alpha[fin] / beta[fin], V[:, fin]
    if operator is None:
        solve = _factorize("superlu", sp.csc_array(Ab - sigma * Bb))
        Bc = sp.csr_array(Bb)

        def operator(x: np.ndarray) -> np.ndarray:
            return np.asarray(solve(Bc @ np.asarray(x).ravel()))
    op = spla.LinearOperator((N, N), matvec=operator, dtype=float)
    v0 = operator(np.random.default_rng(0).standard_normal(N))  # no infinite part
    nu, X = spla.eigs(op, k=k, which="LM", v0=v0, ncv=size)
    ok = np.abs(nu) > 1e-12 * np.abs(nu).max(initial=0.0)
    return sigma + 1.0 / nu[ok], X[:, ok]


def _damped_finish(mu: np.ndarray, U: np.ndarray, gamma: float, M: sp.csr_array,
                   C: sp.csr_array, K: sp.csr_array, A: sp.csr_array, n_modes: int,
                   method: str) -> Modes:
    r"""Roots ``lambda = gamma mu`` and vectors ``u`` (``A u = 0``) as the dense path reports
    them (:class:`substruct.analysis.results.Modes`): zero roots of rigid-body motions once per motion,
    one root of each conjugate pair (``Im > 0``), real roots (``|Im| <= REAL_TOL |lambda|``)
    each on its own; refined on the Rayleigh functional; ascending in ``|lambda|``, then
    ``Re lambda``; ``n_modes`` of them."""
    lam = gamma * mu
    fin = np.isfinite(lam) & (np.abs(mu) < 1e8)
    lam, U = lam[fin], U[:, fin]
    zero = np.abs(mu[fin]) <= ZERO_ROOT
    out_l: list[complex] = []
    out_u: list[np.ndarray] = []
    if zero.any():
        # rigid-body motions (K u = 0, A u = 0): an undamped one is a defective double zero
        # root, which Arnoldi splits by ~sqrt(eps); report each motion once with lambda = 0
        # (the rank of the cluster's vectors), and a slow decay -c/m inside the cluster from
        # the damping on those motions, as substruct.analysis.modes.roots.root_structure counts them
        Z = U[:, zero] / np.linalg.norm(U[:, zero], axis=0)
        W, sv, _ = np.linalg.svd(Z, full_matrices=False)
        W = W[:, sv > 1e-6 * sv[0]]
        Wm, Wc = W.conj().T @ (M @ W), W.conj().T @ (C @ W)
        rates, V = sla.eigh((Wc + Wc.conj().T) / 2, (Wm + Wm.conj().T) / 2)
        for j in range(W.shape[1]):
            w = W @ V[:, j]
            out_l.append(0j)
            out_u.append(w)
            if 1e-8 * gamma < abs(rates[j]) <= ZERO_ROOT * gamma:
                out_l.append(complex(-rates[j]))
                out_u.append(w)
    for j in np.flatnonzero(~zero).tolist():
        l, u = complex(lam[j]), U[:, j]
        real = abs(l.imag) <= REAL_TOL * abs(l)
        if not real and l.imag < 0:
            continue
        Mu, Cu, Ku = M @ u, C @ u, K @ u
        l, _ = rayleigh_root(l, u @ Mu, u @ Cu, u @ Ku)
        if real:
            l = complex(l.real, 0.0)
        out_l.append(l)
        out_u.append(u)
    n = K.shape[0]
    lam_p = np.array(out_l, dtype=complex)
    Up = np.array(out_u, dtype=complex).T.reshape(n, -1)
    order = np.lexsort((lam_p.real, np.abs(lam_p)))[:n_modes]
    lam_p, Up = lam_p[order], Up[:, order]
    if Up.shape[1]:  # as roots.normalize_shapes: largest entry real positive, u^H M u = 1
        top = Up[np.argmax(np.abs(Up), axis=0), np.arange(Up.shape[1])]
        Up = Up * (np.abs(top) / np.where(top == 0, 1, top))
        mass = np.real(np.sum(np.conj(Up) * (M @ Up), axis=0))
        norm = np.linalg.norm(Up, axis=0)
        mmax = float(abs(M).max()) if M.nnz else 0.0
        scale = np.where(mass > 1e-14 * norm**2 * max(mmax, 1e-300), np.sqrt(np.abs(mass)), norm)
        Up = Up / np.where(scale > 0, scale, 1.0)
    omega = np.abs(lam_p)
    zeta = np.where(omega > 0, -lam_p.real / np.where(omega > 0, omega, 1), 0.0)
    return Modes(eigenvalues=lam_p, omega=omega, damping_ratio=zeta, shapes=Up,
                 residual=constraint_residuals(A, Up), method=method, solver="sparse-damped")


def _balance(M: sp.sparray, C: sp.sparray, K: sp.sparray) -> tuple[float, float]:
    r"""``(gamma, delta)``: :math:`\lambda = \gamma \mu`, the pencil
    :math:`\delta(\gamma^2 \mu^2 M + \gamma \mu C + K)` (Fan, Lin and Van Dooren, with traces
    for norms: :math:`\gamma = \sqrt{\operatorname{tr} K / \operatorname{tr} M}`)."""
    m2 = float(abs(M.diagonal()).sum())
    c2 = float(abs(C.diagonal()).sum())
    k2 = float(abs(K.diagonal()).sum())
    if m2 <= 0 or k2 <= 0:
        return 1.0, 1.0 / max(m2, c2, k2, 1e-300)
    gamma = np.sqrt(k2 / m2)
    return gamma, 2.0 / (k2 + c2 * gamma)


#: The shift of the damped shift-invert, in units of :math:`\gamma` (:func:`_balance`).  Not
#: too small: with an undamped rigid-body motion (a defective zero root) the error of the other
#: roots grows as the shift nears zero (KKT form: ``3e-9`` at ``-1e-5``, ``4e-13`` at
#: ``-1e-3``).  The roots nearest the shift are not quite the smallest ones: see
#: :func:`damped_sparse_modes` for the check that they cover them.
DAMPED_SHIFT = -1e-3
#: Roots below this (units of :math:`\gamma`) are zero roots of rigid-body motions: the double
#: zero root of an undamped one comes out split by ``sqrt(eps)`` (``5e-9`` seen).
ZERO_ROOT = 1e-6


def damped_sparse_modes(M: sp.sparray, C: sp.sparray | None, K: sp.sparray,
                        A: sp.sparray | None, n_modes: int, *, formulation: str = NULL_SPACE,
                        sigma: float | None = None, ncv: int | None = None,
                        extra: int = 6, elimination: Elimination | None = None) -> Modes:
    r"""Lowest ``n_modes`` roots of :math:`(\lambda^2 M + \lambda C + K) u = A^T \mu`,
    :math:`A u = 0`, for any damping ``C`` (non-proportional, discrete dashpots), sparse.

    Balanced (:func:`_balance`, :math:`\lambda = \gamma s`, :math:`M' = \delta\gamma^2 M`,
    :math:`C' = \delta\gamma C`, :math:`K' = \delta K`) and linearized to a first-order pencil
    :math:`\mathcal{A} x = s \mathcal{B} x`, solved by ``eigs`` in shift-invert mode about
    :math:`\sigma` (default ``DAMPED_SHIFT``, a small negative real) with one SuperLU of
    :math:`\mathcal{A} - \sigma \mathcal{B}`: :math:`s = \sigma + 1/\nu`.  Massless
    coordinates and multipliers make :math:`\mathcal{B}` singular; their infinite roots are
    :math:`\nu = 0` and never computed.  Two formulations:

    ``null-space``: :math:`u = T p` (:func:`~substruct.linalg.nullspace.master_slave`),
    :math:`M_r = T^T M' T`, etc., :math:`x = [p; s p]`,

    .. math::  \begin{bmatrix} 0 & I \\ -K_r & -C_r \end{bmatrix} x
               = s \begin{bmatrix} I & 0 \\ 0 & M_r \end{bmatrix} x .

    ``kkt``: Lagrange multipliers, no ``T``; independent rows ``A_k`` of ``A`` (those kept by
    :func:`~substruct.linalg.nullspace.master_slave`, of unit norm), scaled to the size of
    ``K'``, :math:`x = [u; s u; \mu]`,

    .. math::  \begin{bmatrix} 0 & I & 0 \\ -K' & -C' & -A_k^T \\ A_k & 0 & 0 \end{bmatrix} x
               = s \begin{bmatrix} I & 0 & 0 \\ 0 & M' & 0 \\ 0 & 0 & 0 \end{bmatrix} x .

    Both have the finite roots of the constrained problem and nothing else (the paper's
    state-space form, eqs 28-34, has ``2 rank(A)`` spurious zero roots besides; it needs the
    dense projector and is not used here).  Roots are reported as the dense
    :func:`substruct.analysis.modes.dense.coupled_modes` reports them (:func:`_damped_finish`): one of each
    conjugate pair, real (over-damped) roots one entry each with damping ratio 1, a rigid-body
    motion once with ``lambda = 0``, each root refined on the Rayleigh functional
    :math:`u^T (\lambda^2 M + \lambda C + K) u = 0` of its vector; ``omega = |lambda|``,
    ``damping_ratio = -Re lambda / |lambda|``, shapes complex with ``u^H M u = 1``.

    Args:
        M, C, K: sparse ``n x n`` (``C`` ``None`` for none).
        A: ``m x n`` constraint rows, any rank.
        n_modes: roots wanted (after pairing).
        formulation: ``null-space`` or ``kkt``.
        sigma: the shift in units of :math:`\gamma`.
        ncv: Arnoldi basis size (``eigs`` default if ``None``).
        extra: roots computed beyond ``2 n_modes`` (conjugates, clusters).

    Raises:
        AnalysisInputError: the shifted pencil exactly singular (a motion with neither mass,
            damping nor stiffness).
    """
    M, K, A, k = check_inputs(M, K, A, n_modes)
    n = K.shape[0]
    C = sp.csr_array((n, n)) if C is None else sp.csr_array(C, dtype=float)
    if C.shape != (n, n):
        raise ValueError(f"C has shape {C.shape}, K has {K.shape}")
    gamma, delta = _balance(M, C, K)
    Ms, Cs, Ks = delta * gamma**2 * M, delta * gamma * C, delta * K
    s = DAMPED_SHIFT if sigma is None else float(sigma)
    el = elimination or eliminate(M, A)
    # the roots the first-order pencil has: two per free direction that has mass
    finite = 2 * free_coordinates(el, M)
    if formulation == NULL_SPACE:
        T = sp.csc_array(el.T)
        r = T.shape[1]
        red = [sp.csr_array(T.T @ (X @ T)) for X in (Ms, Cs, Ks)]
        Mr, Cr, Kr = ((X + X.T) / 2 for X in red)
        I = sp.eye_array(r, format="csr")
        Ab = sp.block_array([[None, I], [-Kr, -Cr]], format="csc")
        Bb = sp.block_array([[I, None], [None, Mr]], format="csc")
        lift = lambda X: T @ X[:r]  # noqa: E731
        method = "null-space/sparse"
        operator = _quadratic_operator(Mr, Cr, Kr, s)
    elif formulation == KKT:
        r = n - el.rank
        Ak = sp.csr_array(A[el.kept_rows])  # rows of unit 2-norm (check_inputs)
        if Ak.shape[0]:
            Ak = Ak * (float(np.mean(abs(Ks.diagonal()))) or 1.0)
        m = Ak.shape[0]
        I = sp.eye_array(n, format="csr")
        Z = sp.csr_array((m, m))
        Ab = sp.block_array([[None, I, None], [-Ks, -Cs, -Ak.T], [Ak, None, Z]], format="csc")
        Bb = sp.block_array([[I, None, None], [None, Ms, None], [None, None, Z]],
                            format="csc")
        lift = lambda X: X[:n]  # noqa: E731
        method = "kkt/sparse"
        operator = None
    else:
        raise ValueError(f"unknown formulation {formulation!r}; expected 'null-space' or 'kkt'")
    if r == 0:  # the constraints fix every coordinate: no motion at all
        mu, X = np.zeros(0, complex), np.zeros((Ab.shape[0], 0), complex)
    else:  # at most 2 r roots; fewer than k modes if there are fewer (as the dense path)
        want = min(2 * k + extra, 2 * r)
        while True:
            mu, X = _scaled_shift_invert(Ab, Bb, want, s, ncv, finite, operator)
            # the want roots nearest s hold every root with |mu| <= reach - |s|: enough if
            # that covers the k-th smallest root (a conjugate pair is 2 of them)
            reach = np.abs(mu - s).max(initial=0.0)
            small = np.sort(np.abs(mu))
            if want >= 2 * r or mu.size < want or \
                    small[min(2 * k, small.size) - 1] <= reach - abs(s):
                break
            want = min(2 * want, 2 * r)
    return _damped_finish(mu, lift(X), gamma, M, C, K, A, k, method)
