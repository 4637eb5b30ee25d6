"""Dense copies of matrices known to be small (the ``m x m`` constraint block, reduced models).

Everything large stays ``scipy.sparse``; a dense copy is made only where the size is known to be
small, and refused above :data:`DENSE_LIMIT` entries rather than exhausting the memory.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["DENSE_LIMIT", "dense"]

#: Largest number of entries of a dense copy made without complaint.
DENSE_LIMIT = 50_000_000


def dense(mat: sp.sparray | sp.spmatrix | np.ndarray) -> np.ndarray:
    """A dense copy of a matrix known to be small.

    Args:
        mat: a sparse matrix or an array.

    Returns:
        The matrix as a ``numpy`` array (the array itself if it is one already).

    Raises:
        MemoryError: a sparse matrix of more than :data:`DENSE_LIMIT` entries.
    """
    if sp.issparse(mat):
        if mat.shape[0] * mat.shape[1] > DENSE_LIMIT:
            raise MemoryError(f"refusing a dense {mat.shape} copy")
        return np.asarray(mat.toarray())  # type: ignore[union-attr]
    return np.asarray(mat)
