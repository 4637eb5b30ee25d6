r"""The substitutions of a band LU for many right-hand sides, compiled (Numba).

LAPACK's ``gbtrs`` solves a right-hand side at a time, one BLAS ``tbsv`` call each, and for
the narrow bands of chains and rods the calls cost more than the arithmetic; NumPy row
operations over all right-hand sides pay a pass over the whole block per operation.  Here the
same substitutions run as compiled loops over rows of a C-ordered block, each row operation a
contiguous loop over the right-hand sides (``benchmarks/frf_sweep.py``: 0.65 ms against about
3 ms a frequency for 400 right-hand sides of a 399-coordinate chain).

The module is imported only by :func:`substruct.linalg.banded.band_solve_many`, so that Numba
is loaded by the sweeps that use it; its compiled code is cached beside this file (or in
Numba's user cache when that is not writable, or compiled in each process when neither is).
"""

from __future__ import annotations

from typing import Callable

import numpy as np
from numba import njit

__all__ = ["band_substitute", "band_substitute_python", "compiled"]


def compiled(func: Callable[..., None]) -> Callable[..., None]:
    """``func`` compiled by Numba, its machine code cached on disk where a cache directory is
    writable, else compiled anew in each process (Numba refuses ``cache=True`` without one)."""
    try:
        return njit(cache=True, nogil=True)(func)  # type: ignore[no-any-return]
    except RuntimeError:
        return njit(nogil=True)(func)  # type: ignore[no-any-return]


def band_substitute_python(lu: np.ndarray, piv: np.ndarray, b: int, rhs: np.ndarray,
                           x: np.ndarray) -> None:
    r"""``x = A^{-1} rhs`` from LAPACK ``gbtrf``'s factors of ``A`` (``P A = L U``).

    ``lu``: band storage of ``gbtrf`` with ``b`` sub- and super-diagonals (``U`` with ``2 b``
    super-diagonals in rows ``0 .. 2 b``, the multipliers of ``L`` in rows ``2 b + 1 ..
    3 b``); ``piv``: 0-based pivots (row ``j`` swapped with row ``piv[j]`` at step ``j``);
    ``rhs``, ``x``: ``n x p``, C-ordered (a row of ``rhs`` is copied into ``x`` when the
    forward substitution first reaches it, while it is in cache).  Forward, then back
    substitution, row by row:

    .. math::  y_j \leftrightarrow y_{\pi_j}, \quad y_{j+d} \leftarrow y_{j+d} -
               l_{j+d,j}\, y_j \ (d = 1..b); \qquad
               x_j = y_j / u_{jj}, \quad y_i \leftarrow y_i - u_{ij}\, x_j \
               (j - 2b \le i < j) .
    """
    n, p = x.shape
    kd = 2 * b
    ready = 0  # rows of x holding their right-hand side
    for j in range(n - 1):
        while ready <= min(j + b, n - 1):
            for c in range(p):
                x[ready, c] = rhs[ready, c]
            ready += 1
        q = piv[j]
        if q != j:
            for c in range(p):
                t = x[j, c]
                x[j, c] = x[q, c]
                x[q, c] = t
        for d in range(1, min(b, n - 1 - j) + 1):
            lower = lu[kd + d, j]
            if lower != 0:
                for c in range(p):
                    x[j + d, c] -= lower * x[j, c]
    while ready < n:
        for c in range(p):
            x[ready, c] = rhs[ready, c]
        ready += 1
    for j in range(n - 1, -1, -1):
        s = 1.0 / lu[kd, j]
        for c in range(p):
            x[j, c] *= s
        for r in range(kd):
            i = j - kd + r
            if i >= 0:
                upper = lu[r, j]
                if upper != 0:
                    for c in range(p):
                        x[i, c] -= upper * x[j, c]


#: :func:`band_substitute_python` compiled: the one the solves call.
band_substitute = compiled(band_substitute_python)
