"""The shift-invert Lanczos solver on a cluster of nearly equal eigenvalues straddling the
wanted count (identical parts coupled weakly, as 50 copies of one superelement): the first
attempt does not converge within its restarts, a basis four times larger does, and the
eigenvalues and vectors are those of a dense solve; a problem that converges within the first
attempt is solved exactly as ARPACK alone solves it."""

from __future__ import annotations

import numpy as np
import scipy.linalg as sl
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import substruct.linalg.lanczos as lanczos
from substruct.linalg.lanczos import shift_invert_lanczos


def _cluster(parts: int, size: int = 30, spread: float = 1e-4):
    """``parts`` grounded spring chains of ``size`` masses each, the masses of each part
    perturbed by ``spread`` (relative), coupled by weak springs between neighbours: the lowest
    eigenvalue of every part forms a cluster of ``parts`` values within about ``spread``."""
    rng = np.random.default_rng(1)
    chain = sp.diags([-np.ones(size - 1), 2 * np.ones(size), -np.ones(size - 1)], [-1, 0, 1])
    K = sp.lil_array(sp.block_diag([chain] * parts))
    for p in range(parts - 1):  # a weak spring from the tip of a part to the next one
        i, j = p * size + size - 1, (p + 1) * size + size - 1
        for a, b, v in ((i, i, 1e-7), (j, j, 1e-7), (i, j, -1e-7), (j, i, -1e-7)):
            K[a, b] += v
    m = np.concatenate([np.full(size, 1.0 + spread * rng.uniform(-1, 1)) for _ in range(parts)])
    return sp.csc_array(K), sp.csc_array(sp.diags(m))


def _solve(K, M, sigma):
    lu = spla.splu(sp.csc_array(K - sigma * M))
    return lu.solve


def _counted(monkeypatch) -> list[dict]:
    calls: list[dict] = []
    real = spla.eigsh

    def eigsh(*args, **kwargs):
        calls.append({"ncv": kwargs.get("ncv"), "maxiter": kwargs.get("maxiter")})
        return real(*args, **kwargs)

    monkeypatch.setattr(lanczos.spla, "eigsh", eigsh)
    return calls


def test_a_cluster_straddling_k_converges_with_a_larger_basis(monkeypatch) -> None:
    K, M = _cluster(parts=40)
    calls = _counted(monkeypatch)
    lam, U = shift_invert_lanczos(K, M, 10, 0.0, _solve(K, M, 0.0),
                                  np.random.default_rng(0).standard_normal(K.shape[0]))
    # the default basis (21) did not converge in 50 restarts in the cluster of 40 (ARPACK
    # alone needs about 60 here, thousands for 20 coupled superelements); 84 converged
    assert [c["ncv"] for c in calls] == [None, 84]
    assert calls[0]["maxiter"] == lanczos.FIRST_ATTEMPT_RESTARTS
    ref = sl.eigh(K.toarray(), M.toarray(), eigvals_only=True, subset_by_index=[0, 9])
    np.testing.assert_allclose(np.sort(lam), ref, rtol=1e-10)
    # each vector an eigenvector to the working precision: |K u - lam M u| / |K u|
    res = np.abs(K @ U - (M @ U) * lam).max(axis=0) / np.abs(K @ U).max(axis=0)
    assert res.max() < 1e-8


def test_a_problem_that_converges_at_once_is_unchanged(monkeypatch) -> None:
    K, M = _cluster(parts=3)
    v0 = np.random.default_rng(0).standard_normal(K.shape[0])
    op = spla.LinearOperator(K.shape, matvec=_solve(K, M, 0.0), dtype=float)
    ref_lam, ref_U = spla.eigsh(K, k=4, M=M, sigma=0.0, which="LM", OPinv=op, v0=v0)
    calls = _counted(monkeypatch)
    lam, U = shift_invert_lanczos(K, M, 4, 0.0, _solve(K, M, 0.0), v0)
    assert len(calls) == 1
    assert np.array_equal(lam, ref_lam) and np.array_equal(U, ref_U)
