"""The type of a factorization: a matrix in, a solve out."""

from __future__ import annotations

from typing import Callable

import numpy as np
import scipy.sparse as sp

__all__ = ["Factorize", "Solve"]

#: A solve ``b -> A^{-1} b`` (``b`` a vector or an ``n x k`` block).
Solve = Callable[[np.ndarray], np.ndarray]
#: A factorization ``A -> Solve``.
Factorize = Callable[[sp.sparray], Solve]
