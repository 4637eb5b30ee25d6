"""Modal truncation (eqs 21-22)."""

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from substruct.models.discrete import free_free
from substruct.models.rod import paper_taper, rod_assumed_modes, rod_fe, uniform_rod_frequencies
from substruct.models.reduction import modal_truncation, undamped_modes
from substruct.substructure import Substructure, as_csr
from references import tapered_rod_frequency
from references import tapered_rod_frequency


def tapered_rod(n=8):
    EA, m = paper_taper(6e6, 1.0, 200.0)
    return rod_assumed_modes("rod", 200.0, EA, m, n)


def test_modes_are_mass_normalized_and_lowest():
    rod = tapered_rod()
    omega, Phi = undamped_modes(rod, 4)
    M, K = rod.M.toarray(), rod.K.toarray()
    assert np.allclose(Phi.T @ M @ Phi, np.eye(4), atol=1e-12)
    KPhi = Phi.T @ K @ Phi
    assert np.allclose(KPhi, np.diag(omega**2), rtol=1e-12, atol=1e-9 * omega[-1] ** 2)
    all_lam = sla.eigh(K, M, eigvals_only=True)
    assert np.allclose(omega**2, all_lam[:4], rtol=1e-12)
    # eight assumed modes: an upper bound (Rayleigh-Ritz) of the shooting solution of the
    # rod's differential equation (tests/references.py), close to it
    exact = tapered_rod_frequency(1)
    assert exact <= omega[0] <= exact * (1 + 1e-5)


def test_reduced_substructure():
    rod = tapered_rod()
    red = modal_truncation(rod, 4)
    omega, Phi = undamped_modes(rod, 4)
    assert red.dof_labels == ("y1", "y2", "y3", "y4")
    assert red.kind == "modal" and red.meta["reduced_from"] == 8 and red.meta["n_keep"] == 4
    assert np.array_equal(red.M.toarray(), np.eye(4))
    assert np.array_equal(red.K.toarray(), np.diag(omega**2))
    assert np.allclose(red.meta["omega"], omega)
    assert red.C.nnz == 0
    # points follow the modal coordinates: row(x) @ Phi
    x = 123.0
    assert np.allclose(red.row(x).toarray(), rod.row(x).toarray() @ Phi)
    q = Phi @ np.array([1.0, -2.0, 0.5, 0.0])
    assert np.allclose(red.geometry.displacement(np.array([1.0, -2.0, 0.5, 0.0])),
                       rod.geometry.displacement(q))


def test_rayleigh_damping_gives_alpha_plus_beta_lambda():
    rod = tapered_rod()
    alpha, beta = 0.3, 2e-4
    red = modal_truncation(rod, 4, damping={"rayleigh": (alpha, beta)})
    lam = red.meta["omega"] ** 2
    assert np.allclose(red.C.toarray(), np.diag(alpha + beta * lam), rtol=1e-14)
    # the same as projecting C = alpha M + beta K
    damped = Substructure(rod.name, rod.M, rod.K, as_csr(alpha * rod.M + beta * rod.K),
                          rod.dof_labels, rod.locate)
    projected = modal_truncation(damped, 4).C.toarray()
    assert np.allclose(projected, red.C.toarray(), rtol=1e-10, atol=1e-10 * red.C.max())


def test_modal_damping_ratios():
    rod = tapered_rod()
    red = modal_truncation(rod, 3, damping=0.02)
    omega = red.meta["omega"]
    assert np.allclose(red.C.toarray(), np.diag(0.04 * omega))
    red = modal_truncation(rod, 3, damping={"zeta": [0.01, 0.02, 0.05]})
    assert np.allclose(red.C.diagonal(), 2 * np.array([0.01, 0.02, 0.05]) * omega)
    with pytest.raises(ValueError, match="2 modal damping ratios for 3"):
        modal_truncation(rod, 3, damping=[0.1, 0.2])
    with pytest.raises(ValueError, match="rod.*>= 0"):
        modal_truncation(rod, 3, damping=-0.1)
    with pytest.raises(ValueError, match="rayleigh"):
        modal_truncation(rod, 3, damping={"viscous": 1.0})


@pytest.mark.parametrize("n_keep", [0, 9, -1])
def test_bad_n_keep(n_keep):
    with pytest.raises(ValueError, match=f"rod: n_keep = {n_keep}.* 8 coordinates"):
        modal_truncation(tapered_rod(), n_keep)


def test_massless_coordinates_rejected():
    with pytest.raises(ValueError, match="absorber: modal truncation needs M positive definite"):
        modal_truncation(free_free("absorber", 1.0, 100.0), 1)


@pytest.mark.parametrize("support", ["fixed-free", "free-free"])
def test_sparse_shift_invert_matches_dense(support):
    """A 400-DOF P1 rod: eigsh with SuperLU OPinv equals dense eigh (forced by dense_limit)."""
    rod = rod_fe("rod", 1.0, 1.0, 1.0, 400, order=1, support=support)
    w_sparse, P_sparse = undamped_modes(rod, 5, dense_limit=10)
    w_dense, P_dense = undamped_modes(rod, 5)
    assert np.allclose(w_sparse, w_dense, rtol=1e-10, atol=1e-5)
    assert np.allclose(P_sparse, P_dense, atol=1e-8)  # same sign convention
    M = rod.M
    assert np.allclose(P_sparse.T @ (M @ P_sparse), np.eye(5), atol=1e-12)
    exact = uniform_rod_frequencies(1.0, 1.0, 1.0, 5, support)
    assert np.allclose(w_sparse[1:], exact[1:], rtol=1e-4)


def test_sparse_path_uses_given_factorization():
    rod = rod_fe("rod", 1.0, 1.0, 1.0, 200, order=2)
    calls = []

    def factorize(A):
        calls.append(A.shape)
        lu = spla.splu(sp.csc_matrix(A))
        return lu.solve

    red = modal_truncation(rod, 3, dense_limit=10, factorization=factorize)
    assert calls == [(400, 400)]
    assert np.allclose(red.meta["omega"], uniform_rod_frequencies(1, 1, 1, 3), rtol=1e-8)


def test_free_part_elastic_modes_to_round_off():
    """A free-free solid (six rigid-body modes) truncated by shift-invert Lanczos: its elastic
    modes satisfy ``K phi = w^2 M phi`` to round-off (3.9e-14 measured; 1.7e-9 before the
    rigid-body modes were deflated from the operator, whose largest eigenvalue they were)."""
    import scipy.sparse as sp

    from substruct.models.reduction import undamped_modes
    from substruct.models.solid import BoxGrid, solid_box

    b = solid_box("b", BoxGrid((1.0, 0.4, 0.3), (10, 4, 3)), 2.1e11, 0.3, 7850.0)
    K, M = sp.csr_array(b.K), sp.csr_array(b.M)
    w, Phi = undamped_modes(b, 20, dense_limit=10)
    assert np.all(w[:6] < 1e-6 * w[6])                  # six rigid-body modes
    R = K @ Phi[:, 6:] - (M @ Phi[:, 6:]) * w[6:] ** 2
    rel = np.linalg.norm(R, axis=0) / np.linalg.norm(K @ Phi[:, 6:], axis=0)
    assert rel.max() < 1e-11, rel.max()
