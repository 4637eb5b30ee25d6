"""The fast paths of the production receptance sweep (issue 13) held to an independent
formulation: the dense inverse of the whole KKT matrix ``[[Z, A^T], [A, 0]]`` at a few
frequencies; the batched band solve against dense solves; the output gather against ``O X``."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp

import substruct.analysis.sparse_sweep as sweep
from substruct.analysis.sparse_sweep import Gather, null_space_sparse_sweep
from substruct.linalg.banded import (
    band_factor_batch,
    band_solve_batch,
    band_storage,
    batch_size,
)


def kkt_inverse(K, M, C, A, w, E, O) -> np.ndarray:
    """``O [I 0] [[Z, A^T], [A, 0]]^{-1} [E; 0]`` by a dense inverse, a frequency at a time."""
    n, m = K.shape[0], A.shape[0]
    out = []
    for wk in w:
        Z = (K - wk**2 * M + 1j * wk * C).toarray()
        G = np.block([[Z, A.toarray().T], [A.toarray(), np.zeros((m, m))]])
        Ginv = np.linalg.inv(G)
        out.append(O.toarray() @ Ginv[:n, :n] @ E.toarray())
    return np.array(out)


def chains(n: int = 200, k: float = 1e4):
    d = np.full(n, 2 * k)
    d[-1] = k
    Kc = sp.diags_array([-np.full(n - 1, k), d, -np.full(n - 1, k)], offsets=[-1, 0, 1])
    K = sp.csr_array(sp.block_diag([Kc, Kc]))
    M = sp.csr_array(sp.eye_array(2 * n))
    C = sp.csr_array(1e-4 * K + 0.5 * M)
    A = sp.csr_array(([1.0, -1.0], ([0, 0], [n - 1, 2 * n - 1])), shape=(1, 2 * n))
    return K, M, C, A


def random_assembly(n: int = 150, m: int = 6, seed: int = 3):
    """A damped assembly with a scattered (non-banded) pattern: SPD ``K`` and ``M`` from random
    sparse factors, a non-proportional ``C``, ``m`` random dense-ish constraint rows."""
    rng = np.random.default_rng(seed)
    G = sp.random_array((n, n), density=0.03, rng=rng) + sp.eye_array(n)
    K = sp.csr_array(G @ G.T * 1e3 + sp.eye_array(n))
    H = sp.random_array((n, n), density=0.01, rng=rng)
    M = sp.csr_array(H @ H.T + sp.eye_array(n))
    D = sp.random_array((n, n), density=0.02, rng=rng)
    C = sp.csr_array(D @ D.T * 0.5 + 0.01 * K)
    A = sp.csr_array(sp.random_array((m, n), density=0.1, rng=rng))
    return K, M, C, A


def test_chains_match_the_dense_kkt_inverse():
    K, M, C, A = chains()
    n = K.shape[0]
    w = np.linspace(1.0, 150.0, 40)  # one batch of the band path and part of another
    E, O = sp.eye_array(n, format="csc"), sp.eye_array(n, format="csr")
    assert batch_size(n - 1, n, w.size) > 1
    H = null_space_sparse_sweep(K, M, C, A, w, E, O)
    idx = [0, 13, 27, 39]
    ref = kkt_inverse(K, M, C, A, w[idx], E, O)
    assert np.abs(H[idx] - ref).max() / np.abs(ref).max() < 1e-9


def test_random_scattered_assembly_matches_the_dense_kkt_inverse():
    K, M, C, A = random_assembly()
    n = K.shape[0]
    rng = np.random.default_rng(7)
    w = np.array([0.5, 3.0, 11.0, 40.0])
    E = sp.csc_array(np.hstack([np.eye(n)[:, :50], rng.standard_normal((n, 3))]))
    O = sp.csr_array(np.vstack([np.eye(n)[::3], rng.standard_normal((2, n))]))
    H = null_space_sparse_sweep(K, M, C, A, w, E, O)
    ref = kkt_inverse(K, M, C, A, w, E, O)
    assert np.abs(H - ref).max() / np.abs(ref).max() < 1e-9


@pytest.mark.parametrize("b", [0, 1, 3])
def test_batched_band_solve_with_pivoting_equals_dense_solves(b):
    rng = np.random.default_rng(b)
    n, F, p = 60, 5, 7
    mats = []
    for _ in range(F):  # small diagonal: partial pivoting swaps rows
        Z = sum(sp.diags_array(rng.standard_normal(n - abs(d)) + 1j * rng.standard_normal(
            n - abs(d)), offsets=d) for d in range(-b, b + 1))
        mats.append(sp.csr_array(Z))
    ab = np.array([band_storage(Z, b) for Z in mats], dtype=complex)
    rhs = rng.standard_normal((n, p)) + 1j * rng.standard_normal((n, p))
    piv = band_factor_batch(ab, b)
    if b:
        assert np.any(piv != np.arange(n))
    out = np.empty((n, F, p), dtype=complex)
    band_solve_batch(ab, piv, b, rhs, out)
    for f, Z in enumerate(mats):
        np.testing.assert_allclose(out[:, f], sla.solve(Z.toarray(), rhs), rtol=0,
                                   atol=1e-10 * np.abs(out[:, f]).max())


def test_singular_matrix_in_a_batch_is_named():
    ab = np.array([band_storage(sp.eye_array(4), 1), np.zeros((4, 4))], dtype=complex)
    with pytest.raises(np.linalg.LinAlgError) as info:
        band_factor_batch(ab, 1)
    assert info.value.args[1] == 1


def test_gather_runs_scaled_scattered_and_mixed_rows():
    rng = np.random.default_rng(5)
    n, p = 30, 4
    X = rng.standard_normal((n, 3, p))[:, 1]  # rows C-contiguous, strided like a batch
    rows = [np.eye(n)[i] for i in range(20, 10, -1)]  # a reversed run
    rows += [np.eye(n)[i] for i in range(0, 5)]  # a forward run
    rows += [2.5 * np.eye(n)[7], np.eye(n)[3], 0.3 * np.eye(n)[1] + 0.7 * np.eye(n)[2]]
    O = sp.csr_array(np.array(rows))
    g = Gather(O)
    assert len(g.runs) >= 2 and g.unit is None
    out = np.empty((O.shape[0], p))
    g(X, out)
    np.testing.assert_allclose(out, O @ X, rtol=0, atol=1e-14)
    scattered = sp.csr_array(np.eye(n)[rng.permutation(n)])
    g = Gather(scattered)
    assert g.unit is not None
    out = np.empty((n, p))
    g(X, out)
    np.testing.assert_allclose(out, scattered @ X, rtol=0, atol=0)


def test_few_inputs_take_the_per_frequency_band_solve(monkeypatch):
    """One input: rows of a batch would be too short, LAPACK's gbsv a frequency at a time."""
    K, M, C, A = chains(40)
    n = K.shape[0]
    assert batch_size(n - 1, 1, 100) == 0
    real, called = sweep.band_solve, []

    def counted(*args):
        called.append(1)
        return real(*args)
    monkeypatch.setattr(sweep, "band_solve", counted)
    w = np.array([2.0, 60.0])
    E, O = sp.eye_array(n, format="csc")[:, [5]], sp.eye_array(n, format="csr")
    H = null_space_sparse_sweep(K, M, C, A, w, E, O)
    ref = kkt_inverse(K, M, C, A, w, E, O)
    assert np.abs(H - ref).max() / np.abs(ref).max() < 1e-9
    assert len(called) == 2
