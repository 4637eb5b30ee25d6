"""The types of the linear algebra: a matrix (sparse or dense), a factorization (a matrix in, a
solve out)."""

from __future__ import annotations

from typing import Callable, TypeAlias

import numpy as np
import scipy.sparse as sp

__all__ = ["Factorize", "Matrix", "Solve"]

#: A matrix, sparse or dense.
Matrix: TypeAlias = sp.sparray | sp.spmatrix | np.ndarray

#: A solve ``b -> A^{-1} b`` (``b`` a vector or an ``n x k`` block).
Solve = Callable[[np.ndarray], np.ndarray]
#: A factorization ``A -> Solve``.
Factorize = Callable[[sp.sparray], Solve]
