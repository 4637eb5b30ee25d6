"""Tolerances from the data's scale and the algorithm's error bound, never from a few ulps of
one machine's BLAS (whose kernels sum in different orders: ``OPENBLAS_CORETYPE=SkylakeX`` and
``Haswell`` differ in the last bits)."""

from __future__ import annotations

import numpy as np

#: Unit roundoff of double precision.
EPS = np.finfo(float).eps


def backward_bound(n: int, c: float = 4.0) -> float:
    r"""``c n eps``: the relative (backward) error bound of a backward-stable dense
    factorization (SVD, QR, LU with pivoting) of size ``n`` or of an inner product of length
    ``n`` (Higham, *Accuracy and Stability of Numerical Algorithms*, sections 3.1, 9 and 19),
    whatever the order of the sums, with a generous constant ``c``."""
    return c * n * EPS


def solve_bound(Z: np.ndarray, X: np.ndarray, c: float = 4.0) -> float:
    r"""The forward error bound of a computed solution ``X`` of ``Z X = B`` by a backward-stable
    solver: ``c n eps cond(Z) max|X|``."""
    Z = np.asarray(Z)
    return backward_bound(Z.shape[0], c) * float(np.linalg.cond(Z)) * float(np.abs(X).max())


def row_scale(A: np.ndarray) -> np.ndarray:
    """``sqrt(n) max_j |a_ij|`` per row: a bound of each row's 2-norm that does not underflow
    for rows of ``1e-300`` (the plain 2-norm does)."""
    return np.sqrt(A.shape[1]) * np.abs(A).max(axis=1)
