"""CHOLMOD (SuiteSparse) supernodal Cholesky through scikit-sparse, when it is installed."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from substruct.linalg.solve_type import Solve

__all__ = ["cholmod", "cholmod_failures", "has_cholmod"]


def cholmod(A: sp.sparray | sp.spmatrix) -> Solve:
    r"""CHOLMOD supernodal Cholesky :math:`P A P^T = L L^T` (scikit-sparse), for symmetric
    positive definite ``A``; a complex right-hand side is solved as its real and imaginary
    parts.

    Raises:
        sksparse.cholmod.CholmodNotPositiveDefiniteError: ``A`` is not positive definite.
    """
    from sksparse.cholmod import cholesky  # optional dependency

    factor = cholesky(sp.csc_matrix(A))

    def solve(b: np.ndarray) -> np.ndarray:
        b = np.asarray(b)
        if np.iscomplexobj(b):  # real factors: CHOLMOD refuses a complex right-hand side
            return factor(np.ascontiguousarray(b.real)) + \
                1j * factor(np.ascontiguousarray(b.imag))
        return factor(b)

    return solve


def has_cholmod() -> bool:
    """Whether scikit-sparse's CHOLMOD can be imported."""
    try:
        import sksparse.cholmod  # noqa: F401
    except ImportError:
        return False
    return True


def cholmod_failures() -> tuple[type[BaseException], ...]:
    """The exceptions of a CHOLMOD factorization that failed (not positive definite, out of
    memory) rather than a bug."""
    from sksparse.cholmod import CholmodError

    return (CholmodError, MemoryError)
