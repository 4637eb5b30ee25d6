"""Shock response spectra against the single-DOF ODE solved independently (solve_ivp on the
continuous half-sine), the closed-form half-sine response, and the asymptotes."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from substruct.analysis.transient.srs import srs


def half_sine(t, peak, tau):
    return np.where((t >= 0) & (t <= tau), peak * np.sin(np.pi * t / tau), 0.0)


def exact_peaks(fn, zeta, peak, tau, t_end):
    """Largest positive/negative absolute acceleration and |z| of the oscillator, by
    solve_ivp (rtol 1e-11) on the continuous pulse, read on a 200,000-point dense output."""
    wn = 2 * np.pi * fn

    def rhs(t, y):
        return [y[1], -half_sine(t, peak, tau) - 2 * zeta * wn * y[1] - wn * wn * y[0]]

    t = np.linspace(0, t_end, 200001)
    first = solve_ivp(rhs, (0, tau), [0.0, 0.0], method="DOP853", rtol=1e-11, atol=1e-14,
                      dense_output=True)
    second = solve_ivp(rhs, (tau, t_end), first.y[:, -1], method="DOP853", rtol=1e-11,
                       atol=1e-14, dense_output=True)
    y = np.where(t <= tau, first.sol(np.minimum(t, tau)), second.sol(np.maximum(t, tau)))
    acc = -2 * zeta * wn * y[1] - wn * wn * y[0]
    return acc.max(), -acc.min(), np.abs(y[0]).max() * wn


@pytest.mark.parametrize("fn", [20.0, 100.0, 400.0])
def test_half_sine_against_ode(fn):
    """Stated error: peaks read at samples lose at most (pi fn dt)^2 / 2 and the straight-line
    input differs from the sine by about (pi dt / tau)^2 of its peak: twice their sum is the
    tolerance (2e-5 here; 1e-6 to 4e-6 measured)."""
    peak, tau, zeta = 100.0, 0.005, 0.05
    dt = min(1e-3 * tau, 0.01 / fn)
    t_end = tau + 1.0 / 20.0  # the residual over one period of the lowest frequency
    t = np.arange(0, tau + dt / 2, dt)
    s = srs(half_sine(t, peak, tau), dt, [fn], zeta, pad=t_end - t[-1])
    pos, neg, pv = exact_peaks(fn, zeta, peak, tau, t_end)
    scale = max(pos, neg)
    tol = 2 * ((np.pi * fn * dt) ** 2 / 2 + (np.pi * dt / tau) ** 2)
    assert s.pos[0] == pytest.approx(pos, abs=tol * scale)
    assert s.neg[0] == pytest.approx(neg, abs=tol * scale)
    assert s.maxabs[0] == pytest.approx(max(pos, neg), abs=tol * scale)
    assert s.pv[0] == pytest.approx(pv, rel=tol)


def test_undamped_half_sine_closed_form():
    """Undamped, during the pulse: z'' + wn^2 z = -P sin(Om t) from rest has
    z = -P / (wn^2 - Om^2) (sin(Om t) - (Om / wn) sin(wn t)), absolute acceleration
    -wn^2 z; its maximum over the pulse (fn tau = 1.5) against the spectrum with no residual
    time (pad 0) and zeta = 1e-6 (its effect ~ zeta wn tau = 1e-5)."""
    peak, tau, fn = 1.0, 0.01, 150.0
    wn, Om = 2 * np.pi * fn, np.pi / tau
    r = Om / wn
    tt = np.linspace(0, tau, 400001)
    # undamped relative response to -peak sin(Om t) from rest, absolute acc = -wn^2 z
    z = -peak / (wn ** 2 - Om ** 2) * (np.sin(Om * tt) - r * np.sin(wn * tt))
    primary = (wn ** 2 * np.abs(z)).max()
    dt = 1e-6
    t = np.arange(0, tau + dt / 2, dt)
    s = srs(half_sine(t, peak, tau), dt, [fn], 1e-6, pad=0.0)
    assert s.maxabs[0] == pytest.approx(primary, rel=1e-4)


def test_high_frequency_asymptote_is_peak_input():
    """A stiff oscillator follows the base: SRS -> peak input; the departure falls like
    (1 / (fn tau))^2 (quasi-static with the inertia correction)."""
    peak, tau, zeta = 50.0, 0.01, 0.05
    dt = 1e-6
    t = np.arange(0, tau + dt / 2, dt)
    fns = np.array([2000.0, 4000.0, 8000.0])
    s = srs(half_sine(t, peak, tau), dt, fns, zeta, pad=0.002)
    err = np.abs(s.maxabs / peak - 1)
    assert err[-1] < 2e-3
    assert np.all(np.diff(err) < 0)


def test_low_frequency_asymptote_velocity_change():
    """A soft oscillator sees an impulse: its residual pseudo-velocity tends to the velocity
    change of the pulse, 2 peak tau / pi (undamped limit: zeta = 1e-4)."""
    peak, tau = 10.0, 0.01
    dt = 1e-5
    t = np.arange(0, tau + dt / 2, dt)
    s = srs(half_sine(t, peak, tau), dt, [0.5], 1e-4)
    dv = 2 * peak * tau / np.pi
    assert s.pv[0] == pytest.approx(dv, rel=1e-2)


@pytest.mark.parametrize("kwargs, words", [
    ({"zeta": 0.0}, r"\(0, 1\)"),
    ({"zeta": 1.0}, r"\(0, 1\)"),
    ({"zeta": float("nan")}, r"\(0, 1\)"),
    ({"dt": 0.0}, "time step"),
    ({"fn": [0.0, 10.0]}, "> 0"),
    ({"fn": [5000.0]}, "time step <="),
])
def test_srs_refusals(kwargs, words):
    args = {"acc": np.ones(10), "dt": 1e-4, "fn": [10.0], "zeta": 0.05} | kwargs
    with pytest.raises(ValueError, match=words):
        srs(**args)
