r"""Bases of the null space of a constraint matrix, :math:`A N = 0`: the coordinates that
satisfy the constraints are :math:`u = N p` (paper eqs 2-3; the null-space formulation).

Two routines, one for each size of problem:

* :func:`null_space_basis`, dense and orthonormal by the SVD, for small ``A`` (the paper's
  models, reduced models, the ``m x s`` blocks of massless coordinates);
* :func:`master_slave`, sparse, by eliminating one *slave* coordinate per independent row,
  for finite-element models with many ties (``T`` keeps the sparsity of ``A``).

Both decide the rank on equilibrated rows (:mod:`substruct.linalg.scaling`), so a row
``1e-300 q_1`` eliminates ``q_1`` as ``q_1`` does, and both refuse a row that is exactly zero.
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass
import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from substruct.linalg.constraints import RANK_RTOL, independent_rows
from substruct.linalg.dense import dense
from substruct.linalg.scaling import row_scale

__all__ = ["Elimination", "master_slave", "null_space_basis"]


def null_space_basis(A: sp.sparray | sp.spmatrix | np.ndarray, rtol: float = RANK_RTOL,
                     col_scale: np.ndarray | None = None) -> np.ndarray:
    r"""Orthonormal basis ``N`` of :math:`\operatorname{null}(A)` (``A N = 0``, ``N^T N = I``),
    dense, by the SVD of the equilibrated rows.

    .. math::  D A = U \Sigma V^T, \qquad N = V_{:, r:}, \qquad
               r = \operatorname{rank} A

    ``r`` is the rank that :func:`substruct.linalg.constraints.independent_rows` decides (with
    ``col_scale``), so that this basis and the independent rows of the Lagrange formulation
    always agree on it.  A zero row constrains nothing and changes nothing here (the analyses
    refuse one at their entry, :func:`substruct.linalg.scaling.equilibrate`).
    """
    Ad = np.asarray(dense(A), dtype=float)
    n = Ad.shape[1]
    if Ad.shape[0] == 0:
        return np.eye(n)
    As = row_scale(Ad, keep_zero=True).apply(Ad)
    r = independent_rows(Ad, rtol, col_scale).rank
    _, _, Vh = sla.svd(As, full_matrices=True)
    return Vh[r:].T.copy()


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


def master_slave(A: sp.sparray | sp.spmatrix | np.ndarray, prefer: np.ndarray | None = None,
                 rtol: float = RANK_RTOL, pivot: float = 0.1,
                 col_scale: np.ndarray | None = None) -> Elimination:
    r"""Eliminate one *slave* coordinate per independent constraint row (sparse Gauss-Jordan).

    Rows are taken in order, on :math:`\tilde A = A C` (``C`` = ``col_scale``, e.g.
    :func:`substruct.linalg.scaling.mass_column_scale`; the identity if ``None``).  Each row,
    scaled to unit largest entry, has the expressions of the slaves chosen so far substituted
    into it; if what remains is below ``rtol`` the row is a combination of the earlier rows
    (dropped), otherwise its slave is chosen among the entries of magnitude at least ``pivot``
    times the largest (threshold pivoting), preferring coordinates flagged in ``prefer`` (e.g.
    massless ones), then the largest:

    .. math::  \tilde u_s = -\sum_{j \ne s} \frac{\tilde a_j}{\tilde a_s} \tilde u_j .

    Earlier expressions that used ``u_s`` are updated, so every slave is a combination of
    masters only.  A node-to-node tie ``u_a - u_b`` costs ``O(1)``.  The basis of ``A`` is
    :math:`T = C \tilde T C_m^{-1}` (``C_m`` the factors of the masters), so ``T[masters] = I``.

    Args:
        A: ``m x n`` constraint matrix (any rank).
        prefer: boolean mask over the ``n`` coordinates to pick as slaves when possible.
        rtol: relative size under which a reduced row counts as zero (dependent).
        pivot: threshold-pivoting fraction.
        col_scale: ``n`` positive column factors, or ``None``.

    An empty row constrains nothing and is listed in ``dropped_rows`` (the analyses refuse one
    at their entry, :func:`substruct.linalg.scaling.equilibrate`).
    """
    As = sp.csr_array(A, dtype=float)
    m, n = As.shape
    c = np.ones(n) if col_scale is None else np.asarray(col_scale, dtype=float)
    if col_scale is not None:
        As = sp.csr_array(As @ sp.diags_array(c))
    As.eliminate_zeros()
    pref = np.zeros(n, dtype=bool) if prefer is None else np.asarray(prefer, dtype=bool)
    expr: dict[int, dict[int, float]] = {}
    users: dict[int, set[int]] = defaultdict(set)
    kept, dropped, slaves = [], [], []
    for i in range(m):
        lo, hi = As.indptr[i], As.indptr[i + 1]
        cols, vals = As.indices[lo:hi], As.data[lo:hi]
        scale = np.abs(vals).max(initial=0.0)
        if scale == 0.0:  # an empty row constrains nothing
            dropped.append(i)
            continue
        acc: dict[int, float] = defaultdict(float)
        for j, v in zip(cols.tolist(), (vals / scale).tolist()):
            if j in expr:
                for k, w in expr[j].items():
                    acc[k] += v * w
            else:
                acc[j] += v
        row = {j: v for j, v in acc.items() if abs(v) > rtol}
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
            cs = et.pop(s)
            for j, v in e.items():
                prev = et.get(j, 0.0)
                w = prev + cs * v
                if abs(w) > 1e-14 * (abs(prev) + abs(cs * v)):
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
    return _basis(n, expr, slaves, kept, dropped, c)


def _basis(n: int, expr: dict[int, dict[int, float]], slaves: list[int], kept: list[int],
           dropped: list[int], c: np.ndarray) -> Elimination:
    r"""Assemble :math:`T = C \tilde T C_m^{-1}` from the slaves' expressions in the masters."""
    slaves_a = np.asarray(slaves, dtype=np.int64)
    is_slave = np.zeros(n, dtype=bool)
    is_slave[slaves_a] = True
    masters = np.flatnonzero(~is_slave)
    col = np.full(n, -1, dtype=np.int64)
    col[masters] = np.arange(masters.size)
    r, cc, v = [masters], [np.arange(masters.size)], [np.ones(masters.size)]
    for s, e in expr.items():
        if e:
            js = np.fromiter(e.keys(), dtype=np.int64, count=len(e))
            r.append(np.full(len(e), s))
            cc.append(col[js])
            # u_s = c_s u~_s = c_s sum_j e_j u~_j = sum_j (c_s e_j / c_j) u_j
            v.append(np.fromiter(e.values(), dtype=float, count=len(e)) * c[s] / c[js])
    T = sp.csc_array((np.concatenate(v), (np.concatenate(r), np.concatenate(cc))),
                     shape=(n, masters.size))
    return Elimination(T=T, masters=masters, slaves=slaves_a,
                       kept_rows=np.asarray(kept, dtype=np.int64),
                       dropped_rows=np.asarray(dropped, dtype=np.int64))
