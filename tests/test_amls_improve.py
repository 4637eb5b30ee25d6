"""The blocked subspace iteration of AMLS (substruct.linalg.amls_improve) against the textbook
form it replaces: ``W = (K - sigma M)^{-1} M U`` and a full Rayleigh-Ritz after every step,
on whole ``n x p`` arrays.

With more vectors than one column block (``p > SOLVE_COLUMNS``) the blocked form spans the same
subspace (a Cholesky QR between steps instead of a Rayleigh-Ritz changes the basis, not its
span), so the Ritz values agree to round-off of the projected eigenproblem (1e-10 relative,
its condition times eps), the vectors are M-orthonormal (1e-10) and equal the reference's up
to sign on simple eigenvalues.  Only those up to ``lam_max`` come back.  The upper-triangle
projection equals ``W.T @ (A @ W)`` to round-off of the products.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp

from substruct.linalg.amls_improve import SOLVE_COLUMNS, projection, subspace_iteration
from substruct.linalg.factorize import factorizer
from substruct.models.solid import BoxGrid, solid_box


@pytest.fixture(scope="module")
def pencil():
    b = solid_box("b", BoxGrid((4.0, 1.0, 1.0), (16, 4, 4)), 2.1e11, 0.3, 7850.0,
                  fixed=[{"box": [[0, 0, 0], [0, 1, 1]]}])
    K, M = sp.csr_array(b.K), sp.csr_array(b.M)
    lam = sla.eigh(K.toarray(), M.toarray(), eigvals_only=True)
    return K, M, lam


def reference(K, M, U, solve, iterations):
    lam = None
    for _ in range(iterations):
        W = np.asarray(solve(M @ U)).reshape(U.shape)
        kr, mr = W.T @ (K @ W), W.T @ (M @ W)
        lam, rot = sla.eigh((kr + kr.T) / 2, (mr + mr.T) / 2)
        U = W @ rot
    return lam, U


def test_projection_is_the_full_product(pencil):
    K, _, _ = pencil
    W = np.random.default_rng(1).standard_normal((K.shape[0], SOLVE_COLUMNS + 70))
    full = W.T @ (K @ W)
    P = projection(K, W)
    assert np.array_equal(P, P.T)
    assert np.abs(P - full).max() < 1e-12 * np.abs(full).max()


@pytest.mark.parametrize("iterations", [1, 2, 3])
def test_blocked_iteration_equals_the_whole_array_form(pencil, iterations):
    K, M, lam = pencil
    n, p = K.shape[0], SOLVE_COLUMNS + 72          # two column blocks, the second partial
    U0 = np.random.default_rng(0).standard_normal((n, p))
    sigma = -1e-3 * lam[0]
    solve = factorizer("auto")(sp.csc_array(K - sigma * M))
    lam_max = 0.5 * (lam[39] + lam[40])
    ref_lam, ref_U = reference(K, M, U0.copy(), solve, iterations)
    got_lam, got_U = subspace_iteration(K, M, U0.copy(), solve, iterations, lam_max)
    keep = ref_lam <= lam_max
    assert got_lam.size == keep.sum() > 0
    assert np.allclose(got_lam, ref_lam[keep], rtol=1e-10, atol=0)
    assert np.allclose(got_U.T @ (M @ got_U), np.eye(got_lam.size), atol=1e-10)
    simple = np.ones(got_lam.size, dtype=bool)
    close = np.isclose(got_lam[1:], got_lam[:-1], rtol=1e-6)
    simple[1:] &= ~close
    simple[:-1] &= ~close
    R = ref_U[:, keep]
    dots = np.abs(np.einsum("ij,ij->j", got_U, M @ R))[simple]
    assert np.allclose(dots, 1.0, atol=1e-8)
    # Rayleigh-Ritz values: upper bounds of the exact eigenvalues, to the round-off of the
    # dense reference, whose eigenvalues are exact to a few eps times the largest (measured:
    # 10 eps lam_max below on one OpenBLAS kernel, 6 on another); bound 1000 eps lam_max
    floor = 1e3 * np.finfo(float).eps * lam.max()
    assert np.all(got_lam >= lam[:got_lam.size] - floor)
