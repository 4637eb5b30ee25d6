r"""Coupled modes of large constrained models, undamped or damped, with no dense ``n x n`` matrix.

The lowest ``k`` solutions of

.. math::  K u = \omega^2 M u + A^T \mu, \qquad A u = 0,

by shift-invert Lanczos (``scipy.sparse.linalg.eigsh``) about a shift :math:`\sigma < 0`, with an
``OPinv`` built from a factorization of the registry (:func:`substruct.linalg.factorize.factorizer`),
never one that ``eigsh`` makes for itself (on 95k coordinates the factorization ``eigsh``
made took 279 s and 5.5 GB, a chosen one 13-28 s: docs/performance.md).  Two independent paths:

**Null space** (:func:`null_space_modes`): a sparse basis ``T`` of :math:`\operatorname{null}(A)`
by master-slave elimination (:func:`substruct.linalg.nullspace.master_slave`), :math:`u = T p`, and
the reduced pencil

.. math::  T^T K T\, p = \omega^2\, T^T M T\, p ,

symmetric positive (semi)definite: any factorization of :math:`T^T (K - \sigma M) T` serves
(SuperLU, or CHOLMOD when scikit-sparse is installed).

**Generalized inverse** (:func:`generalized_inverse_modes`): the paper's projected operator
:math:`M^* K` (eq 30, :math:`M^* = P M_d^{-1}`,
:math:`P = I - M_d^{-1} A^T (A M_d^{-1} A^T)^+ A` the :math:`M_d`-orthogonal projector onto
:math:`\operatorname{null}(A)`) in shift-invert form.  For :math:`x \in \operatorname{null}(A)`,
:math:`y = (M^* K - \sigma I)^{-1} x` is the first block of the saddle-point solve

.. math::  \begin{bmatrix} K - \sigma M & A^T \\ A & 0 \end{bmatrix}
           \begin{bmatrix} y \\ \mu \end{bmatrix} = \begin{bmatrix} M x \\ 0 \end{bmatrix},

(indeed :math:`P M_d^{-1} (K - \sigma M) y = P M_d^{-1} M x = x`), factorized once.  The
result is restricted by :math:`P`, applied through a second saddle-point solve with
:math:`M_d`: :math:`P y = v` where :math:`[M_d, A^T; A, 0][v; z] = [M_d y; 0]`.  The
``2 rank(A)`` spurious zero roots of :math:`M^* K` (vectors that violate :math:`A u = 0`)
become the eigenvalue 0 of the shift-inverted operator and are never computed.

Both return :class:`substruct.analysis.results.Modes` with real mode shapes (undamped),
``u^T M u = 1``.  The constraint rows are equilibrated first
(:func:`substruct.analysis.modes.krylov.check_inputs`), so ``1e-8 q_1 = 0`` is ``q_1 = 0``; the Krylov
basis is capped by the coordinates the constraints leave free
(:func:`substruct.analysis.modes.krylov.krylov_size`).

**Damped models** (any ``C``): :mod:`substruct.analysis.modes.damped`, to which
:func:`sparse_coupled_modes` dispatches when ``C`` has nonzeros.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from substruct.analysis.modes.krylov import (
    check_inputs,
    constraint_residuals,
    default_shift,
    eliminate,
    free_coordinates,
    DENSE_FREE,
    krylov_size,
    rigid_eigenvalue,
)
from substruct.analysis.errors import AnalysisInputError, singular_model
from substruct.analysis.results import Modes
from substruct.analysis.modes.damped import damped_sparse_modes
from substruct.linalg.definite import SingularPencil, definite_factorization
from substruct.linalg.factorize import Factorize, Solve, factorizer
from substruct.linalg.lanczos import shift_invert_lanczos_deflated
from substruct.linalg.massless import massless_split
from substruct.linalg.nullspace import Elimination
from substruct.linalg.scaling import massless_coordinates, rigid_modes
from substruct.vocabulary import FORMULATIONS, GENERALIZED_INVERSE, KKT, NULL_SPACE

__all__ = [
    "FORMULATIONS",
    "generalized_inverse_modes",
    "has_damping",
    "null_space_modes",
    "sparse_coupled_modes",
]

#: The formulations of :func:`sparse_coupled_modes`.


def _finish(lam: np.ndarray, U: np.ndarray, K: sp.csr_array, M: sp.csr_array,
            A: sp.csr_array, method: str) -> Modes:
    """Rayleigh-Ritz on the Lanczos vectors, normalization, residuals, :class:`Modes`."""
    KU, MU = K @ U, M @ U
    kr, mr = U.T @ KU, U.T @ MU
    lam, rot = sla.eigh((kr + kr.T) / 2, (mr + mr.T) / 2)
    U = U @ rot
    order = np.argsort(lam)
    lam, U = lam[order], U[:, order]
    scale = max(abs(lam).max(initial=0.0), 1e-300)
    lam = np.where(lam < 0, np.where(lam > -1e-8 * scale, 0.0, lam), lam)
    # a rigid-body mode's omega^2 is round-off: zero, as the dense path reports it; a soft
    # mode below the same level (a stiff body on soft springs) keeps its frequency
    lam = np.where(rigid_modes(lam, U, K, M), 0.0, lam)
    big = np.argmax(np.abs(U), axis=0)
    U = U * np.sign(U[big, np.arange(U.shape[1])])
    U = U / np.sqrt(np.einsum("ij,ij->j", U, M @ U))
    omega = np.sqrt(np.maximum(lam, 0.0))
    return Modes(eigenvalues=1j * omega, omega=omega, damping_ratio=np.zeros_like(omega),
                 shapes=U, residual=constraint_residuals(A, U), method=method,
                 solver="sparse")


def null_space_modes(M: sp.sparray, K: sp.sparray, A: sp.sparray | None, n_modes: int, *,
                     sigma: float | None = None, factorization: str | Factorize = "auto",
                     ncv: int | None = None, elimination: Elimination | None = None) -> Modes:
    r"""Lowest ``n_modes`` modes under ``A u = 0`` by master-slave elimination.

    .. math::  u = T p, \quad A T = 0: \qquad
               (T^T K T)\, p = \omega^2 (T^T M T)\, p ,

    solved by ``eigsh`` in shift-invert mode about ``sigma`` (default
    :math:`-10^{-9} \operatorname{tr} K_T / \operatorname{tr} M_T`) with ``OPinv`` from the
    chosen factorization of :math:`T^T (K - \sigma M) T`.  Massless coordinates are preferred
    as slaves, so the reduced mass is definite when every massless coordinate is tied.

    Args:
        M, K: sparse symmetric ``n x n``; ``M`` may be singular on massless coordinates.
        A: ``m x n`` constraint rows (any rank; redundant rows are detected and skipped).
        n_modes: number of modes wanted (fewer than the free coordinates, less one for the
            Krylov basis).
        sigma: the shift.
        factorization: ``"auto"`` (CHOLMOD when scikit-sparse is installed, else SuperLU:
            docs/performance.md), ``"superlu"``, ``"cholmod"`` or a callable
            (:func:`substruct.linalg.factorize.factorizer`).
        ncv: Lanczos basis size (``max(2 k + 1, 20)`` if ``None``), capped by the free
            coordinates (:func:`substruct.analysis.modes.krylov.krylov_size`).
        elimination: a precomputed :func:`~substruct.linalg.nullspace.master_slave` of ``A``.

    Raises:
        ValueError: too few free coordinates for ``n_modes`` and a Krylov basis; bad shapes;
            an empty constraint row.
        AnalysisInputError: the shifted pencil is singular
            (:func:`substruct.linalg.definite.numerically_singular`): a motion with neither
            mass nor stiffness, which would enter every mode shape unseen.
    """
    M, K, A, k = check_inputs(M, K, A, n_modes)
    el = elimination or eliminate(M, A)
    T = sp.csc_array(el.T)
    Mt = sp.csc_array(T.T @ (M @ T))
    split = massless_split(Mt)
    if split.rotated:  # massless combinations of coordinates made coordinates: u = T Q p
        Mt = sp.csc_array(split.mass(Mt))
        T = sp.csc_array(T @ split.Q)
    Kt = sp.csc_array(T.T @ (K @ T))
    Kt, Mt = (Kt + Kt.T) / 2, (Mt + Mt.T) / 2
    try:
        size = krylov_size(k, Kt.shape[0] - split.count, ncv)
    except AnalysisInputError:
        if Kt.shape[0] > DENSE_FREE:
            raise
        size = 0                        # the reduced pencil is small: solved densely
    s = default_shift(Kt, Mt) if sigma is None else float(sigma)
    try:
        solve = definite_factorization(factorizer(factorization, spd=True),
                                       sp.csc_array(Kt - s * Mt))
    except SingularPencil:
        raise singular_model("K - sigma M of the free coordinates is singular") from None
    if not size:
        P = small_pencil_modes(Kt, Mt, k, s)
        return _finish(np.zeros(P.shape[1]), T @ P, K, M, A, "null-space/sparse")
    v0 = np.random.default_rng(0).standard_normal(Kt.shape[0])
    lam, P = shift_invert_lanczos_deflated(Kt, Mt, k, s, solve, rigid_eigenvalue(Kt, Mt), v0,
                                           size)
    return _finish(lam, T @ P, K, M, A, "null-space/sparse")


def small_pencil_modes(K: sp.sparray, M: sp.sparray, k: int, sigma: float) -> np.ndarray:
    r"""The vectors of the lowest ``k`` finite eigenvalues of a pencil of at most
    :data:`~substruct.analysis.modes.krylov.DENSE_FREE` coordinates, by a dense ``eigh`` in the
    inverse form, definite on the right whatever the mass,

    .. math::  M p = \mu\, (K - \sigma M)\, p, \qquad \omega^2 = \sigma + 1/\mu

    (the largest :math:`\mu` the lowest modes; a massless direction has :math:`\mu = 0`
    and is not kept).  The eigenvalues follow from the Rayleigh-Ritz step of the caller."""
    mu, V = sla.eigh(sp.csr_array(M).toarray(), sp.csr_array(K - sigma * M).toarray())
    order = np.argsort(mu)[::-1]
    finite = order[mu[order] > 1e3 * np.finfo(float).eps * max(mu.max(initial=0.0), 0.0)]
    return V[:, finite[:k]]


def _saddle(B: sp.sparray, Ak: sp.csr_array, scale: float) -> Solve:
    r"""The first block of the solution of :math:`[B, s A_k^T; s A_k, 0] [y; z] = [f; 0]`,
    factorized once (:func:`substruct.linalg.factorize.superlu_saddle`)."""
    n, r = B.shape[0], Ak.shape[0]
    big = sp.block_array([[B, scale * Ak.T], [scale * Ak, None]], format="csc")
    lu = factorizer("saddle")(big)
    pad = np.zeros(r)

    def solve(f: np.ndarray) -> np.ndarray:
        return lu(np.concatenate([np.asarray(f, dtype=float).ravel(), pad]))[:n]

    return solve


def generalized_inverse_modes(M: sp.sparray, K: sp.sparray, A: sp.sparray | None,
                              n_modes: int, *, sigma: float | None = None, project: bool = True,
                              ncv: int | None = None, elimination: Elimination | None = None
                              ) -> Modes:
    r"""Lowest ``n_modes`` modes under ``A u = 0``: shift-invert of the paper's :math:`M^* K`.

    .. math::

        \operatorname{OP} = P\, (M^* K - \sigma I)^{-1}\big|_{\operatorname{null} A}, \qquad
        (M^* K - \sigma I)^{-1} M^{-1} f = y : \
        \begin{bmatrix} K - \sigma M & A_k^T \\ A_k & 0 \end{bmatrix}
        \begin{bmatrix} y \\ \mu \end{bmatrix} = \begin{bmatrix} f \\ 0 \end{bmatrix},

    with :math:`M^* = P M_d^{-1}` (eq 10) and the projector
    :math:`P = I - M_d^{-1} A^T (A M_d^{-1} A^T)^+ A` applied through
    :math:`[M_d, A_k^T; A_k, 0]`.  ``A_k`` are independent rows of ``A`` (found by
    :func:`~substruct.linalg.nullspace.master_slave`; the pseudo-inverse of eq 5 and the reduced
    set give the same ``P``).  The saddle-point matrices are indefinite: they are factorized by
    SuperLU (``"saddle"`` of the registry).  ``project`` switches the restriction by ``P`` off
    (one factorization fewer; ``KKT`` output already lies in :math:`\operatorname{null}(A)` up
    to round-off).

    Returns ``eigsh``'s Ritz pairs after a Rayleigh-Ritz step, as :class:`Modes`.

    Raises:
        ValueError: too few free coordinates for ``n_modes`` and a Krylov basis; bad shapes;
            an empty constraint row.
        AnalysisInputError: the shifted pencil is singular
            (:func:`substruct.linalg.definite.numerically_singular`): a motion with neither
            mass nor stiffness, which would enter every mode shape unseen.
    """
    M, K, A, k = check_inputs(M, K, A, n_modes)
    split = massless_split(M)
    if split.rotated:  # massless combinations of coordinates made coordinates: u = Q p
        Q = split.Q
        rot = generalized_inverse_modes(split.mass(M), sp.csr_array(Q.T @ (K @ Q)),
                                        sp.csr_array(A @ Q), k, sigma=sigma, project=project,
                                        ncv=ncv)
        U = Q @ rot.shapes
        return dataclasses.replace(rot, shapes=U, residual=constraint_residuals(A, U))
    n = K.shape[0]
    massless = massless_coordinates(M)
    el = elimination or eliminate(M, A)
    size = krylov_size(k, free_coordinates(el, M), ncv)
    Ak = sp.csr_array(A[el.kept_rows])  # rows of unit 2-norm (check_inputs)
    kscale = float(np.mean(abs(K.diagonal()))) or 1.0
    s = default_shift(K, M) if sigma is None else float(sigma)
    try:   # the solves stay in null(A): the test is of the pencil there
        kkt = definite_factorization(lambda B: _saddle(B, Ak, kscale),
                                     sp.csc_array(K - s * M))
    except SingularPencil:
        raise singular_model("K - sigma M on the constraints' null space is singular") from None
    solve: Solve = kkt
    if project and Ak.shape[0]:
        Md = sp.csc_array(M + sp.diags_array(massless.astype(float)) *
                          (float(np.mean(abs(M.diagonal()))) or 1.0))
        mscale = float(np.mean(abs(Md.diagonal()))) or 1.0
        proj_solve = _saddle(Md, Ak, mscale)

        def projected(f: np.ndarray) -> np.ndarray:
            return proj_solve(Md @ kkt(f))

        solve = projected
    rng = np.random.default_rng(0)
    v0 = kkt(M @ rng.standard_normal(n))  # a start in null(A)
    lam, U = shift_invert_lanczos_deflated(K, M, k, s, solve, rigid_eigenvalue(K, M), v0, size)
    return _finish(lam, U, K, M, A, "generalized-inverse/sparse")


def has_damping(C: sp.sparray | np.ndarray | None) -> bool:
    """Whether ``C`` has a nonzero entry."""
    if C is None:
        return False
    Cs = sp.csr_array(C)
    return bool(Cs.nnz and np.any(Cs.data != 0))


def sparse_coupled_modes(M: sp.sparray, K: sp.sparray, A: sp.sparray | None, n_modes: int,
                         method: str = NULL_SPACE, *, C: sp.sparray | None = None,
                         **options: Any) -> Modes:
    """Lowest ``n_modes`` modes under ``A u = 0``, sparse; damped when ``C`` has nonzeros.

    Undamped (``C`` ``None`` or zero), ``method``: ``null-space`` (:func:`null_space_modes`,
    the default: the smallest factorization, SPD so CHOLMOD can serve),
    ``generalized-inverse`` (:func:`generalized_inverse_modes`, the paper's projected
    operator in scalable form) or ``kkt`` (the same saddle-point shift-invert without the
    projection: Lagrange multipliers).  ``options`` go to the chosen function.

    Damped: :func:`substruct.analysis.modes.damped.damped_sparse_modes`, ``method``
    ``null-space`` or ``kkt`` (the formulation); ``generalized-inverse`` is solved by the
    null-space pencil too (the projected state-space form of eqs 28-34 needs the dense
    projector), so it is not an independent check of ``null-space``: ``kkt`` is.
    ``ncv``, ``extra`` and ``elimination`` of ``options`` go to it; the others (``sigma`` in
    units of ``omega^2``, ``factorization``) belong to the undamped functions and are ignored.

    The method string of the result is ``"<method>/sparse"``, its ``solver`` ``"sparse"``
    (``"sparse-damped"`` for a damped model).
    """
    if method not in FORMULATIONS:
        raise ValueError(f"unknown method {method!r}; expected one of "
                         f"{', '.join(map(repr, FORMULATIONS))}")
    if has_damping(C):
        keep = {k: v for k, v in options.items() if k in ("ncv", "extra", "elimination")}
        modes = damped_sparse_modes(M, C, K, A, n_modes,
                                    formulation=KKT if method == KKT else NULL_SPACE,
                                    **keep)
    elif method == NULL_SPACE:
        modes = null_space_modes(M, K, A, n_modes, **options)
    else:
        modes = generalized_inverse_modes(M, K, A, n_modes, project=method != KKT, **options)
    modes.method = f"{method}/sparse"
    return modes
