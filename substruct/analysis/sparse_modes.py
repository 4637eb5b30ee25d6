r"""Coupled modes of large constrained models, undamped or damped, with no dense ``n x n`` matrix.

The lowest ``k`` solutions of

.. math::  K u = \omega^2 M u + A^T \mu, \qquad A u = 0,

by shift-invert Lanczos (``scipy.sparse.linalg.eigsh``) about a shift :math:`\sigma < 0`, with an
``OPinv`` built here from a sparse factorization chosen by the caller (never one that ``eigsh``
makes for itself, DESIGN.md section 6).  Two independent paths:

**Null space** (:func:`null_space_modes`): a sparse basis ``T`` of :math:`\operatorname{null}(A)`
by master-slave elimination (:func:`master_slave`), :math:`u = T p`, and the reduced pencil

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

Both return :class:`substruct.analysis.dense_modes.Modes` with real mode shapes (undamped), ``u^T M u = 1``.

**Damped models** (any ``C``): :mod:`substruct.analysis.sparse_damped`, to which
:func:`sparse_coupled_modes` dispatches when ``C`` has nonzeros.
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass
from typing import Callable

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from substruct.analysis.dense_modes import Modes

__all__ = [
    "FACTORIZATIONS",
    "Elimination",
    "factorizer",
    "master_slave",
    "null_space_modes",
    "generalized_inverse_modes",
    "sparse_coupled_modes",
    "has_damping",
    "SPARSE_METHODS",
]

Solve = Callable[[np.ndarray], np.ndarray]
Factorize = Callable[[sp.csc_array], Solve]

#: Names accepted for ``factorization``: ``"auto"`` is CHOLMOD when scikit-sparse is importable
#: (symmetric positive definite matrices only), else SuperLU.
FACTORIZATIONS = ("superlu", "cholmod", "auto")


# ----------------------------------------------------------------------------- factorizations


def _superlu(A: sp.sparray) -> Solve:
    """SuperLU with the ``MMD_AT_PLUS_A`` ordering and partial pivoting (any ``A``)."""
    lu = spla.splu(sp.csc_matrix(A), permc_spec="MMD_AT_PLUS_A")
    return lu.solve


def _superlu_spd(A: sp.sparray) -> Solve:
    """SuperLU in symmetric mode for symmetric positive definite ``A``: ``MMD_AT_PLUS_A``
    ordering, diagonal pivots (``diag_pivot_thresh=0``, stable for SPD).  Same fill as with
    partial pivoting, 5 times faster on 3D elasticity (30k DOF: 14 s instead of 80 s)."""
    lu = spla.splu(sp.csc_matrix(A), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                   options={"SymmetricMode": True})
    return lu.solve


def _cholmod(A: sp.sparray) -> Solve:
    """CHOLMOD supernodal Cholesky (scikit-sparse), for symmetric positive definite ``A``."""
    from sksparse.cholmod import cholesky  # optional dependency
    factor = cholesky(sp.csc_matrix(A))
    return factor


def _has_cholmod() -> bool:
    try:
        import sksparse.cholmod  # noqa: F401
    except ImportError:
        return False
    return True


def factorizer(factorization: str | Factorize = "auto", spd: bool = True) -> Factorize:
    """A factorization ``A -> (b -> A^{-1} b)`` by name, or the callable given.

    Args:
        factorization: ``"superlu"`` (always available; symmetric mode with diagonal pivots
            when ``spd``, partial pivoting otherwise), ``"cholmod"`` (needs scikit-sparse),
            ``"auto"`` (CHOLMOD if importable and ``spd``, else SuperLU), or a callable.
        spd: whether the matrices will be symmetric positive definite (CHOLMOD needs it).
    """
    if callable(factorization):
        return factorization
    if factorization == "superlu":
        return _superlu_spd if spd else _superlu
    if factorization == "cholmod":
        if not spd:
            raise ValueError("CHOLMOD needs a symmetric positive definite matrix; the "
                             "saddle-point (KKT) systems need 'superlu'")
        if not _has_cholmod():
            raise ValueError("factorization 'cholmod' needs scikit-sparse (pip install "
                             "scikit-sparse, with libsuitesparse-dev)")
        return _cholmod
    if factorization == "auto":
        if spd:
            return _cholmod if _has_cholmod() else _superlu_spd
        return _superlu
    raise ValueError(f"unknown factorization {factorization!r}; expected one of "
                     f"{', '.join(FACTORIZATIONS)} or a callable")


# --------------------------------------------------------------------- master-slave elimination


@dataclass(frozen=True)
class Elimination:
    r"""A sparse basis of :math:`\operatorname{null}(A)` by master-slave elimination.

    .. math::  u = T u_m, \qquad A T = 0, \qquad
               T = \Pi \begin{bmatrix} I \\ -A_s^{-1} A_m \end{bmatrix}

    Attributes:
        T: sparse ``n x (n - rank)``; its columns are the masters, in ascending order.
        masters: the coordinates kept (``T[masters] = I``).
        slaves: one eliminated coordinate per independent row, in ``kept_rows`` order.
        kept_rows: an independent subset of the rows of ``A`` (``rank`` of them).
        dropped_rows: rows that are combinations of the kept ones (redundant).
    """

    T: sp.csc_array
    masters: np.ndarray
    slaves: np.ndarray
    kept_rows: np.ndarray
    dropped_rows: np.ndarray

    @property
    def rank(self) -> int:
        """Number of independent constraints."""
        return int(self.slaves.size)


def master_slave(A: sp.sparray | np.ndarray, prefer: np.ndarray | None = None,
                 rtol: float = 1e-10, pivot: float = 0.1) -> Elimination:
    r"""Eliminate one *slave* coordinate per independent constraint row (sparse Gauss-Jordan).

    Rows are taken in order.  Each row, scaled to unit largest entry, has the expressions of
    the slaves chosen so far substituted into it; if what remains is below ``rtol`` the row is
    a combination of the earlier rows (dropped), otherwise its slave is chosen among the
    entries of magnitude at least ``pivot`` times the largest (threshold pivoting), preferring
    coordinates flagged in ``prefer`` (e.g. massless ones), then the largest:

    .. math::  u_s = -\sum_{j \ne s} \frac{a_j}{a_s} u_j .

    Earlier expressions that used ``u_s`` are updated, so every slave is a combination of
    masters only.  A node-to-node tie ``u_a - u_b`` costs ``O(1)``.

    Args:
        A: ``m x n`` constraint matrix (any rank).
        prefer: boolean mask over the ``n`` coordinates to pick as slaves when possible.
        rtol: relative size under which a reduced row counts as zero (dependent).
        pivot: threshold-pivoting fraction.
    """
    A = sp.csr_array(A, dtype=float)
    m, n = A.shape
    pref = np.zeros(n, dtype=bool) if prefer is None else np.asarray(prefer, dtype=bool)
    expr: dict[int, dict[int, float]] = {}
    users: dict[int, set[int]] = defaultdict(set)
    kept, dropped, slaves = [], [], []
    for i in range(m):
        lo, hi = A.indptr[i], A.indptr[i + 1]
        cols, vals = A.indices[lo:hi], A.data[lo:hi]
        scale = np.abs(vals).max(initial=0.0)
        if scale == 0.0:
            dropped.append(i)
            continue
        row: dict[int, float] = defaultdict(float)
        for j, v in zip(cols.tolist(), (vals / scale).tolist()):
            if j in expr:
                for k, w in expr[j].items():
                    row[k] += v * w
            else:
                row[j] += v
        row = {j: v for j, v in row.items() if abs(v) > rtol}
        if not row:
            dropped.append(i)
            continue
        big = max(abs(v) for v in row.values())
        s = max((j for j, v in row.items() if abs(v) >= pivot * big),
                key=lambda j: (pref[j], abs(row[j]), -j))
        a_s = row.pop(s)
        e = {j: -v / a_s for j, v in row.items()}
        for t in users.pop(s, ()):  # s was a master of earlier slaves
            et = expr[t]
            c = et.pop(s)
            for j, v in e.items():
                prev = et.get(j, 0.0)
                w = prev + c * v
                if abs(w) > 1e-14 * (abs(prev) + abs(c * v)):
                    et[j] = w
                    users[j].add(t)
                else:  # exact cancellation
                    et.pop(j, None)
                    users[j].discard(t)
        expr[s] = e
        for j in e:
            users[j].add(s)
        kept.append(i)
        slaves.append(s)
    slaves_a = np.asarray(slaves, dtype=np.int64)
    is_slave = np.zeros(n, dtype=bool)
    is_slave[slaves_a] = True
    masters = np.flatnonzero(~is_slave)
    col = np.full(n, -1, dtype=np.int64)
    col[masters] = np.arange(masters.size)
    r, c, v = [masters], [np.arange(masters.size)], [np.ones(masters.size)]
    for s, e in expr.items():
        if e:
            r.append(np.full(len(e), s))
            c.append(col[np.fromiter(e.keys(), dtype=np.int64, count=len(e))])
            v.append(np.fromiter(e.values(), dtype=float, count=len(e)))
    T = sp.csc_array((np.concatenate(v), (np.concatenate(r), np.concatenate(c))),
                     shape=(n, masters.size))
    return Elimination(T=T, masters=masters, slaves=slaves_a,
                       kept_rows=np.asarray(kept, dtype=np.int64),
                       dropped_rows=np.asarray(dropped, dtype=np.int64))


# ---------------------------------------------------------------------------------- helpers


def _massless(M: sp.csr_array) -> np.ndarray:
    return np.asarray(abs(M).sum(axis=1)).ravel() == 0.0


def _stiffness_over_mass(K: sp.sparray, M: sp.sparray) -> float:
    r""":math:`\operatorname{tr} K / \operatorname{tr} M`, the scale of the eigenvalues."""
    return max(abs(K.diagonal()).sum() / max(abs(M.diagonal()).sum(), 1e-300), 1e-300)


def _default_shift(K: sp.sparray, M: sp.sparray) -> float:
    r"""A small negative shift, :math:`-10^{-9} \operatorname{tr} K / \operatorname{tr} M`,
    so that ``K - sigma M`` is definite even with rigid-body modes."""
    return -1e-9 * _stiffness_over_mass(K, M)


def _norm2(A: sp.csr_array) -> float:
    """The spectral norm of a sparse ``A`` (from ``A A^T``)."""
    m = A.shape[0]
    if m == 0:
        return 1.0
    AAt = sp.csr_array(A @ A.T)
    if m <= 400:
        return float(np.sqrt(max(np.linalg.eigvalsh(AAt.toarray()).max(), 0.0))) or 1.0
    lam = spla.eigsh(AAt, k=1, which="LA", tol=1e-4, return_eigenvectors=False)[0]
    return float(np.sqrt(max(lam, 0.0))) or 1.0


def _finish(lam: np.ndarray, U: np.ndarray, K: sp.sparray, M: sp.sparray, A: sp.csr_array,
            method: str) -> Modes:
    """Rayleigh-Ritz on the Lanczos vectors, normalization, residuals, :class:`Modes`."""
    KU, MU = K @ U, M @ U
    kr, mr = U.T @ KU, U.T @ MU
    lam, rot = sla.eigh((kr + kr.T) / 2, (mr + mr.T) / 2)
    U = U @ rot
    order = np.argsort(lam)
    lam, U = lam[order], U[:, order]
    scale = max(abs(lam).max(initial=0.0), 1e-300)
    lam = np.where(lam < 0, np.where(lam > -1e-8 * scale, 0.0, lam), lam)
    # a rigid-body mode's omega^2 is round-off of the size eps |K| / |M|: zero, as the dense
    # path reports it (a free-free rod of 600 coordinates gave omega = 1e-5 rad/s otherwise)
    lam = np.where(lam <= 1e-12 * _stiffness_over_mass(K, M), 0.0, lam)
    big = np.argmax(np.abs(U), axis=0)
    U = U * np.sign(U[big, np.arange(U.shape[1])])
    U = U / np.sqrt(np.einsum("ij,ij->j", U, M @ U))
    omega = np.sqrt(np.maximum(lam, 0.0))
    if A.shape[0]:
        res = np.linalg.norm(A @ U, axis=0) / (_norm2(A) * np.linalg.norm(U, axis=0))
    else:
        res = np.zeros(U.shape[1])
    return Modes(eigenvalues=1j * omega, omega=omega, damping_ratio=np.zeros_like(omega),
                 shapes=U, residual=res, method=method)


def _check(M, K, A, n_modes) -> tuple[sp.csr_array, sp.csr_array, sp.csr_array, int]:
    K = sp.csr_array(K, dtype=float)
    n = K.shape[0]
    M = sp.csr_array(M, dtype=float)
    if M.shape != (n, n):
        raise ValueError(f"M has shape {M.shape}, K has {K.shape}")
    A = sp.csr_array((0, n)) if A is None else sp.csr_array(A, dtype=float)
    if A.shape[1] != n:
        raise ValueError(f"A has {A.shape[1]} columns for {n} coordinates")
    k = int(n_modes)
    if k < 1:
        raise ValueError(f"n_modes must be >= 1, got {n_modes!r}")
    return M, K, A, k


def _eigsh(K, M, k: int, sigma: float, solve: Solve, v0: np.ndarray, ncv: int | None
           ) -> tuple[np.ndarray, np.ndarray]:
    n = K.shape[0]
    op = spla.LinearOperator((n, n), matvec=solve, dtype=float)
    return spla.eigsh(K, k=k, M=M, sigma=sigma, which="LM", OPinv=op, v0=v0, ncv=ncv)


# ---------------------------------------------------------------------------------- the paths


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
        n_modes: number of modes wanted (``< n - rank(A)``).
        sigma: the shift.
        factorization: ``"auto"`` (CHOLMOD when scikit-sparse is installed, else SuperLU:
            docs/performance.md), ``"superlu"``, ``"cholmod"`` or a callable
            (:func:`factorizer`).
        ncv: Lanczos basis size (``eigsh`` default if ``None``).
        elimination: a precomputed :func:`master_slave` of ``A``.
    """
    M, K, A, k = _check(M, K, A, n_modes)
    el = elimination or master_slave(A, prefer=_massless(M))
    T = sp.csc_array(el.T)
    Kt = sp.csc_array(T.T @ (K @ T))
    Mt = sp.csc_array(T.T @ (M @ T))
    Kt, Mt = (Kt + Kt.T) / 2, (Mt + Mt.T) / 2
    if k >= Kt.shape[0]:
        raise ValueError(f"{k} modes asked of a constrained model with {Kt.shape[0]} "
                         f"degrees of freedom (use the dense coupled_modes)")
    s = _default_shift(Kt, Mt) if sigma is None else float(sigma)
    solve = factorizer(factorization, spd=True)(sp.csc_array(Kt - s * Mt))
    v0 = np.random.default_rng(0).standard_normal(Kt.shape[0])
    lam, P = _eigsh(Kt, Mt, k, s, solve, v0, ncv)
    return _finish(lam, T @ P, K, M, A, "null-space/sparse")


