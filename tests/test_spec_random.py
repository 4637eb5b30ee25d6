"""Random vibration, base-driven FRF and loss-factor damping against closed forms and
independent formulations (Miles' equation, the Lyapunov covariance of the state-space model,
the partitioned dynamic stiffness, the quadratic formula)."""

import numpy as np

import pytest
import scipy.linalg as sla
import scipy.sparse as sp

from substruct.analysis.api import receptance_sweep
from substruct.analysis.errors import AnalysisInputError
from substruct.analysis.frf.base_drive import RELATIVE, base_drive_sweep
from substruct.analysis.system import SweepOptions
from substruct.analysis.frf.random import (
    check_psd_table,
    check_spectral_matrix,
    interpolate_psd,
    mean_square,
    miles_absolute_rms,
    miles_rms,
    response_psd,
    rms,
)
from substruct.analysis.frf.structural import LossFactor, hysteretic_sweep, modal_loss_factors


def spring(n, i, j, k):
    """Stiffness ``k`` between coordinates ``i`` and ``j`` (``j`` None: to ground)."""
    K = np.zeros((n, n))
    K[i, i] += k
    if j is not None:
        K[j, j] += k
        K[i, j] -= k
        K[j, i] -= k
    return K


# --------------------------------------------------------------------- base drive


def sdof_on_base(k=400.0, m=1.0, zeta=0.05, base_mass=0.0):
    wn = np.sqrt(k / m)
    K = spring(2, 0, 1, k)
    C = spring(2, 0, 1, 2 * zeta * wn * m)
    return K, np.diag([base_mass, m]), C, np.array([[1.0, 0.0]]), wn


@pytest.mark.parametrize("base_mass", [0.0, 3.0])
def test_sdof_transmissibility_exact(base_mass):
    """T = (1 + 2 i zeta r) / (1 - r^2 + 2 i zeta r) by the paper's R and the relative form."""
    zeta = 0.05
    K, M, C, A, wn = sdof_on_base(zeta=zeta, base_mass=base_mass)
    w = np.linspace(0.5, 4 * wn, 121)
    res = base_drive_sweep(K, M, C, A, w, np.array([[1.0]]), np.array([[0.0, 1.0]]),
                           options=SweepOptions(checks=["null-space", "kkt"]))
    r = w / wn
    exact = (1 + 2j * zeta * r) / (1 - r ** 2 + 2j * zeta * r)
    assert np.abs(res.H[:, 0, 0] - exact).max() <= 1e-12 * np.abs(exact).max()
    assert set(res.agreement) == {"null-space", "kkt", RELATIVE}
    # per base acceleration: the same divided by -omega^2
    acc = base_drive_sweep(K, M, C, A, w, np.array([[1.0]]), np.array([[0.0, 1.0]]),
                           per="acceleration")
    assert np.allclose(acc.H[:, 0, 0] * -(w ** 2), exact, rtol=1e-12, atol=0)


def test_sdof_transmissibility_loss_factor():
    """K (1 + i eta): T = (1 + i eta) / (1 - r^2 + i eta)."""
    eta = 0.08
    K, M, _, A, wn = sdof_on_base()
    w = np.linspace(1.0, 3 * wn, 120)
    res = base_drive_sweep(K, M, None, A, w, np.array([[1.0]]), np.array([[0.0, 1.0]]),
                           loss=[LossFactor(eta, sp.csr_array(K))],
                           options=SweepOptions(checks=["kkt"]))
    r = w / wn
    exact = (1 + 1j * eta) / (1 - r ** 2 + 1j * eta)
    assert np.abs(res.H[:, 0, 0] - exact).max() <= 1e-12 * np.abs(exact).max()


