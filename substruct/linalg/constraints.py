r"""Linear constraints ``A q = b`` (paper eqs 2-3, 25): rank, independent rows, consistency.

The constraint matrix may hold redundant rows (the same compatibility twice, a user constraint
implied by the connections).  The generalized-inverse formulas accept that as it is, through the
Moore-Penrose inverse; the Lagrange (KKT) and null-space formulations need an independent set of
rows.  A nonhomogeneous set is *consistent* when every right-hand side lies in the range of ``A``;
an inconsistent set has no solution at all and is reported, never least-squared.

Every decision here is taken on equilibrated rows and mass-scaled columns
(:mod:`substruct.linalg.scaling`), :math:`\tilde A = D A C`: it depends neither on the scale of a
row (``1e-8 q_1 = 0`` is ``q_1 = 0``) nor on the units of a coordinate.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from substruct.linalg.dense import dense
from substruct.linalg.scaling import row_scale

__all__ = [
    "ConstraintError",
    "IndependentRows",
    "RANK_RTOL",
    "check_consistent",
    "independent_rows",
    "particular_solution",
    "pinv_sym",
]

#: Relative size of a pivot of the equilibrated rows under which a row counts as dependent.
RANK_RTOL = 1e-10


class ConstraintError(ValueError):
    """Constraints that cannot hold (inconsistent right-hand sides)."""


@dataclass(frozen=True)
class IndependentRows:
    """An independent subset of the rows of ``A``.

    Attributes:
        keep: indices of the kept rows (``rank`` of them), ascending.
        rank: numerical rank of ``A``.
        combination: ``(m - rank, rank)`` matrix ``W`` with ``A[dropped] = W A[keep]``.
        dropped: indices of the redundant rows, ascending.
    """

    keep: np.ndarray
    rank: int
    combination: np.ndarray
    dropped: np.ndarray


def independent_rows(A: sp.sparray | sp.spmatrix | np.ndarray, rtol: float = RANK_RTOL,
                     col_scale: np.ndarray | None = None) -> IndependentRows:
    r"""Pick ``rank(A)`` independent rows of ``A`` by QR with column pivoting.

    .. math::  \tilde A = D A C, \qquad \tilde A^T \Pi = Q R, \qquad
               \operatorname{rank} A = \#\{i : |R_{ii}| > r_{tol} |R_{11}|\}

    Only the columns with a nonzero entry enter the dense QR (a tie of 1,200 rows on a
    100k-coordinate model touches a few thousand).  ``D`` scales every row to unit 2-norm
    (powers of two), safely for tiny rows
    (:func:`substruct.linalg.scaling.row_scale`); ``C`` is ``col_scale`` (e.g.
    :func:`substruct.linalg.scaling.mass_column_scale`), the identity if ``None``.  The
    combination ``W`` of the dropped rows is solved on the well-conditioned :math:`\tilde A` and
    returned for ``A`` itself: :math:`W = D_d^{-1} \tilde W D_k`.

    A row that is exactly zero is dependent (``0 = 0 \cdot A_k``) and is listed in
    ``dropped``, with a zero combination, so that a nonzero right-hand side on it is reported
    by :func:`check_consistent`; the analyses refuse such rows at their entry
    (:func:`substruct.linalg.scaling.equilibrate`).

    Args:
        A: ``m x n`` constraint matrix.
        rtol: relative pivot size under which a row is dependent.
        col_scale: ``n`` positive column factors, or ``None``.
    """
    scale_c = None if col_scale is None else np.asarray(col_scale, dtype=float)
    if sp.issparse(A):  # only the columns the rows touch: the rank and W are those of A
        As_ = sp.csr_array(A)
        cols = np.unique(As_.indices[As_.data != 0]) if As_.nnz else np.zeros(0, int)
        A = As_[:, cols]
        scale_c = None if scale_c is None else scale_c[cols]
    Ad = np.asarray(dense(A), dtype=float)
    m = Ad.shape[0]
    if m == 0:
        return IndependentRows(np.zeros(0, int), 0, np.zeros((0, 0)), np.zeros(0, int))
    if Ad.shape[1] == 0:  # every row zero: all dependent
        return IndependentRows(np.zeros(0, int), 0, np.zeros((m, 0)), np.arange(m))
    Ac = Ad if scale_c is None else Ad * scale_c[None, :]
    scale = row_scale(Ac, keep_zero=True)
    As = scale.apply(Ac)
    _, R, piv = sla.qr(As.T, mode="economic", pivoting=True)
    diag = np.abs(np.diag(R))
    rank = int(np.sum(diag > rtol * diag[0])) if diag.size and diag[0] > 0 else 0
    keep = np.sort(piv[:rank])
    dropped = np.sort(piv[rank:])
    if dropped.size and rank:
        Ws, *_ = np.linalg.lstsq(As[keep].T, As[dropped].T, rcond=None)
        # A~_i = d_i a_i C:  a_d = (d_k / d_d) W~ a_k
        W = Ws.T * scale.ratio(dropped, keep)
    else:
        W = np.zeros((dropped.size, rank))
    return IndependentRows(keep, rank, W, dropped)


def check_consistent(A: sp.sparray | sp.spmatrix | np.ndarray,
                     rhs: sp.sparray | sp.spmatrix | np.ndarray,
                     rows: IndependentRows | None = None, labels: Sequence[str] | None = None,
                     rtol: float = 1e-8) -> IndependentRows:
    r"""Check that ``A q = rhs`` can hold: every redundant row's right-hand side is the same
    combination of the kept rows' right-hand sides as its left-hand side.

    .. math::  A_{d} = W A_{k} \;\Rightarrow\; \text{rhs}_{d} = W\, \text{rhs}_{k}

    Judged on the equilibrated rows (``D A``, ``D rhs``): the misfit of row ``d`` is
    :math:`|d_d (\text{rhs}_d - W \text{rhs}_k)|` relative to :math:`\max |D\, \text{rhs}|`,
    whatever the scale of each row.  ``rhs`` is ``b`` (an ``m``-vector) or ``R`` (``m x k``,
    eq 14).

    Raises:
        ConstraintError: naming the first offending row.
    """
    rows = independent_rows(A) if rows is None else rows
    if rows.dropped.size == 0:
        return rows
    Ad = np.asarray(dense(A), dtype=float)
    Rd = np.asarray(dense(rhs))
    Rd = Rd.reshape(Rd.shape[0], -1)
    scale = row_scale(Ad, keep_zero=True)
    Rs = scale.apply(Rd)
    # d_d (rhs_d - W rhs_k) = d_d rhs_d - (W d_d / d_k) (d_k rhs_k)
    Ws = rows.combination * scale.ratio(rows.keep, rows.dropped).T
    predicted = Ws @ Rs[rows.keep]
    actual = Rs[rows.dropped]
    size = max(float(np.abs(Rs).max()), 1e-300)
    err = np.abs(actual - predicted).max(axis=1) / size
    bad = np.flatnonzero(err > rtol)
    if bad.size:
        i = int(rows.dropped[bad[0]])
        name = labels[i] if labels is not None else f"row {i}"
        raise ConstraintError(
            f"inconsistent constraints: {name} is a combination of the other rows but its "
            f"right-hand side differs by {err[bad[0]]:.3g} (relative)")
    return rows


def particular_solution(A: sp.sparray | sp.spmatrix | np.ndarray, rhs: np.ndarray,
                        rows: IndependentRows | None = None) -> np.ndarray:
    r"""Minimum-norm ``x`` with ``A x = rhs`` (``rhs`` consistent), from the independent rows,
    equilibrated (scaling rows changes neither the solutions nor the minimum-norm one):

    .. math::  x = \tilde A_k^T (\tilde A_k \tilde A_k^T)^{-1} \tilde r_k, \qquad
               \tilde A_k = D_k A_k, \quad \tilde r_k = D_k\, \text{rhs}_k
    """
    rows = independent_rows(A) if rows is None else rows
    Ad = np.asarray(dense(A), dtype=float)
    rk = np.asarray(dense(rhs)).reshape(Ad.shape[0], -1)[rows.keep]
    if rows.rank == 0:
        return np.zeros((Ad.shape[1], rk.shape[1]))
    scale = row_scale(Ad[rows.keep])
    Ak, rk = scale.apply(Ad[rows.keep]), scale.apply(rk)
    return Ak.T @ np.linalg.solve(Ak @ Ak.T, rk)


def pinv_sym(S: np.ndarray, rank: int | None = None, rtol: float = 1e-11) -> np.ndarray:
    r"""Moore-Penrose inverse of a small symmetric positive semidefinite matrix.

    .. math::  S = V \Lambda V^T, \qquad S^+ = V_r \Lambda_r^{-1} V_r^T

    with :math:`\Lambda_r` the ``rank`` largest eigenvalues when ``rank`` is given (a rank
    decided on the equilibrated rows by :func:`independent_rows`, so the three formulations
    agree on it), else those above ``rtol`` times the largest.  Either way an eigenvalue at the
    rounding level of ``S`` (``m eps`` times the largest) is not inverted: ``S = A M^{-1} A^T``
    squares the conditioning of ``A``, and rows independent to ``1e-9`` only are dependent
    in ``S``.
    """
    if S.size == 0:
        return np.array(S, dtype=float, copy=True)
    Ssym = (S + S.T) / 2
    if rank is None:
        return sla.pinvh(Ssym, rtol=rtol)
    w, V = np.linalg.eigh(Ssym)
    floor = S.shape[0] * np.finfo(float).eps * max(float(w[-1]), 0.0)
    keep = np.zeros(w.size, dtype=bool)
    keep[w.size - max(min(int(rank), w.size), 0):] = True
    keep &= w > floor
    w, V = w[keep], V[:, keep]
    return (V / w) @ V.T
