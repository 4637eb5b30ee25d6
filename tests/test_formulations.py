"""The three formulations (generalized inverse, null space, KKT) held to each other."""

import numpy as np
import pytest
import scipy.sparse as sp

from substruct.linalg.constraints import ConstraintError, independent_rows
from substruct.analysis.formulations.coupling import (FORMULATIONS, constrained_acceleration, receptance,
                                receptance_agreement)
from substruct.analysis.checks import modes_agreement
from substruct.analysis.modes.dense import FORMULATIONS, coupled_modes


def random_system(rng, n, n_massless=0, damped=True):
    """SPD K, SPD (or semidefinite, with massless coordinates) M, PSD C."""
    X = rng.standard_normal((n, n))
    K = X @ X.T + n * np.eye(n)
    Y = rng.standard_normal((n, n))
    M = Y @ Y.T / n + 0.5 * np.eye(n)
    massless = rng.choice(n, n_massless, replace=False) if n_massless else np.zeros(0, int)
    M[massless, :] = 0.0
    M[:, massless] = 0.0
    Z = rng.standard_normal((n, 2))
    C = 0.3 * Z @ Z.T if damped else np.zeros((n, n))
    return M, C, K, massless


def random_constraints(rng, n, m, redundant=0, reach=None):
    """``m`` random rows plus ``redundant`` combinations of them; ``reach`` forces columns."""
    A = rng.standard_normal((m, n)) * (rng.random((m, n)) < 0.6)
    if reach is not None:
        for j, col in enumerate(reach):
            A[j % m, col] = 1.0 + rng.random()
    if redundant:
        A = np.vstack([A, rng.standard_normal((redundant, m)) @ A])
    return A


CASES = [  # (n, m, redundant, massless, damped)
    (6, 2, 0, 0, True),
    (8, 3, 2, 0, True),
    (10, 4, 1, 2, True),
    (12, 3, 0, 3, False),
    (7, 1, 0, 1, True),
]


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("n,m,redundant,n_massless,damped", CASES)
def test_receptances_agree(seed, n, m, redundant, n_massless, damped):
    rng = np.random.default_rng(seed)
    M, C, K, massless = random_system(rng, n, n_massless, damped)
    A = random_constraints(rng, n, m, redundant, reach=massless)
    # R consistent with redundant rows: same combination as A
    rows = independent_rows(A)
    R = np.zeros((A.shape[0], n))
    R[rows.keep] = rng.standard_normal((rows.rank, n))
    R[rows.dropped] = rows.combination @ R[rows.keep]
    omegas = [0.37, 1.9, 4.4]
    for RR in (None, R):
        agree = receptance_agreement(K, M, C, A, omegas, RR)
        assert max(agree.values()) < 1e-10, agree
        H = receptance(K, M, C, A, omegas, RR)
        target = 0.0 if RR is None else RR
        np.testing.assert_allclose(np.einsum("ij,wjk->wik", A, H) - target, 0.0,
                                   atol=1e-10 * np.abs(H).max())
        if RR is None:  # reciprocity for homogeneous constraints
            np.testing.assert_allclose(H, H.transpose(0, 2, 1), atol=1e-10 * np.abs(H).max())


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("n,m,redundant,n_massless,damped", CASES)
def test_modes_agree(seed, n, m, redundant, n_massless, damped):
    rng = np.random.default_rng(100 + seed)
    M, C, K, massless = random_system(rng, n, n_massless, damped)
    A = random_constraints(rng, n, m, redundant, reach=massless)
    sets = {mth: coupled_modes(M, C, K, A, method=mth) for mth in FORMULATIONS}
    ref = sets["null-space"]
    r = np.linalg.matrix_rank(A)
    for mth, md in sets.items():
        assert len(md) == len(ref), (mth, md.omega, ref.omega)
        assert modes_agreement(md, ref) < 1e-9, mth
        assert np.all(md.residual < 1e-9)
    gi = sets["generalized-inverse"]
    # the paper's pencil sets aside 2 rank(A) zero roots (and nothing physical)
    n_zero = sum(abs(l) < 1e-6 for l in gi.spurious)
    assert n_zero == 2 * r


def test_inconsistent_constraints_are_reported(three_dof):
    M, C, K, w = three_dof
    A = np.array([[1.0, 0.0, 2.0], [2.0, 0.0, 4.0]])      # second row = 2 x first
    R_bad = np.array([[1.0, 1.0, 3.0], [1.0, 1.0, 3.0]])  # but its rhs is not 2 x first
    with pytest.raises(ConstraintError, match="inconsistent"):
        receptance(K, M, C, A, w, R=R_bad)
    R_ok = np.array([[1.0, 1.0, 3.0], [2.0, 2.0, 6.0]])
    for method in FORMULATIONS:
        H = receptance(K, M, C, A, w, R=R_ok, method=method)
        np.testing.assert_allclose(A[:1] @ H, R_ok[:1], atol=1e-12)


def test_constrained_acceleration_eq5_matches_lagrange():
    rng = np.random.default_rng(7)
    M, C, K, _ = random_system(rng, 9)
    A = random_constraints(rng, 9, 3, redundant=1)
    b = A @ rng.standard_normal(9)          # consistent
    force = rng.standard_normal(9)
    qdd = constrained_acceleration(sp.csr_array(M), A, b, force)
    rows = independent_rows(A)
    Ak = A[rows.keep]
    kkt = np.block([[M, Ak.T], [Ak, np.zeros((rows.rank, rows.rank))]])
    ref = np.linalg.solve(kkt, np.concatenate([force, b[rows.keep]]))[:9]
    np.testing.assert_allclose(qdd, ref, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(A @ qdd, b, atol=1e-10)


def test_constrained_acceleration_eq10_semidefinite_mass():
    """Free-free absorber: massless boundary coordinate tied to a mass (eqs 6-10)."""
    rng = np.random.default_rng(3)
    M, C, K, massless = random_system(rng, 8, n_massless=2)
    A = random_constraints(rng, 8, 3, reach=massless)
    b = A @ rng.standard_normal(8)
    force = rng.standard_normal(8)
    qdd = constrained_acceleration(M, A, b, force)
    kkt = np.block([[M, A.T], [A, np.zeros((3, 3))]])
    ref = np.linalg.solve(kkt, np.concatenate([force, b]))[:8]
    np.testing.assert_allclose(qdd, ref, rtol=1e-9, atol=1e-11)
