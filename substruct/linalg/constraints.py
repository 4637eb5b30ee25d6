"""Linear constraints ``A q = b`` (paper eqs 2-3, 25): rank, consistency and null-space bases.

The constraint matrix may hold redundant rows (the same compatibility twice, a user constraint
implied by the connections).  The generalized-inverse formulas accept that as it is, through the
Moore-Penrose inverse; the Lagrange (KKT) and null-space formulations need an independent set of
rows.  A nonhomogeneous set is *consistent* when every right-hand side lies in the range of ``A``;
an inconsistent set has no solution at all and is reported, never least-squared.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

__all__ = [
    "ConstraintError",
    "IndependentRows",
    "check_consistent",
    "dense",
    "independent_rows",
    "null_space_basis",
    "particular_solution",
]

#: Largest number of entries of a dense copy of ``A`` made without complaint.
DENSE_LIMIT = 50_000_000


class ConstraintError(ValueError):
    """Constraints that cannot hold (inconsistent right-hand sides)."""


def dense(mat: sp.sparray | np.ndarray) -> np.ndarray:
    """Dense copy of a matrix known to be small."""
    if sp.issparse(mat):
        if mat.shape[0] * mat.shape[1] > DENSE_LIMIT:
            raise MemoryError(f"refusing a dense {mat.shape} copy")
        return mat.toarray()
    return np.asarray(mat)


@dataclass(frozen=True)
class IndependentRows:
    """An independent subset of the rows of ``A``.

    Attributes:
        keep: indices of the kept rows (``rank`` of them).
        rank: numerical rank of ``A``.
        combination: ``(m - rank, rank)`` matrix ``W`` with ``A[dropped] = W A[keep]``.
        dropped: indices of the redundant rows.
    """

    keep: np.ndarray
    rank: int
    combination: np.ndarray
    dropped: np.ndarray


def _row_scale(A: np.ndarray) -> np.ndarray:
    norms = np.linalg.norm(A, axis=1)
    norms[norms == 0.0] = 1.0
    return norms


def independent_rows(A: sp.sparray | np.ndarray, rtol: float = 1e-10) -> IndependentRows:
    r"""Pick ``rank(A)`` independent rows of ``A`` by QR with column pivoting of ``A^T``.

    .. math::  A^T \Pi = Q R, \qquad \operatorname{rank} A = \#\{i : |R_{ii}| > r_{tol} |R_{11}|\}

    Rows are scaled to unit norm first, so that the choice does not depend on units.
    """
    Ad = dense(A)
    m = Ad.shape[0]
    if m == 0:
        return IndependentRows(np.zeros(0, int), 0, np.zeros((0, 0)), np.zeros(0, int))
    As = Ad / _row_scale(Ad)[:, None]
    _, R, piv = sla.qr(As.T, mode="economic", pivoting=True)
    diag = np.abs(np.diag(R))
    rank = int(np.sum(diag > rtol * diag[0])) if diag.size and diag[0] > 0 else 0
    keep = np.sort(piv[:rank])
    dropped = np.sort(piv[rank:])
    if dropped.size and rank:
        W, *_ = np.linalg.lstsq(Ad[keep].T, Ad[dropped].T, rcond=None)
        W = W.T
    else:
        W = np.zeros((dropped.size, rank))
    return IndependentRows(keep, rank, W, dropped)


def check_consistent(A: sp.sparray | np.ndarray, rhs: sp.sparray | np.ndarray,
                     rows: IndependentRows | None = None, labels: list[str] | None = None,
                     rtol: float = 1e-8) -> IndependentRows:
    r"""Check that ``A q = rhs`` can hold: every redundant row's right-hand side is the same
    combination of the kept rows' right-hand sides as its left-hand side.

    .. math::  A_{d} = W A_{k} \;\Rightarrow\; \text{rhs}_{d} = W\, \text{rhs}_{k}

    ``rhs`` is ``b`` (an ``m``-vector) or ``R`` (``m x k``, eq 14).  Raises
    :class:`ConstraintError` naming the first offending row.
    """
    rows = independent_rows(A) if rows is None else rows
    Rd = dense(rhs)
    Rd = Rd.reshape(Rd.shape[0], -1)
    if rows.dropped.size == 0:
        return rows
    predicted = rows.combination @ Rd[rows.keep]
    actual = Rd[rows.dropped]
    scale = max(np.abs(Rd).max(), 1e-300)
    err = np.abs(actual - predicted).max(axis=1) / scale
    bad = np.flatnonzero(err > rtol)
    if bad.size:
        i = int(rows.dropped[bad[0]])
        name = labels[i] if labels is not None else f"row {i}"
        raise ConstraintError(
            f"inconsistent constraints: {name} is a combination of the other rows but its "
            f"right-hand side differs by {err[bad[0]]:.3g} (relative)")
    return rows


def null_space_basis(A: sp.sparray | np.ndarray, rtol: float = 1e-10) -> np.ndarray:
    r"""Orthonormal basis ``N`` of ``null(A)`` (``A N = 0``, ``N^T N = I``) by the SVD.

    .. math::  A = U \Sigma V^T, \qquad N = V_{:, r:}

    Dense: for the small and reduced models of the paper.  Rows are scaled to unit norm first.
    """
    Ad = dense(A)
    n = Ad.shape[1]
    if Ad.shape[0] == 0:
        return np.eye(n)
    As = Ad / _row_scale(Ad)[:, None]
    return sla.null_space(As, rcond=rtol)


def particular_solution(A: sp.sparray | np.ndarray, rhs: np.ndarray,
                        rows: IndependentRows | None = None) -> np.ndarray:
    r"""Minimum-norm ``x`` with ``A x = rhs`` (rhs consistent): ``x = A_k^T (A_k A_k^T)^{-1} rhs_k``."""
    rows = independent_rows(A) if rows is None else rows
    Ad = dense(A)[rows.keep]
    rk = np.asarray(dense(rhs)).reshape(dense(A).shape[0], -1)[rows.keep]
    if rows.rank == 0:
        return np.zeros((Ad.shape[1], rk.shape[1]))
    return Ad.T @ np.linalg.solve(Ad @ Ad.T, rk)
