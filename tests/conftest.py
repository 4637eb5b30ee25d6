"""Shared fixtures: the three-DOF system of the paper's Fig. 2 (eqs 35-36).

BLAS is pinned to one thread before numpy loads: the dense solves here are small, and on two
cores threaded BLAS makes them several times slower.
"""

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
import pytest  # noqa: E402


@pytest.fixture
def three_dof():
    """``(M, C, K, omega)`` of eqs (35)-(36)."""
    m1, m2, m3 = 1.0, 2.0, 4.0
    k1 = k2 = 10.0
    k3 = 20.0
    c = 10.0
    M = np.diag([m1, m2, m3])
    C = np.zeros((3, 3))
    C[0, 0] = c
    K = np.array([[k1 + k2, -k2, 0.0], [-k2, k2 + k3, -k3], [0.0, -k3, k3]])
    return M, C, K, 2.0