def test_two_supports_against_partitioned_stiffness():
    """base1 - k1 - m1 - k2 - m2 - k3 - base2, both bases moved independently: the free
    response is -Z_ff^-1 Z_fb g, Z = K + i w C - w^2 M."""
    n = 4  # 0: base1, 1: m1, 2: m2, 3: base2
    K = spring(n, 0, 1, 300.0) + spring(n, 1, 2, 150.0) + spring(n, 2, 3, 500.0)
    C = 0.01 * K + np.diag([0, 0.3, 0.2, 0])
    M = np.diag([0.0, 1.5, 0.7, 0.0])
    A = np.array([[1.0, 0, 0, 0], [0, 0, 0, 2.0]])  # the second row scaled: E follows it
    E = np.array([[1.0, 0.0], [0.0, 2.0]])
    w = np.linspace(1.0, 60.0, 80)
    res = base_drive_sweep(K, M, C, A, w, E, np.eye(n)[[1, 2]],
                           options=SweepOptions(checks=["null-space"]))
    free, held = [1, 2], [0, 3]
    for k, wk in enumerate(w):
        Z = K + 1j * wk * C - wk ** 2 * M
        T = -np.linalg.solve(Z[np.ix_(free, free)], Z[np.ix_(free, held)])
        assert np.allclose(res.H[k], T, rtol=1e-11, atol=1e-12 * np.abs(T).max())


@pytest.mark.filterwarnings("ignore::Warning")
def test_base_drive_mechanism_refused():
    """A free mass not held by the moving support: no influence vector."""
    K = spring(3, 0, 1, 100.0)
    M = np.diag([0.0, 1.0, 1.0])
    with pytest.raises(AnalysisInputError):
        base_drive_sweep(K, M, None, np.array([[1.0, 0, 0]]), [1.0, 2.0],
                         np.array([[1.0]]), np.array([[0, 1.0, 0]]))


# --------------------------------------------------------------------- random vibration


def resonance_grid(fns, lo, hi, n_geo=300, n_band=200, width=0.5):
    """A geometric grid from lo to hi joined with a linear band fn (1 +- width) at each
    natural frequency (the half-power band of zeta = 0.05 gets 20 points)."""
    parts = [np.geomspace(lo, hi, n_geo)]
    parts += [np.linspace(fn * (1 - width), fn * (1 + width), n_band) for fn in fns]
    return np.unique(np.concatenate(parts))


def test_miles_sdof_white_base_acceleration():
    """Relative displacement, pseudo-acceleration (Miles) and absolute acceleration RMS of a
    SDOF under white base acceleration W (one-sided, per Hz) against the closed forms.

    Bound: the trapezoid on 500 points (resonance_grid: 20 in the half-power band) and the
    missed tails (below 1e-3 fn: 8 zeta fn / omega_n 1e-3 = 6e-5 of the variance) leave
    under 1e-4 of the RMS (2e-5 measured for the relative displacement of the closed-form
    curve on this grid), so 2e-4 separates Miles (pseudo-acceleration) from the absolute
    acceleration (they differ by sqrt(1 + 1/Q^2) - 1 = 5e-3 at Q = 10)."""
    zeta, W = 0.05, 0.04 * 9.80665 ** 2  # 0.04 g^2/Hz in (m/s^2)^2/Hz
    Q = 1 / (2 * zeta)
    K, M, C, A, wn = sdof_on_base(zeta=zeta)
    fn = wn / (2 * np.pi)
    f = resonance_grid([fn], 1e-3 * fn, 1e3 * fn)
    w = 2 * np.pi * f
    H = base_drive_sweep(K, M, C, A, w, np.array([[1.0]]), np.array([[0.0, 1.0]]),
                         per="acceleration").H  # output displacement per base acceleration
    rel = H + 1 / w[:, None, None] ** 2  # z = x - g, g = -a / w^2
    absacc = -(w ** 2)[:, None, None] * H
    S = np.full(len(f), W)
    z_rms = rms(f, response_psd(rel, S)[:, 0, 0].real)
    assert z_rms == pytest.approx(np.sqrt(Q * W / (32 * np.pi ** 3 * fn ** 3)), rel=2e-4)
    assert wn ** 2 * z_rms == pytest.approx(miles_rms(fn, Q, W), rel=2e-4)
    a_rms = rms(f, response_psd(absacc, S)[:, 0, 0].real)
    assert a_rms == pytest.approx(miles_absolute_rms(fn, Q, W), rel=2e-4)
    assert abs(a_rms / miles_rms(fn, Q, W) - 1) > 4e-3  # the grid resolves the difference


