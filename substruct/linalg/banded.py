r"""Banded storage and solves for matrices that a reverse Cuthill-McKee ordering makes narrow
(chains, rods, beams, thin structures): LAPACK's band LU (``gbsv``) with many right-hand sides.

With the ordering :math:`\pi` of :func:`band_ordering` the matrix :math:`A_{\pi\pi}` has
half-bandwidth ``b``: :math:`a_{ij} = 0` for :math:`|i - j| > b`.  Its LU with partial
pivoting costs :math:`O(n b^2)` and a solve :math:`O(n b)` a right-hand side, in LAPACK's
column-major blocks, where a general sparse solve of hundreds of right-hand sides pays a
per-column overhead (SuperLU: 11 ms for 400 right-hand sides of a 399-coordinate chain;
the band solve takes a fraction of a millisecond).  The frequency sweeps use it when ``b`` is
at most :data:`BAND_MAX` (:mod:`substruct.analysis.sparse_sweep`).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from scipy.sparse.csgraph import reverse_cuthill_mckee

__all__ = ["BAND_MAX", "BATCH_BYTES", "band_factor_batch", "band_ordering", "band_solve",
           "band_solve_batch", "band_storage", "batch_size"]

#: Largest half-bandwidth for which a band solve is chosen over a sparse LU.
BAND_MAX = 32
#: Bytes of the solution block of one batch of :func:`band_solve_batch` (``n x F x p`` complex).
BATCH_BYTES = 32 * 2**20
#: Fewest entries ``F p`` a row operation of :func:`band_solve_batch` must touch to be chosen
#: over LAPACK's solve a matrix at a time (below it NumPy's cost a call dominates).
BATCH_MIN_ROW = 2048


def band_ordering(pattern: sp.sparray | sp.spmatrix) -> tuple[np.ndarray, int]:
    """``(order, b)``: the reverse Cuthill-McKee ordering of the symmetrized ``pattern`` and
    the half-bandwidth ``b`` of ``pattern[order][:, order]``."""
    P = sp.csr_matrix(abs(sp.csr_matrix(pattern)))
    P = sp.csr_matrix(P + P.T)
    order = np.asarray(reverse_cuthill_mckee(P, symmetric_mode=True), dtype=np.int64)
    inverse = np.empty_like(order)
    inverse[order] = np.arange(order.size)
    coo = P.tocoo()
    width = int(np.abs(inverse[coo.row] - inverse[coo.col]).max(initial=0))
    return order, width


def band_storage(A: sp.sparray | sp.spmatrix, b: int) -> np.ndarray:
    r"""LAPACK ``gbsv`` band storage of the square ``A`` (already ordered) with ``b`` sub- and
    super-diagonals and ``b`` more rows for the fill of pivoting:
    ``ab[2 b + i - j, j] = a_ij``, shape ``(3 b + 1, n)``."""
    coo = sp.coo_matrix(A)
    n = A.shape[0]
    ab = np.zeros((3 * b + 1, n), dtype=np.result_type(coo.data.dtype, float))
    keep = np.abs(coo.row - coo.col) <= b
    np.add.at(ab, (2 * b + coo.row[keep] - coo.col[keep], coo.col[keep]), coo.data[keep])
    return ab


def band_solve(ab: np.ndarray, b: int, rhs: np.ndarray) -> np.ndarray:
    """``A^{-1} rhs`` from the band storage ``ab`` (:func:`band_storage`; overwritten) by
    LAPACK ``gbsv``; the solution is column-major (Fortran order) like ``rhs``.

    Raises:
        numpy.linalg.LinAlgError: ``A`` is singular.
    """
    gbsv, = sla.get_lapack_funcs(("gbsv",), (ab, rhs))
    _, _, x, info = gbsv(b, b, ab, rhs, overwrite_ab=True)
    if info > 0:
        raise np.linalg.LinAlgError(f"singular matrix: zero pivot {info}")
    if info < 0:
        raise ValueError(f"gbsv: illegal argument {-info}")
    return x


def batch_size(n: int, p: int, count: int) -> int:
    """How many matrices :func:`band_solve_batch` takes at once for ``n`` unknowns, ``p``
    right-hand sides and ``count`` matrices in all: as many as fit :data:`BATCH_BYTES` (at
    least one, at most ``count``); 0 when a row of the batch would hold fewer than
    :data:`BATCH_MIN_ROW` entries (then LAPACK's :func:`band_solve` a matrix at a time is
    faster)."""
    f = int(min(max(BATCH_BYTES // max(16 * n * p, 1), 1), max(count, 1)))
    return f if f * p >= BATCH_MIN_ROW else 0


def band_factor_batch(ab: np.ndarray, b: int) -> np.ndarray:
    r"""LU with partial pivoting (LAPACK ``gbtrf``) of each matrix of the stack ``ab``
    (``F x (3 b + 1) x n`` band storage of :func:`band_storage`, complex), in place:
    :math:`P_f A_f = L_f U_f`, ``U_f`` with ``2 b`` super-diagonals in rows ``0 .. 2 b``,
    the multipliers of ``L_f`` below.  Returns the pivots, ``F x n``, 0-based (row ``j`` was
    swapped with row ``piv[f, j]`` at step ``j``).

    Raises:
        numpy.linalg.LinAlgError: a matrix is singular (its index in ``args[1]``).
    """
    gbtrf, = sla.get_lapack_funcs(("gbtrf",), (ab,))
    piv = np.empty((ab.shape[0], ab.shape[2]), dtype=np.intp)
    for f in range(ab.shape[0]):
        lu, pf, info = gbtrf(ab[f], b, b, overwrite_ab=True)
        if info > 0:
            raise np.linalg.LinAlgError(f"singular matrix: zero pivot {info}", f)
        if lu is not ab[f]:
            ab[f] = lu
        piv[f] = pf
    return piv


def band_solve_batch(lu: np.ndarray, piv: np.ndarray, b: int, rhs: np.ndarray,
                     out: np.ndarray) -> None:
    r"""``out[:, f, :] = A_f^{-1} rhs`` for the stack factorized by :func:`band_factor_batch`.

    The substitutions of LAPACK's ``gbtrs``, row by row, each row operation done for every
    matrix and every right-hand side at once (``out[j]`` is ``F x p``, contiguous):

    .. math::  y_{j+d} \leftarrow y_{j+d} - l_{j+d,j}\, y_j \quad (d = 1..b,\ \text{after
               the swap of } y_j, y_{\pi_j}), \qquad
               x_j = y_j / u_{jj}, \quad y_i \leftarrow y_i - u_{ij}\, x_j \quad
               (j - 2b \le i < j) .

    LAPACK solves a right-hand side at a time with a BLAS call a row (``tbsv``), which costs
    more than the arithmetic for narrow bands; here a NumPy call a row serves ``F p`` entries.

    Args:
        lu: ``F x (3 b + 1) x n`` factors of :func:`band_factor_batch`.
        piv: ``F x n`` 0-based pivots.
        b: half-bandwidth.
        rhs: ``n x p`` right-hand sides, shared by the ``F`` matrices.
        out: ``n x F x p`` complex, written (its rows ``out[j]`` must be C-contiguous).
    """
    F, _, n = lu.shape
    kd = 2 * b
    np.copyto(out, rhs[:, None, :])
    tmp = np.empty(out.shape[1:], dtype=out.dtype)
    lower = np.ascontiguousarray(lu[:, kd + 1:, :].transpose(2, 1, 0))[..., None]  # n, b, F, 1
    upper = np.ascontiguousarray(lu[:, :kd, :].transpose(2, 1, 0))[..., None]  # n, 2b, F, 1
    inv_diag = np.ascontiguousarray((1.0 / lu[:, kd, :]).T)[..., None]  # n, F, 1
    shift = piv.T - np.arange(n)[:, None]  # n, F: row j swapped with j + shift
    swaps: list[list[tuple[int, np.ndarray]]] = [[] for _ in range(n)]
    for j in np.flatnonzero(shift.any(axis=1)).tolist():
        for d in range(1, b + 1):
            mask = shift[j] == d
            if mask.any():
                swaps[j].append((d, mask[:, None]))
    for j in range(n - 1):
        row = out[j]
        for d, mask in swaps[j]:
            np.copyto(tmp, row)
            np.copyto(row, out[j + d], where=mask)
            np.copyto(out[j + d], tmp, where=mask)
        for d in range(min(b, n - 1 - j)):
            np.multiply(row, lower[j, d], out=tmp)
            np.subtract(out[j + 1 + d], tmp, out=out[j + 1 + d])
    used = np.any(upper[..., 0] != 0, axis=2).tolist()  # n x 2b: u_ij != 0 for some f
    for j in range(n - 1, -1, -1):
        row = out[j]
        row *= inv_diag[j]
        for r, nonzero in enumerate(used[j]):
            i = j - kd + r
            if nonzero and i >= 0:
                np.multiply(row, upper[j, r], out=tmp)
                np.subtract(out[i], tmp, out=out[i])
