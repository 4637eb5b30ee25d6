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

__all__ = ["BAND_MAX", "band_ordering", "band_solve", "band_storage"]

#: Largest half-bandwidth for which a band solve is chosen over a sparse LU.
BAND_MAX = 32


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