def state_space(K, M, C, B):
    n = K.shape[0]
    Mi = np.linalg.inv(M)
    Aa = np.block([[np.zeros((n, n)), np.eye(n)], [-Mi @ K, -Mi @ C]])
    Bb = np.vstack([np.zeros((n, B.shape[1])), Mi @ B])
    return Aa, Bb


def test_two_dof_correlated_forces_against_lyapunov():
    """Two correlated white forces (one-sided S_f, per Hz) on a grounded 2-DOF: the
    displacement covariance from the PSD integral equals the Lyapunov solution of
    A P + P A^T + B (S_f / 2) B^T = 0 (auto and cross terms)."""
    K = spring(2, 0, None, 800.0) + spring(2, 0, 1, 400.0)
    M = np.diag([2.0, 1.0])
    C = 0.002 * K + 0.05 * M
    Sf = np.array([[1.0, 0.6], [0.6, 2.0]])
    check_spectral_matrix(Sf)
    fn = np.sqrt(sla.eigh(K, M, eigvals_only=True)) / (2 * np.pi)
    f = resonance_grid(fn, 1e-3, 2e3, n_geo=400)
    H = receptance_sweep(K, M, C, None, 2 * np.pi * f, np.eye(2), np.eye(2),
                         checks=["kkt"]).H
    Sy = response_psd(H, Sf)
    assert np.allclose(Sy, Sy.conj().transpose(0, 2, 1))
    cov = np.real(mean_square(f, Sy))
    Aa, Bb = state_space(K, M, C, np.eye(2))
    P = sla.solve_continuous_lyapunov(Aa, -Bb @ (Sf / 2) @ Bb.T)[:2, :2]
    assert np.allclose(cov, P, rtol=1e-3, atol=1e-3 * np.abs(P).max())
    assert rms(f, np.stack([Sy[:, i, i].real for i in range(2)], axis=1)) == \
        pytest.approx(np.sqrt(np.diag(P)), rel=5e-4)


def test_two_dof_base_acceleration_against_quad():
    """A 2-DOF chain on a base under a shaped base-acceleration PSD: RMS of the absolute
    acceleration of the top mass by the grid against scipy.integrate.quad of the hand-built
    transmissibility (partitioned dynamic stiffness) times the log-log interpolated spec."""
    from scipy.integrate import quad
    n = 3
    K = spring(n, 0, 1, 4.0e4) + spring(n, 1, 2, 2.0e4)
    M = np.diag([0.0, 2.0, 1.0])
    C = 1e-3 * K
    A = np.array([[1.0, 0, 0]])
    table_f, table_s = [20.0, 80.0, 350.0, 2000.0], [0.01, 0.04, 0.04, 0.007]
    fn = np.sqrt(sla.eigh(K[1:, 1:], M[1:, 1:], eigvals_only=True)) / (2 * np.pi)
    f = np.union1d(resonance_grid(fn, 20.0, 2000.0, n_geo=400, n_band=300, width=0.3),
                   table_f)  # the table's kinks on the grid
    f = f[(f >= table_f[0]) & (f <= table_f[-1])]  # the level jumps to 0 outside the table
    w = 2 * np.pi * f
    H = base_drive_sweep(K, M, C, A, w, np.array([[1.0]]), np.eye(n)[[2]],
                         per="acceleration").H
    acc = -(w ** 2)[:, None, None] * H
    Sa = interpolate_psd(table_f, table_s, f)
    got = rms(f, response_psd(acc, Sa)[:, 0, 0].real)

    def integrand(x):
        wk = 2 * np.pi * x
        Z = K + 1j * wk * C - wk ** 2 * M
        T = -np.linalg.solve(Z[1:, 1:], Z[1:, :1])[1, 0]
        return abs(T) ** 2 * interpolate_psd(table_f, table_s, np.array([x]))[0]

    ref = quad(integrand, 20.0, 2000.0, points=sorted([80.0, 350.0, *fn]), limit=2000,
               epsabs=0, epsrel=1e-10)[0]
    assert got == pytest.approx(np.sqrt(ref), rel=1e-4)


