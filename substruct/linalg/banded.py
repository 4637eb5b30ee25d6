r"""Banded storage and solves for matrices that a reverse Cuthill-McKee ordering makes narrow
(chains, rods, beams, thin structures): LAPACK's band LU (``gbsv``) with many right-hand sides.

With the ordering :math:`\pi` of :func:`band_ordering` the matrix :math:`A_{\pi\pi}` has
half-bandwidth ``b``: :math:`a_{ij} = 0` for :math:`|i - j| > b`.  Its LU with partial
pivoting costs :math:`O(n b^2)` and a solve :math:`O(n b)` a right-hand side, in LAPACK's
column-major blocks, where a general sparse solve of hundreds of right-hand sides pays a
per-column overhead (SuperLU: 11 ms for 400 right-hand sides of a 399-coordinate chain).
LAPACK's substitutions ``gbtrs`` call a BLAS ``tbsv`` a right-hand side, so with hundreds of
them :func:`band_solve_many` does the substitutions in compiled loops instead
(:mod:`substruct.linalg.band_kernel`).  The frequency sweeps use these solves when ``b`` is at
most :data:`BAND_MAX` (:mod:`substruct.analysis.frf.sparse`).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from scipy.sparse.csgraph import reverse_cuthill_mckee

__all__ = ["BAND_MAX", "KERNEL_MIN_WORK", "band_factor", "band_ordering", "band_solve",
           "band_solve_many", "band_storage", "kernel_pays"]

#: Largest half-bandwidth for which a band solve is chosen over a sparse LU.
BAND_MAX = 32
#: Least work ``n p count`` (unknowns x right-hand sides x matrices) for which the compiled
#: substitutions of :func:`band_solve_many` are chosen over LAPACK's ``gbsv``: below it the
#: 0.5-0.8 s of CPU that loading Numba and its cached code costs a fresh process is more than
#: they save (about 23 ns an unknown and right-hand side: 4 against 27 ns with 400 right-hand
#: sides, ``benchmarks/frf_sweep.py``).
KERNEL_MIN_WORK = 30_000_000


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


def band_factor(ab: np.ndarray, b: int) -> tuple[np.ndarray, np.ndarray]:
    r"""LU with partial pivoting (LAPACK ``gbtrf``) of the band storage ``ab`` of
    :func:`band_storage` (overwritten): :math:`P A = L U`.  Returns the factors in band
    storage (``U`` with ``2 b`` super-diagonals in rows ``0 .. 2 b``, the multipliers of ``L``
    below) and the 0-based pivots.

    Raises:
        numpy.linalg.LinAlgError: ``A`` is singular.
    """
    gbtrf, = sla.get_lapack_funcs(("gbtrf",), (ab,))
    lu, piv, info = gbtrf(ab, b, b, overwrite_ab=True)
    if info > 0:
        raise np.linalg.LinAlgError(f"singular matrix: zero pivot {info}")
    if info < 0:
        raise ValueError(f"gbtrf: illegal argument {-info}")
    return lu, piv


def kernel_pays(n: int, p: int, count: int) -> bool:
    """Whether ``count`` solves of ``n`` unknowns with ``p`` right-hand sides each go to the
    compiled substitutions (:func:`band_solve_many`): at least :data:`KERNEL_MIN_WORK` of
    ``n p count``, else LAPACK's :func:`band_solve` costs less than loading Numba."""
    return n * p * count >= KERNEL_MIN_WORK


def band_solve_many(ab: np.ndarray, b: int, rhs: np.ndarray, x: np.ndarray) -> None:
    r"""``x = A^{-1} rhs`` for many right-hand sides (``rhs``, ``x``: ``n x p``, C-ordered,
    complex like ``ab``): :func:`band_factor`, then the compiled substitutions
    (:func:`substruct.linalg.band_kernel.band_substitute`), each row operation one contiguous
    loop over the ``p`` right-hand sides.  ``ab`` is overwritten.

    Raises:
        numpy.linalg.LinAlgError: ``A`` is singular.
    """
    from substruct.linalg.band_kernel import band_substitute
    lu, piv = band_factor(ab, b)
    band_substitute(lu, np.asarray(piv, dtype=np.int64), b, rhs, x)
