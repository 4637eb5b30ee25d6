"""The permutation from a scikit-fem vector basis's DOFs to the translations of substruct's
grids, found by position: how the quadratic-solid tests compare their element matrices with
scikit-fem's."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp


def skfem_to_grids(basis, pts: np.ndarray, n: int) -> sp.csr_array:
    """``P`` (``n x basis.N``) with ``P[3 g + c, d] = 1`` where DOF ``d`` of the basis (a
    corner or edge DOF of component ``c``) sits at grid ``g``'s position ``pts[g]``: our matrix
    is compared with ``P @ ref @ P.T``."""
    key = {tuple(np.round(x, 12)): k for k, x in enumerate(pts)}
    target = np.empty(basis.N, dtype=np.int64)
    for c in range(3):
        for dofs in (basis.nodal_dofs[c], basis.edge_dofs[c]):
            for d in dofs:
                target[d] = 3 * key[tuple(np.round(basis.doflocs[:, d], 12))] + c
    return sp.csr_array((np.ones(basis.N), (target, np.arange(basis.N))), shape=(n, basis.N))