def test_loglog_rule_exact_on_spec_table():
    """20-80 Hz +3 dB/oct, 80-350 Hz 0.04 g^2/Hz, 350-2000 Hz -3 dB/oct: the mean square is
    0.04/160 (80^2 - 20^2) + 0.04 * 270 + 14 ln(2000/350) (6.06 grms), exactly by the log-log
    rule on the four breakpoints; the trapezoid converges to it on a fine interpolated grid."""
    f = np.array([20.0, 80.0, 350.0, 2000.0])
    s = np.array([0.01, 0.04, 0.04, 0.04 * 350 / 2000])
    exact = 0.04 / 160 * (80 ** 2 - 20 ** 2) + 0.04 * 270 + 14 * np.log(2000 / 350)
    assert mean_square(f, s, "loglog") == pytest.approx(exact, rel=1e-13)
    assert np.sqrt(exact) == pytest.approx(6.06, abs=5e-3)
    fine = np.linspace(20.0, 2000.0, 200001)
    assert mean_square(fine, interpolate_psd(f, s, fine)) == pytest.approx(exact, rel=1e-8)
    # b = -1 exactly, and a steep power law between two points
    assert mean_square(np.array([10.0, 1000.0]), np.array([1.0, 0.01]), "loglog") == \
        pytest.approx(10 * np.log(100), rel=1e-12)
    assert mean_square(np.array([10.0, 100.0]), np.array([1.0, 1e-4]), "loglog") == \
        pytest.approx(1e4 / 3 * (10.0 ** -3 - 100.0 ** -3), rel=1e-12)  # S = (f/10)^-4


@pytest.mark.parametrize("freq, level, words", [
    ([10.0, 10.0, 20.0], [1, 1, 1], "increase"),
    ([10.0, 5.0], [1, 1], "increase"),
    ([10.0, 20.0], [1, -1e-3], ">= 0"),
    ([10.0, 20.0], [1, np.nan], "finite"),
])
def test_bad_psd_tables(freq, level, words):
    with pytest.raises(ValueError, match=words):
        check_psd_table(freq, level)


@pytest.mark.parametrize("S, words", [
    (np.array([[1.0, 0.5], [0.4, 1.0]]), "Hermitian"),
    (np.array([[1.0, 2.0], [2.0, 1.0]]), "semidefinite"),
    (np.array([[1.0, 0.5j], [0.5j, 1.0]]), "Hermitian"),
])
def test_bad_spectral_matrices(S, words):
    with pytest.raises(ValueError, match=words):
        check_spectral_matrix(S)


def test_coherent_inputs_accepted():
    """A rank-one (fully coherent) complex cross-spectral matrix is semidefinite."""
    v = np.array([1.0, 0.3 - 0.4j])
    check_spectral_matrix(np.outer(v, v.conj()))


# --------------------------------------------------------------------- loss factor


