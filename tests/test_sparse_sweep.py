"""The production receptance sweep (issue 13): the null-space form on a sparse master-slave
basis, band or sparse LU per frequency, against the KKT and generalized-inverse sweeps of every
frequency; the checks at a few frequencies; singular frequencies refused."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

import substruct.analysis.frf.sparse as sweep
from substruct.analysis.api import receptance_sweep
from substruct.analysis.formulations.coupling import receptance
from substruct.analysis.errors import CheckError
from substruct.analysis.frf.production import check_frequencies
from substruct.analysis.frf.sparse import null_space_sparse_sweep


def chains(n: int = 60, k: float = 1e4, m: float = 1.0):
    """Two fixed-free chains of ``n`` masses tied tip to tip, Rayleigh damping."""
    d = np.full(n, 2 * k)
    d[-1] = k
    Kc = sp.diags_array([-np.full(n - 1, k), d, -np.full(n - 1, k)], offsets=[-1, 0, 1])
    K = sp.csr_array(sp.block_diag([Kc, Kc]))
    M = sp.csr_array(sp.eye_array(2 * n) * m)
    C = sp.csr_array(1e-4 * K + 0.5 * M)
    A = sp.csr_array(([1.0, -1.0], ([0, 0], [n - 1, 2 * n - 1])), shape=(1, 2 * n))
    return K, M, C, A


@pytest.mark.parametrize("band", [True, False])
def test_sweep_equals_the_kkt_sweep_for_all_inputs_and_outputs(band, monkeypatch):
    if not band:
        monkeypatch.setattr(sweep, "BAND_MAX", -1)  # the sparse LU path
    K, M, C, A = chains()
    n = K.shape[0]
    w = np.linspace(1.0, 150.0, 37)
    E, O = sp.eye_array(n).tocsc(), sp.eye_array(n).tocsr()
    H = null_space_sparse_sweep(K, M, C, A, w, E, O)
    ref = receptance(K, M, C, A, w, method="kkt", inputs=E, outputs=O)
    assert np.abs(H - ref).max() / np.abs(ref).max() < 1e-9
    # the tie holds: the two tip coordinates move alike under every force
    np.testing.assert_allclose(H[:, n // 2 - 1], H[:, n - 1], rtol=0, atol=1e-14 * abs(H).max())


def test_outputs_at_eliminated_and_interpolated_points(monkeypatch):
    K, M, C, A = chains(40)
    n = K.shape[0]
    w = np.array([3.0, 40.0, 120.0])
    rng = np.random.default_rng(1)
    O = sp.csr_array(np.vstack([np.eye(n)[[39, 79, 5]],
                                0.3 * np.eye(n)[10] + 0.7 * np.eye(n)[11]]))
    E = sp.csc_array(rng.standard_normal((n, 3)))
    for band in (32, -1):
        monkeypatch.setattr(sweep, "BAND_MAX", band)
        H = null_space_sparse_sweep(K, M, C, A, w, E, O)
        ref = receptance(K, M, C, A, w, method="generalized-inverse", inputs=E, outputs=O)
        assert np.abs(H - ref).max() / np.abs(ref).max() < 1e-9


def test_receptance_sweep_takes_the_production_path_and_checks_three_frequencies():
    K, M, C, A = chains()
    n = K.shape[0]
    w = np.linspace(1.0, 150.0, 25)
    E, O = sp.eye_array(n, format="csc")[:, :4], sp.eye_array(n).tocsr()
    res = receptance_sweep(K, M, C, A, w, E, O, checks=("kkt",))
    assert res.method == "null-space/sparse"
    assert set(res.agreement) == {"generalized-inverse", "kkt"}
    assert max(res.agreement.values()) < 1e-9 and res.constraint_residual < 1e-12
    assert list(check_frequencies(25)) == [0, 12, 24] and list(check_frequencies(2)) == [0, 1]
    ref = receptance(K, M, C, A, w, method="kkt", inputs=E, outputs=O)
    assert np.abs(res.H - ref).max() / np.abs(ref).max() < 1e-9


def test_a_check_that_disagrees_fails_the_production_sweep(monkeypatch):
    import substruct.analysis.frf.production as production_sweep
    K, M, C, A = chains()
    n = K.shape[0]
    real = production_sweep.receptance

    def off(*args, method, **kwargs):
        return real(*args, method=method, **kwargs) * (1 + 1e-4)
    monkeypatch.setattr(production_sweep, "receptance", off)
    with pytest.raises(CheckError, match="kkt disagrees with null-space/sparse by 1.0e-04"):
        receptance_sweep(K, M, C, A, [1.0, 2.0], sp.eye_array(n, format="csc")[:, :1],
                         sp.eye_array(n).tocsr(), method="kkt")


def test_a_singular_frequency_is_refused(monkeypatch):
    """A free-free pair at omega = 0: ``Z_T = K`` is singular (the rigid-body motion)."""
    K = sp.csr_array(np.array([[1.0, -1.0], [-1.0, 1.0]]))
    M = sp.csr_array(np.eye(2))
    E, O = sp.eye_array(2, format="csc"), sp.eye_array(2, format="csr")
    for band in (32, -1):
        monkeypatch.setattr(sweep, "BAND_MAX", band)
        with pytest.raises(ValueError, match="singular at omega = 0 rad/s"):
            null_space_sparse_sweep(K, M, None, sp.csr_array((0, 2)), [0.0], E, O)
