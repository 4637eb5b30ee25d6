r"""Coupled modes of constrained systems, dense: the paper's formulation (eqs 23-34) and two
independent ones, for models of a few thousand coordinates at most.

The paper's route: with ``M^*`` of eq (10), the constrained free vibration is (eq 28)

.. math::  (I - M^* M_o) \ddot u + M^* C \dot u + M^* K u = 0

and its roots are found from the state-space pencil of eqs (32)-(34),

.. math::  R \bar\eta = \lambda W \bar\eta, \quad
           W = \begin{bmatrix} 0 & I - M^* M_o \\ I - M^* M_o & M^* C \end{bmatrix}, \quad
           R = \begin{bmatrix} I - M^* M_o & 0 \\ 0 & -M^* K \end{bmatrix}.

``M^* K`` has rank ``n - rank(A)``: the pencil returns ``2 rank(A)`` zero roots whose vectors
violate ``A u = 0``, set aside by :func:`substruct.analysis.modes.roots.classify_roots`.

Checks: null-space elimination ``u = N p``,

.. math::  N^T (\lambda^2 M + \lambda C + K) N p = 0, \qquad A N = 0,

and the Lagrange (KKT) pencil
``\lambda^2 [M, 0; 0, 0] + \lambda [C, 0; 0, 0] + [K, A^T; A, 0]``.  All three are balanced
(:func:`substruct.analysis.modes.pencil.fan_lin_van_dooren`) before QZ, their roots sorted out by
counts (:mod:`substruct.analysis.modes.roots`) and refined on the Rayleigh functional of their own
vectors (:func:`substruct.analysis.modes.pencil.rayleigh_root`).

This is the dense strategy of :func:`substruct.analysis.api.modes`, which chooses it.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from substruct.analysis.formulations.projection import (
    MassSplit,
    constraint_gain,
    projected_inverse,
    split_mass,
)
from substruct.analysis.modes.pencil import (
    Refine,
    fan_lin_van_dooren,
    pencil_roots,
    quadratic_forms,
    quadratic_roots,
    rayleigh_refiner,
    rayleigh_root,
)
from substruct.analysis.errors import AnalysisInputError
from substruct.analysis.results import Modes
from substruct.analysis.modes.roots import classify_roots
from substruct.linalg.constraints import independent_rows
from substruct.linalg.dense import dense
from substruct.linalg.nullspace import null_space_basis
from substruct.linalg.scaling import equilibrate, mass_column_scale
from substruct.vocabulary import FORMULATIONS, GENERALIZED_INVERSE, KKT, NULL_SPACE

__all__ = ["FORMULATIONS", "coupled_modes", "dense_generalized_inverse_modes", "kkt_modes",
           "dense_null_space_modes"]



def dense_generalized_inverse_modes(M: np.ndarray, C: np.ndarray, K: np.ndarray,
                              A: np.ndarray) -> Modes:
    """Eqs (28)-(34): the state-space pencil of the projected equations.

    Solved for ``mu = lambda / gamma`` with ``gamma = sqrt(|M^* K| / |T|)``, which balances the
    blocks of (32)-(34) the way :func:`fan_lin_van_dooren` balances a companion pencil.
    """
    n = K.shape[0]
    ms = split_mass(sp.csr_array(M))
    Mstar = projected_inverse(ms, A)
    Mo = dense(ms.Mo)
    T = np.eye(n) - Mstar @ Mo
    # eq (33) carries T in its first block row as well (T u' = T u'); that row only defines the
    # velocity, and with a massless coordinate that no constraint reaches T is singular and the
    # pencil would be singular too.  The identity there gives the same roots when T is regular.
    I = np.eye(n)
    MsK, MsC = Mstar @ K, Mstar @ C
    gamma, _ = fan_lin_van_dooren(float(np.linalg.norm(T)), float(np.linalg.norm(MsC)),
                                   float(np.linalg.norm(MsK)))
    Wm = np.block([[np.zeros((n, n)), I], [T, MsC / gamma]])
    Rm = np.block([[I, np.zeros((n, n))], [np.zeros((n, n)), -MsK / gamma**2]])
    lam, U = pencil_roots(Rm, Wm, n, gamma)
    return classify_roots(lam, U, A, M, C, K, GENERALIZED_INVERSE,
                          _gi_polish(ms, M, C, K, A, U))


def _gi_polish(ms: MassSplit, M: np.ndarray, C: np.ndarray, K: np.ndarray, A: np.ndarray,
               U: np.ndarray) -> Refine:
    r"""Refinement of the roots of eqs (32)-(34) within the generalized-inverse formulation.

    The pencil carries ``M^* K``, in which the projector of eq (10) mixes the rows of ``K``:
    with a stiffness of ``1e12`` next to ``1`` its soft entries are known to ``1e-4`` only, and
    so are the soft modes' roots and vectors.  The vector ``u`` is projected onto ``null(A)``
    (``P = I - M_d^{-1} A^T S^+ A``, eqs 5, 10) and the root refined on its Rayleigh functional
    (:func:`~substruct.analysis.modes.pencil.rayleigh_root`); if that moves the root by more than
    ``1e-11`` of itself the vector is not good enough, and one step of inverse iteration with
    the receptance of eq (15) at ``lambda``, which works with ``K`` itself, replaces it.  The
    vector reported is the projected one (the pencil's own has ``|A u|`` of ``eps cond``,
    ``2e-10`` seen):

    .. math::  G_\alpha(\lambda)\, x = D_\alpha M u, \qquad
               G_\alpha = -Z + A^T S^+ (A M_d^{-1} Z + \alpha A), \quad
               D_\alpha = A^T S^+ A M_d^{-1} - I, \quad Z = \lambda^2 M + \lambda C + K
    """
    n = K.shape[0]
    if A.size:
        Y, Sp = constraint_gain(ms, A)
        P = np.eye(n) - Y @ Sp @ A
        normA = float(np.linalg.norm(A))
    else:
        P = np.eye(n)

    cache: list[np.ndarray] = []

    def polish(j: int, lam: complex) -> tuple[complex, np.ndarray | None]:
        if not cache:
            cache.extend(quadratic_forms(P @ U, M, C, K))
        first, kept = rayleigh_root(lam, cache[0][j], cache[1][j], cache[2][j])
        u = P @ U[:, j]
        if kept and abs(first - lam) <= 1e-11 * abs(lam):
            return first, u
        Z = lam**2 * M + lam * C + K
        f = M @ u
        if A.size:
            YtZ = Y.T @ Z
            alpha = max(abs(lam) ** 2, float(np.linalg.norm(YtZ)) / normA)
            G = -Z + A.T @ (Sp @ (YtZ + alpha * A))
            rhs = A.T @ (Sp @ (Y.T @ f)) - f
        else:
            G, rhs = -Z, -f
        try:
            x = P @ np.linalg.solve(G, rhs)
        except np.linalg.LinAlgError:
            return first, u
        if not np.all(np.isfinite(x)) or not np.any(x):
            return first, u
        a, b, c = (v[0] for v in quadratic_forms(x[:, None], M, C, K))
        second, kept = rayleigh_root(lam, a, b, c, trust=0.1)
        return (second, x) if kept else (first, u)

    return polish


def dense_null_space_modes(M: np.ndarray, C: np.ndarray, K: np.ndarray, A: np.ndarray) -> Modes:
    """``u = N p`` with ``A N = 0``: ``N^T (lambda^2 M + lambda C + K) N p = 0``."""
    n = K.shape[0]
    N = null_space_basis(A, col_scale=mass_column_scale(M)) if A.size else np.eye(n)
    Mr, Cr, Kr = N.T @ M @ N, N.T @ C @ N, N.T @ K @ N
    if not N.shape[1]:  # the constraints fix every coordinate: no motion at all
        lam, U = np.zeros(0, complex), np.zeros((n, 0), complex)
    elif not np.any(Cr) and np.linalg.eigvalsh((Mr + Mr.T) / 2).min() > 1e-12 * \
            max(np.abs(Mr).max(), 1e-300):
        w2, P = sla.eigh(Kr, Mr)
        lam = np.sqrt(w2.astype(complex)) * 1j  # a negative w2 (unstable) gives a real root
        U = N @ P
        lam = np.concatenate([lam, lam.conj()])
        U = np.hstack([U, U])
    else:
        lam, P = quadratic_roots(Mr, Cr, Kr)
        U = N @ P
    U = U.astype(complex)
    return classify_roots(lam, U, A, M, C, K, NULL_SPACE, rayleigh_refiner(U, M, C, K))


def kkt_modes(M: np.ndarray, C: np.ndarray, K: np.ndarray, A: np.ndarray) -> Modes:
    """Lagrange multipliers: the pencil ``lambda^2 [M,0;0,0] + lambda [C,0;0,0] + [K,A^T;A,0]``."""
    n = K.shape[0]
    rows = independent_rows(A, col_scale=mass_column_scale(M))
    Ak = A[rows.keep] if A.size else np.zeros((0, n))
    if Ak.size:  # multipliers in units of force: A^T of the size of K
        Ak = Ak * (np.linalg.norm(K) / np.linalg.norm(Ak) if np.any(K) else 1.0)
    r = Ak.shape[0]
    Mq = sla.block_diag(M, np.zeros((r, r)))
    Cq = sla.block_diag(C, np.zeros((r, r)))
    Kq = np.block([[K, Ak.T], [Ak, np.zeros((r, r))]])
    lam, V = quadratic_roots(Mq, Cq, Kq)
    # the KKT functional adds 2 mu^T A u (the multipliers of the scaled rows)
    extra = 2 * np.sum(V[n:] * (Ak @ V[:n]), axis=0)
    return classify_roots(lam, V[:n], A, M, C, K, KKT, rayleigh_refiner(V[:n], M, C, K, extra))


#: The dense pencils lose every digit of the roots when the masses span more than this: a
#: nonzero diagonal entry of ``M`` below this fraction of the largest is refused (on
#: ``diag(1, m)`` with a stiffness coupling, ``m = 1e-15`` still gives both roots to 1e-12,
#: ``1e-16`` a root 49 % off and ``1e-17`` a pair with damping ratios of +-1).
DENSE_MASS_RANGE = 1e-15


def coupled_modes(M: sp.sparray | np.ndarray, C: sp.sparray | np.ndarray | None,
                  K: sp.sparray | np.ndarray, A: sp.sparray | np.ndarray | None,
                  method: str = GENERALIZED_INVERSE, n_modes: int | None = None) -> Modes:
    r"""Physical modes of ``M u'' + C u' + K u = 0`` under ``A u = 0`` (eqs 23-34).

    Args:
        M, C, K: ``n x n`` matrices (``M`` may be singular on massless coordinates, eq 6).
        A: ``m x n`` constraint matrix of any rank (``None`` for none).
        method: ``generalized-inverse`` (the paper's eqs 28-34), ``null-space`` or ``kkt``
            (the formulation object of that name,
            :func:`substruct.analysis.formulations.forms.formulation`, solves).
        n_modes: keep the lowest ``n_modes`` physical modes (all if ``None``).

    Returns:
        The physical modes, ascending, and the roots set aside with their reasons
        (:class:`~substruct.analysis.results.Modes`, ``solver = "dense"``; no checks: see
        :func:`substruct.analysis.api.modes`).

    Raises:
        ValueError: an unknown method.
        AnalysisInputError: a motion with no mass, no stiffness and no constraint; masses
            spanning more than :data:`DENSE_MASS_RANGE`.

    Dense algebra: for the reduced models of the paper (a few thousand coordinates at most).
    """
    Md = dense(sp.csr_array(M, dtype=float))
    n = Md.shape[0]
    Kd = dense(sp.csr_array(K, dtype=float))
    Cd = np.zeros((n, n)) if C is None else dense(sp.csr_array(C, dtype=float))
    Ad = np.zeros((0, n)) if A is None or np.size(A) == 0 else \
        dense(sp.csr_array(A, dtype=float))
    if Ad.shape[0]:  # D A u = 0, rows of unit norm: rank decided whatever a row's scale (the
        # rows of a ConstrainedSystem are so already: powers of two, no bit changes)
        Ad = np.asarray(equilibrate(Ad).A)
    if method not in FORMULATIONS:
        raise ValueError(f"unknown method {method!r}; expected one of {', '.join(FORMULATIONS)}")
    masses = np.abs(np.diag(Md))
    if masses.size and np.any((masses > 0) & (masses < DENSE_MASS_RANGE * masses.max())):
        i = int(np.argmin(np.where(masses > 0, masses, np.inf)))
        raise AnalysisInputError(
            f"the masses span more than {-np.log10(DENSE_MASS_RANGE):.0f} orders of "
            f"magnitude (M[{i}, {i}] = {masses[i]:.3g} against {masses.max():.3g}): the dense "
            f"solver's pencils cannot resolve them; give 0 for a massless coordinate, or use "
            f"solver: sparse")
    modes = {GENERALIZED_INVERSE: dense_generalized_inverse_modes,  # each formulation on its own
             NULL_SPACE: dense_null_space_modes, KKT: kkt_modes}[method](Md, Cd, Kd, Ad)
    modes.solver = "dense"
    return modes.lowest(n_modes)


