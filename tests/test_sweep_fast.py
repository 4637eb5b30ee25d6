"""The fast paths of the production receptance sweep (issue 13) held to an independent
formulation: the dense inverse of the whole KKT matrix ``[[Z, A^T], [A, 0]]`` at a few
frequencies; the band solves with many right-hand sides (compiled substitutions) against dense
solves; the output gather against ``O X``."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp

import substruct.analysis.frf.sparse as sweep
from substruct.analysis.frf.sparse import Gather, null_space_sparse_sweep
from substruct.linalg.banded import (
    band_factor,
    band_solve_many,
    band_storage,
    kernel_pays,
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
    w = np.linspace(1.0, 150.0, 400)
    E, O = sp.eye_array(n, format="csc"), sp.eye_array(n, format="csr")
    assert kernel_pays(n - 1, n, w.size)  # the compiled substitutions
    H = null_space_sparse_sweep(K, M, C, A, w, E, O)
    idx = [0, 133, 270, 399]
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


@pytest.mark.parametrize("b, n", [(0, 60), (1, 60), (3, 60), (3, 2), (1, 1)])
def test_band_solve_many_with_pivoting_equals_dense_solves(b, n):
    rng = np.random.default_rng(b + n)
    p = 7
    for _ in range(4):  # small diagonal: partial pivoting swaps rows
        Z = sp.csr_array(sum(sp.diags_array(rng.standard_normal(n - abs(d)) + 1j *
                                            rng.standard_normal(n - abs(d)), offsets=d)
                             for d in range(-b, b + 1) if abs(d) < n))
        rhs = rng.standard_normal((n, p)) + 1j * rng.standard_normal((n, p))
        x = np.full_like(rhs, np.nan)
        band_solve_many(band_storage(Z, b).astype(complex), b, rhs, x)
        if b and n > 10:
            assert np.any(band_factor(band_storage(Z, b).astype(complex), b)[1] !=
                          np.arange(n))
        np.testing.assert_allclose(x, sla.solve(Z.toarray(), rhs), rtol=0,
                                   atol=1e-10 * np.abs(x).max())


def test_singular_band_matrix_is_refused():
    ab = band_storage(sp.diags_array([1.0, 0.0, 2.0, 1.0]), 1).astype(complex)
    with pytest.raises(np.linalg.LinAlgError, match="zero pivot 2"):
        band_solve_many(ab, 1, np.ones((4, 3), dtype=complex), np.empty((4, 3), dtype=complex))


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
    """One input: the compiled substitutions would not pay for loading Numba; LAPACK's gbsv a
    frequency at a time."""
    K, M, C, A = chains(40)
    n = K.shape[0]
    assert not kernel_pays(n - 1, 1, 100)
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


def test_kernel_compiles_without_a_cache_directory(monkeypatch):
    """Where Numba finds no writable cache directory it refuses ``cache=True``; the kernel is
    then compiled in the process and gives the same solution."""
    from numba.core.dispatcher import Dispatcher

    from substruct.linalg import band_kernel

    def refuse(self, *args, **kwargs):
        raise RuntimeError("cannot cache function: no locator available")
    monkeypatch.setattr(Dispatcher, "enable_caching", refuse)
    kernel = band_kernel.compiled(band_kernel.band_substitute_python)
    Z = sp.csr_array(sp.diags_array([np.full(5, 1.0 + 1j), np.full(6, 4.0), np.full(5, 1.0)],
                                    offsets=[-1, 0, 1]))
    lu, piv = band_factor(band_storage(Z, 1).astype(complex), 1)
    x = np.empty((6, 6), dtype=complex)
    kernel(lu, np.asarray(piv, dtype=np.int64), 1, np.eye(6, dtype=complex), x)
    np.testing.assert_allclose(x, np.linalg.inv(Z.toarray()), rtol=0, atol=1e-14)


@pytest.mark.parametrize("n_chain", [80, 20])  # 160 coordinates: production path; 40: direct
def test_constraint_residual_does_not_depend_on_a_row_scale(n_chain):
    """The reported ``max |D A u| / max |H|`` is that of unit-norm rows: a tie row scaled by
    1e8 leaves it at round-off, on the production path (more than 100 coordinates) and on
    the direct formulations (fewer)."""
    from substruct.analysis.api import receptance_sweep
    from substruct.analysis.frf.production import SWEEP_SPARSE_ABOVE

    K, M, C, A = chains(n_chain)
    n = K.shape[0]
    w = np.array([3.0, 40.0, 90.0])
    E, O = sp.eye_array(n, format="csc")[:, :5], sp.eye_array(n, format="csr")[:5]
    one = receptance_sweep(K, M, C, A, w, E, O)
    big = receptance_sweep(K, M, C, sp.csr_array(1e8 * A), w, E, O)
    assert (one.method == "null-space/sparse") == (n > SWEEP_SPARSE_ABOVE)
    np.testing.assert_allclose(big.H, one.H, rtol=0, atol=1e-10 * np.abs(one.H).max())
    assert one.constraint_residual < 1e-12 and big.constraint_residual < 1e-12


def test_checks_solve_a_spread_sample_of_many_inputs_and_catch_a_wrong_column(monkeypatch):
    """With more than CHECK_INPUTS inputs the check formulations solve that many, the first and
    last included; a production answer wrong in one sampled column fails the check."""
    import substruct.analysis.api as api
    from substruct.analysis.errors import CheckError
    from substruct.analysis.frf.production import CHECK_INPUTS, checked_inputs

    cols = checked_inputs(400)
    assert cols.size == CHECK_INPUTS and cols[0] == 0 and cols[-1] == 399
    assert np.all(np.diff(cols) >= 6)  # spread, not a block
    np.testing.assert_array_equal(checked_inputs(10), np.arange(10))
    K, M, C, A = chains(100)
    n = K.shape[0]
    w = np.array([2.0, 30.0, 80.0])
    E, O = sp.eye_array(n, format="csc"), sp.eye_array(n, format="csr")[:7]
    res = api.receptance_sweep(K, M, C, A, w, E, O)
    assert res.agreement["generalized-inverse"] < 1e-10
    from substruct.analysis.frf import production   # api imports it when a sweep runs
    real = production.production_sweep

    def wrong(*args, **kwargs):
        H, checked = real(*args, **kwargs)  # the checks read the checked frequencies
        checked[:, :, checked_inputs(n)[5]] *= 1.001
        return H, checked
    monkeypatch.setattr(production, "production_sweep", wrong)
    with pytest.raises(CheckError, match="generalized-inverse"):
        api.receptance_sweep(K, M, C, A, w, E, O)
