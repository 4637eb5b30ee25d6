"""AMLS on a model whose mass couples coordinates its stiffness does not.

The nested dissection was made on the graph of ``K`` alone.  A chain of CELAS2 springs, one per
component, couples no two components of a grid; a point mass off the grid (with rotary
inertia: a definite 6 x 6 block) couples all six, so the blocks of the dissection were joined
by the mass across their separators and the reduction stopped with an IndexError (a child's
boundary outside its parent's rows).  The dissection is now of ``|K| + |M|``.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from substruct.linalg.amls import amls_modes
from test_massless_directions import chain_with_offset_masses


def test_amls_separates_the_couplings_of_the_mass():
    """The modes up to 2 rad/s with two subspace iterations against the dense pencil (the
    inverse form, definite on the right, every mode with mass)."""
    K, M = chain_with_offset_masses(520, 52)
    d = np.zeros(K.shape[0])
    for g in range(51, 520, 52):
        d[6 * g + 3:6 * g + 6] = 0.5  # rotary inertia: each mass block definite
    M = sp.csr_array(M + sp.diags_array(d))
    mu = sla.eigh(M.toarray(), K.toarray(), eigvals_only=True)
    ref = np.sort(1 / np.sqrt(mu[mu > 1e-12 * mu.max()]))
    got = amls_modes(K, M, 2.0, iterations=2, leaf_size=200)
    assert got.omega.size == np.count_nonzero(ref <= 2.0) == 26
    assert np.abs(got.omega - ref[:26]).max() <= 1e-7 * ref[25]
