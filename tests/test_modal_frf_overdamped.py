r"""The modal receptance and random response of models with over-damped and critically damped
modes, against references computed here without the modal sum.

* Over-damped modes give two real roots each, one entry each, so a damped model of ``n``
  coordinates has up to ``2 n`` entries: the 3-mass chain with a dashpot of 10 on the first
  mass has two complex pairs and two real roots (-2.07, -7.39).  The basis used to ask for at
  most ``n`` entries and dropped the root at -7.39 (``H(2) = 2.487e-02-2.812e-02i`` against
  the exact ``2.4736e-02-2.8626e-02i``).
* A critically damped mode (modal damping ratio 1) has a double root ``-omega`` with one
  eigenvector: the cluster of that root is summed on its invariant subspace
  (:mod:`substruct.analysis.frf.defective`); the reference is the closed form
  ``1 / (s + omega)^2`` of each mode.
* The AMLS basis of ``C = 1000 M`` has the slow roots ``-1e-3`` and ``-3e-3`` beside
  ``-1000``: computed by QR of the first-order matrix they lost seven digits, which the
  second-order residual's ``1 / lambda^3`` multiplied into a disagreement of 0.11.

With every root kept the modal sum is the receptance itself, so the bound is round-off: terms
of at most ``max 1 / |a_r (i w - lambda_r)|`` summed into ``H`` (a cancellation of at most
``1e3`` on these models, measured), times a few ``eps``: ``1e-11`` relative to ``max |H|``.  A
residual adds the rounding of its moments, :math:`\sum_k |X_k| \omega^k` (the Taylor
coefficients of ``H`` about 0, each the difference of a static solve and the kept roots' sums
of :math:`1 / \lambda_r^{k+1}`), which :func:`_moment_bound` computes here.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.linalg import null_space

from cli_helpers import DAMPED_THREE_MASS
from substruct.analysis.api import receptance_sweep
from substruct.analysis.frf.modal import ModalOptions, modal_basis
from substruct.case.loader import parse_case
from substruct.run.runner import run_case

ROUND_OFF = 1e-11
M3 = np.diag([1.0, 2.0, 4.0])
K3 = np.array([[20.0, -10, 0], [-10, 30, -20], [0, -20, 20]])
C3 = np.diag([10.0, 0, 0])


def _error(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.abs(a - b).max() / np.abs(b).max())


def _reference(M, C, K, A, w, E, O) -> np.ndarray:
    """``O T (T^T (K - w^2 M + i w C) T)^-1 T^T E``, ``T`` an orthonormal basis of null(A)."""
    T = null_space(A) if A.shape[0] else np.eye(K.shape[0])
    return np.array([O @ T @ np.linalg.solve(T.T @ (K - x * x * M + 1j * x * C) @ T, T.T @ E)
                     for x in w])


def _moment_bound(M, C, K, A, w, E, O) -> float:
    """``64 eps max_w sum_k S_k w^k / max |H|``, ``S_k`` the size of the terms that make the
    residual moments: ``|O X_k|`` (``X_0 = G E``, ``X_1 = -G C X_0``, ``X_2 = -G (M X_0 + C
    X_1)``, ``G`` the constrained flexibility ``T (T^T K T)^-1 T^T``) and the kept roots' sums
    ``|O u_r| |u_r^T E| / |a_r lambda_r^(k+1)|`` (a cluster's ``|(G_A^-1 G_B)^k G_A^-1|``),
    which cancel to the moment; the static solves carry the condition number of the
    constrained stiffness."""
    T = null_space(A) if A.shape[0] else np.eye(K.shape[0])
    G = T @ np.linalg.solve(T.T @ K @ T, T.T)
    kappa = float(np.linalg.cond(T.T @ K @ T))  # the static solves' error, eps kappa |X_k|
    X = [G @ E]
    X.append(-G @ C @ X[0])
    X.append(-G @ (M @ X[0] + C @ X[1]))
    basis = modal_basis(sp.csr_array(M), sp.csr_array(C), sp.csr_array(K), sp.csr_array(A),
                        float(np.max(w)), cutoff=1e6)
    P, Q = np.abs(O @ basis.shapes), np.abs(basis.shapes.T @ E)
    single = np.ones(basis.count, dtype=bool)
    for c in basis.clusters:
        single[c.index] = False
    top = max(float(np.abs(w).max()), 1.0)
    size = 0.0
    for k in range(3):
        f = np.where(single, 1 / np.abs(basis.norms * basis.eigenvalues ** (k + 1)), 0)
        terms = kappa * np.abs(O @ X[k]).max() + 2 * ((P * f) @ Q).max()
        for c in basis.clusters:
            Y = np.linalg.inv(c.GA)
            for _ in range(k):
                Y = np.linalg.solve(c.GA, c.GB @ Y)
            terms += 2 * (P[:, c.index] @ np.abs(Y) @ Q[c.index]).max()
        size += terms * top ** k
    H = _reference(M, C, K, A, w, E, O)
    return float(64 * np.finfo(float).eps * size / np.abs(H).max())


def _modal(M, C, K, A, w, E, O, **options) -> np.ndarray:
    return receptance_sweep(K, M, C, A, w, E, O, method="modal",
                            modal=ModalOptions(**options), tolerance=1e9).H


def test_three_masses_every_root_kept():
    basis = modal_basis(sp.csr_array(M3), sp.csr_array(C3), sp.csr_array(K3),
                        sp.csr_array((0, 3)), 2.0)
    real = np.sort(basis.eigenvalues[basis.eigenvalues.imag == 0].real)
    assert basis.count == 4 and real.size == 2
    # the real roots: zeros of det(lambda^2 M + lambda C + K) on the real axis
    for lam in real:
        assert abs(np.linalg.det(lam * lam * M3 + lam * C3 + K3)) < 1e-9 * np.abs(K3).max() ** 3
    np.testing.assert_allclose(real, [-7.393, -2.067], atol=1e-3)
    w = np.array([0.5, 1.0, 2.0])
    E, O = np.eye(3)[:, :1], np.eye(3)[:1]
    ref = _reference(M3, C3, K3, np.zeros((0, 3)), w, E, O)
    assert abs(ref[2, 0, 0] - (2.4736e-02 - 2.8626e-02j)) < 1e-6
    for solver in ("dense", "sparse"):
        for residual in ("none", "second-order"):
            H = _modal(M3, C3, K3, np.zeros((0, 3)), w, E, O, solver=solver,
                       residual=residual)
            assert _error(H, ref) < ROUND_OFF + _moment_bound(
                M3, C3, K3, np.zeros((0, 3)), w, E, O), (solver, residual)
    # a count past n: every entry up to 2 n
    H = _modal(M3, C3, K3, np.zeros((0, 3)), w, E, O, count=6, residual="none")
    assert _error(H, ref) < ROUND_OFF


def _mixed(seed: int):
    """A chain of 8 random masses with light and heavy dashpots (complex pairs and real
    roots), two constraint rows."""
    rng = np.random.default_rng(seed)
    n = 8
    k, c = rng.uniform(50, 200, n), rng.uniform(0.1, 1, n)
    c[[1, 5]] = rng.uniform(200, 400, 2)  # over-damped motions
    K, C = np.zeros((n, n)), np.zeros((n, n))
    for X, v in ((K, k), (C, c)):
        X[0, 0] += v[0]
        for i in range(1, n):
            X[i, i] += v[i]
            X[i - 1, i - 1] += v[i]
            X[i, i - 1] -= v[i]
            X[i - 1, i] -= v[i]
    M = np.diag(rng.uniform(0.5, 2, n))
    A = np.zeros((2, n))
    A[0, 2], A[0, 6] = 1.0, -1.0
    A[1, 3], A[1, 4] = 1.0, -0.5
    return M, C, K, A


@pytest.mark.parametrize("seed", [1, 2])
def test_mixed_model_every_root_kept(seed):
    M, C, K, A = _mixed(seed)
    basis = modal_basis(sp.csr_array(M), sp.csr_array(C), sp.csr_array(K), sp.csr_array(A),
                        30.0, cutoff=1e6)
    real = basis.eigenvalues.imag == 0
    assert 0 < real.sum() and (~real).sum() > 0
    assert 2 * (~real).sum() + real.sum() == 2 * (M.shape[0] - 2)  # every root of null(A)
    w = np.linspace(0.5, 30.0, 40)
    E, O = np.eye(8)[:, [0, 5]], np.eye(8)[[0, 2, 7]]
    ref = _reference(M, C, K, A, w, E, O)
    bound = ROUND_OFF + _moment_bound(M, C, K, A, w, E, O)
    for residual in ("none", "static", "second-order"):
        H = _modal(M, C, K, A, w, E, O, solver="dense", cutoff=1e6, residual=residual)
        assert _error(H, ref) < (ROUND_OFF if residual == "none" else bound), residual


def test_critically_damped_modes_closed_form():
    omega = np.array([1.5, 4.7, 7.9])
    M, K, C = np.eye(3), np.diag(omega ** 2), np.diag(2 * omega)  # zeta = 1 each
    Phi = np.linalg.qr(np.random.default_rng(3).standard_normal((3, 3)))[0]
    # the same model in other coordinates q = Phi x: the double roots are not diagonal there
    Mq, Kq, Cq = (Phi @ X @ Phi.T for X in (M, K, C))
    w = np.linspace(0.2, 12.0, 60)
    s = 1j * w
    closed = np.einsum("ir,jr,kr->kij", Phi, Phi, 1.0 / (s[:, None] + omega[None, :]) ** 2)
    H = _modal(Mq, Cq, Kq, np.zeros((0, 3)), w, np.eye(3), np.eye(3), residual="none",
               cutoff=10.0)
    assert _error(H, closed) < ROUND_OFF
    H = _modal(Mq, Cq, Kq, np.zeros((0, 3)), w, np.eye(3), np.eye(3))
    bound = _moment_bound(Mq, Cq, Kq, np.zeros((0, 3)), w, np.eye(3), np.eye(3))
    assert _error(H, closed) < ROUND_OFF + bound


ROD_RATIO_ONE = """
name: ratio_one
substructures:
  - {name: rod, type: rod, length: 1, EA: 1, m: 1, support: fixed-free,
     discretization: {method: fe, elements: 20}, reduce: {modes: 3, damping: {ratio: 1}}}
analysis:
  frf:
    omega: {start: 0.5, stop: 1.5707963, num: 7}
    inputs: [rod@1]
    outputs: [rod@1, rod@0.5]
    method: %s
output: {pictures: false}
"""


def test_critically_damped_rod_case_modal_equals_direct():
    modal = run_case(parse_case(ROD_RATIO_ONE % "modal", "ratio_one.yaml")).frf
    direct = run_case(parse_case(ROD_RATIO_ONE % "kkt", "ratio_one.yaml")).frf
    assert "6 root(s)" in modal.method
    assert _error(np.asarray(modal.H), np.asarray(direct.H)) < ROUND_OFF
    assert max(modal.agreement.values()) < ROUND_OFF


def test_amls_slow_overdamped_roots():
    M, K, C = np.eye(2), np.array([[2.0, -1], [-1, 2]]), 1000 * np.eye(2)
    w = np.array([0.5, 1.0, 2.0])
    E, O = np.eye(2)[:, :1], np.eye(2)
    ref = _reference(M, C, K, np.zeros((0, 2)), w, E, O)
    basis = modal_basis(sp.csr_array(M), sp.csr_array(C), sp.csr_array(K),
                        sp.csr_array((0, 2)), 2.0, solver="amls")
    # modes 1 and sqrt(3) with c = 1000: the slow roots -w^2 / (500 + sqrt(500^2 - w^2))
    slow = np.sort(basis.eigenvalues.real)[-2:]
    exact = -np.array([3.0, 1.0]) / (500 + np.sqrt(500 ** 2 - np.array([3.0, 1.0])))
    np.testing.assert_allclose(slow, exact, rtol=1e-12)
    H = _modal(M, C, K, np.zeros((0, 2)), w, E, O, solver="amls", residual="static")
    assert _error(H, ref) < ROUND_OFF
    # the second-order residual: G C G C G w^2 is 1e9 times |H| here, and its difference
    # from the kept roots' moments is that times eps (measured 7e-7, the dense basis alike)
    H = _modal(M, C, K, np.zeros((0, 2)), w, E, O, solver="amls")
    assert _error(H, ref) < ROUND_OFF + _moment_bound(M, C, K, np.zeros((0, 2)), w, E, O)


RANDOM = "\nname: rnd\n" + DAMPED_THREE_MASS + """\
analysis:
  random:
    frequencies: {start: 0.05, stop: 1, num: 50}
    forces: [{at: P@1, psd: [[0.05, 1], [1, 1]]}, {at: P@3, psd: [[0.05, 2], [1, 2]]}]
    outputs: [P@1, P@2]
    quantity: displacement
%s
output: {pictures: false}
"""


def test_random_response_of_the_overdamped_chain():
    modal = run_case(parse_case(RANDOM % "    method: modal", "rnd.yaml")).random
    f = np.linspace(0.05, 1, 50)
    H = _reference(M3, C3, K3, np.zeros((0, 3)), 2 * np.pi * f, np.eye(3)[:, [0, 2]],
                   np.eye(3)[:2])
    S = np.einsum("kip,p,kjp->kij", H, np.array([1.0, 2.0]), H.conj())
    assert "4 root(s)" in modal.method
    bound = ROUND_OFF + _moment_bound(M3, C3, K3, np.zeros((0, 3)), 2 * np.pi * f,
                                      np.eye(3)[:, [0, 2]], np.eye(3)[:2])
    assert _error(modal.psd, S) < 2 * bound  # |H|^2: twice the relative error of H
    rms = np.sqrt(np.trapezoid(np.real(np.einsum("kii->ki", S)), f, axis=0))
    np.testing.assert_allclose(modal.rms, rms, rtol=2 * bound)