def test_sdof_receptance_loss_factor_exact():
    """1 / (k (1 + i eta) - w^2 m) on a SDOF held by a constraint, every formulation."""
    k, m, eta = 250.0, 0.5, 0.03
    K = spring(2, 0, 1, k)
    M = np.diag([1.0, m])
    w = np.linspace(1.0, 50.0, 97)
    res = hysteretic_sweep(K, M, None, np.array([[1.0, 0.0]]), w, np.eye(2)[:, [1]],
                           np.eye(2)[[1]], [LossFactor(eta, sp.csr_array(K))],
                           checks=["null-space", "kkt"])
    exact = 1 / (k * (1 + 1j * eta) - w ** 2 * m)
    assert np.abs(res.H[:, 0, 0] - exact).max() <= 1e-12 * np.abs(exact).max()
    assert max(res.agreement.values()) < 1e-12


def two_dof_parts(eta1=0.02, eta2=0.10):
    K1 = spring(2, 0, None, 1000.0)
    K2 = spring(2, 0, 1, 300.0)
    return np.diag([2.0, 0.5]), [LossFactor(eta1, sp.csr_array(K1)),
                                  LossFactor(eta2, sp.csr_array(K2))]


def test_two_dof_loss_factors_per_part():
    """Different loss factors on two springs: the sweep equals the dense inverse of
    K1 (1 + i eta1) + K2 (1 + i eta2) - w^2 M; the modal loss factors equal the roots of
    det(K* - lambda M) = 0 by the quadratic formula and, for these small eta, the modal
    strain energy estimate to O(eta^2)."""
    M, parts = two_dof_parts()
    Kc = sum(p.K.toarray() * (1 + 1j * p.eta) for p in parts)
    w = np.linspace(2.0, 60.0, 59)
    Ktot = sum(p.K.toarray() for p in parts)
    res = hysteretic_sweep(Ktot, M, None, None, w, np.eye(2), np.eye(2), parts)
    for k, wk in enumerate(w):
        ref = np.linalg.inv(Kc - wk ** 2 * M)
        assert np.allclose(res.H[k], ref, rtol=1e-11, atol=1e-12 * np.abs(ref).max())
    a = M[0, 0] * M[1, 1]
    b = -(M[0, 0] * Kc[1, 1] + M[1, 1] * Kc[0, 0])
    c = Kc[0, 0] * Kc[1, 1] - Kc[0, 1] ** 2
    disc = np.sqrt(b * b - 4 * a * c)
    lam = np.array([(-b - disc) / (2 * a), (-b + disc) / (2 * a)])
    lam = lam[np.argsort(lam.real)]
    wr, etar = modal_loss_factors(M, parts)
    assert np.allclose(wr, np.sqrt(lam.real), rtol=1e-12)
    assert np.allclose(etar, lam.imag / lam.real, rtol=1e-10)
    lam0, phi = sla.eigh(Ktot, M)
    mse = [sum(p.eta * ph @ p.K.toarray() @ ph for p in parts) / (ph @ Ktot @ ph)
           for ph in phi.T]
    assert np.allclose(etar, mse, atol=0.1 ** 2)


def test_uniform_loss_factor_modal_exact_constrained():
    """One eta on all of K: every modal loss factor is eta, also under a constraint."""
    K = spring(3, 0, 1, 100.0) + spring(3, 1, 2, 50.0) + spring(3, 2, None, 20.0)
    M = np.diag([1.0, 2.0, 0.5])
    A = np.array([[1.0, -1.0, 0.0]])
    wr, etar = modal_loss_factors(M, [LossFactor(0.07, sp.csr_array(K))], A)
    assert len(wr) == 2 and np.allclose(etar, 0.07, rtol=1e-12)


def test_loss_factor_refusals():
    K = spring(1, 0, None, 1.0)
    with pytest.raises(ValueError, match=">= 0"):
        hysteretic_sweep(K, np.eye(1), None, None, [1.0], np.eye(1), np.eye(1),
                         [LossFactor(-0.1, sp.csr_array(K))])
    with pytest.raises(AnalysisInputError, match="frequencies > 0"):
        hysteretic_sweep(K, np.eye(1), None, None, [0.0, 1.0], np.eye(1), np.eye(1),
                         [LossFactor(0.1, sp.csr_array(K))], method="kkt")
