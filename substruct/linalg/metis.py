r"""METIS nested-dissection orderings (``pymetis``), for SuperLU.

SuperLU's own minimum-degree ordering (``MMD_AT_PLUS_A``) fills the factor of a 3D solid like
:math:`n^{5/3}`; nested dissection (separators of the mesh's graph numbered last, recursively)
like :math:`n^{4/3}`, as CHOLMOD's and PARDISO's orderings do.  On the benchmark box the factor
of SuperLU in symmetric mode after METIS has 0.63 times the entries of the one after MMD at
29k coordinates (docs/performance.md); :func:`superlu_metis` factorizes in that order.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from substruct.linalg.solve_type import Solve
from substruct.linalg.superlu import superlu_ordered

__all__ = ["METIS_PIVOTS", "metis_available", "metis_ordering", "superlu_metis"]

#: SuperLU's diagonal pivot threshold after a METIS ordering, for each matrix kind.
METIS_PIVOTS = {"spd": 0.0, "symmetric": 0.1, "complex-symmetric": 0.1}


def metis_available() -> bool:
    """Whether ``pymetis`` can be imported."""
    try:
        import pymetis  # noqa: F401
    except ImportError:
        return False
    return True


def metis_ordering(pattern: sp.sparray | sp.spmatrix) -> np.ndarray:
    r"""METIS nested-dissection ordering of the graph of :math:`|A| + |A|^T` (no self loops):
    ``order`` with ``A[order][:, order]`` the matrix to factorize in natural order."""
    import pymetis  # optional dependency (wheels for Linux, macOS, Windows)

    P = sp.csr_array(abs(sp.csr_array(pattern)))
    G = sp.csr_array(P + P.T)
    G.setdiag(0)
    G.eliminate_zeros()
    G.sort_indices()
    n = G.shape[0]
    if G.nnz == 0:
        return np.arange(n)
    adjacency = pymetis.CSRAdjacency(G.indptr.astype(np.int64), G.indices.astype(np.int64))
    perm, _ = pymetis.nested_dissection(adjacency)
    return np.asarray(perm, dtype=np.int64)


def superlu_metis(A: sp.sparray | sp.spmatrix, kind: str) -> Solve:
    """SuperLU in symmetric mode after :func:`metis_ordering`, for the matrix ``kind``
    (``"spd"``, ``"symmetric"`` or ``"complex-symmetric"``: the pivot threshold of
    :data:`METIS_PIVOTS`)."""
    return superlu_ordered(A, metis_ordering(A), METIS_PIVOTS[kind])