def _saddle(B: sp.sparray, Ak: sp.csr_array, scale: float) -> Solve:
    """SuperLU of ``[B, s A_k^T; s A_k, 0]``; returns ``f -> first block of the solution``.

    Symmetric mode with threshold pivoting (``diag_pivot_thresh=0.1``): diagonal pivots where
    they are large enough, off-diagonal ones for the zero block; 4 times faster than partial
    pivoting on 3D elasticity with ties (10k DOF), same residual.
    """
    n, r = B.shape[0], Ak.shape[0]
    big = sp.block_array([[B, scale * Ak.T], [scale * Ak, None]], format="csc")
    lu = spla.splu(sp.csc_matrix(big), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.1,
                   options={"SymmetricMode": True})
    pad = np.zeros(r)

    def solve(f: np.ndarray) -> np.ndarray:
        return lu.solve(np.concatenate([np.asarray(f, dtype=float).ravel(), pad]))[:n]

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
    :func:`master_slave`; the pseudo-inverse of eq 5 and the reduced set give the same ``P``).
    The saddle-point matrices are indefinite: they are factorized by SuperLU.  ``project``
    switches the restriction by ``P`` off (one factorization fewer; ``KKT`` output already
    lies in :math:`\operatorname{null}(A)` up to round-off).

    Returns ``eigsh``'s Ritz pairs after a Rayleigh-Ritz step, as :class:`Modes`.
    """
    M, K, A, k = _check(M, K, A, n_modes)
    n = K.shape[0]
    el = elimination or master_slave(A, prefer=_massless(M))
    if k >= n - el.rank:
        raise ValueError(f"{k} modes asked of a constrained model with {n - el.rank} "
                         f"degrees of freedom (use the dense coupled_modes)")
    Ak = sp.csr_array(A[el.kept_rows])
    Ak = sp.csr_array(sp.diags_array(1.0 / abs(Ak).max(axis=1).toarray().ravel()) @ Ak) \
        if Ak.shape[0] else Ak
    kscale = float(np.mean(abs(K.diagonal()))) or 1.0
    s = _default_shift(K, M) if sigma is None else float(sigma)
    kkt = _saddle(sp.csc_array(K - s * M), Ak, kscale)
    if project and Ak.shape[0]:
        massless = _massless(M)
        Md = sp.csc_array(M + sp.diags_array(massless.astype(float)) *
                          (float(np.mean(abs(M.diagonal()))) or 1.0))
        mscale = float(np.mean(abs(Md.diagonal()))) or 1.0
        proj_solve = _saddle(Md, Ak, mscale)

        def solve(f: np.ndarray) -> np.ndarray:
            y = kkt(f)
            return proj_solve(Md @ y)
    else:
        solve = kkt
    rng = np.random.default_rng(0)
    v0 = kkt(M @ rng.standard_normal(n))  # a start in null(A)
    lam, U = _eigsh(K, M, k, s, solve, v0, ncv)
    return _finish(lam, U, K, M, A, "generalized-inverse/sparse")


#: The formulations of :func:`sparse_coupled_modes`.
SPARSE_METHODS = ("null-space", "generalized-inverse", "kkt")


def has_damping(C: sp.sparray | np.ndarray | None) -> bool:
    """Whether ``C`` has a nonzero entry."""
    if C is None:
        return False
    C = sp.csr_array(C)
    return bool(C.nnz and np.any(C.data != 0))


def sparse_coupled_modes(M: sp.sparray, K: sp.sparray, A: sp.sparray | None, n_modes: int,
                         method: str = "null-space", *, C: sp.sparray | None = None,
                         **options) -> Modes:
    """Lowest ``n_modes`` modes under ``A u = 0``, sparse; damped when ``C`` has nonzeros.

    Undamped (``C`` ``None`` or zero), ``method``: ``"null-space"`` (:func:`null_space_modes`,
    the default: the smallest factorization, SPD so CHOLMOD can serve),
    ``"generalized-inverse"`` (:func:`generalized_inverse_modes`, the paper's projected
    operator in scalable form) or ``"kkt"`` (the same saddle-point shift-invert without the
    projection: Lagrange multipliers).  ``options`` go to the chosen function.

    Damped: :func:`substruct.analysis.sparse_damped.damped_sparse_modes`, ``method`` ``"null-space"``
    or ``"kkt"`` (the formulation); ``"generalized-inverse"`` is solved by the null-space
    pencil too (the projected state-space form of eqs 28-34 needs the dense projector), so it
    is not an independent check of ``"null-space"``: ``"kkt"`` is.  ``ncv``, ``extra`` and
    ``elimination`` of ``options`` go to it; the others (``sigma`` in units of ``omega^2``,
    ``factorization``) belong to the undamped functions and are ignored.

    The method string of the result is ``"<method>/sparse"``.
    """
    if method not in SPARSE_METHODS:
        raise ValueError(f"unknown method {method!r}; expected one of "
                         f"{', '.join(map(repr, SPARSE_METHODS))}")
    if has_damping(C):
        from substruct.analysis.sparse_damped import damped_sparse_modes
        keep = {k: v for k, v in options.items() if k in ("ncv", "extra", "elimination")}
        modes = damped_sparse_modes(M, C, K, A, n_modes,
                                    formulation="kkt" if method == "kkt" else "null-space",
                                    **keep)
    elif method == "null-space":
        modes = null_space_modes(M, K, A, n_modes, **options)
    else:
        modes = generalized_inverse_modes(M, K, A, n_modes, project=method != "kkt", **options)
    modes.method = f"{method}/sparse"
    return modes
