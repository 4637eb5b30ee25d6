"""Monte Carlo over noisy receptances (substruct.analysis.frf.vp_noise).

Two parts, each a joint receptance (symmetric, complex, 6 x 6) measured through a rigid 50 mm
adapter by three turned triaxial sensors and nine impacts, coupled at the virtual point J.
Checked: zero noise gives the nominal exactly; the spread is first order in the noise (its
measured slope between two levels); a seed gives the same numbers bit for bit in process and
through a task map (the Dask study backend's ``Session.map``); Tikhonov regularisation and
weakening reduce the spread at a given noise level.
"""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from substruct.analysis.frf.virtual_point import VirtualPoint, idm_rows, virtual_point_transform
from substruct.analysis.frf.vp_coupling import Regularisation
from substruct.analysis.frf.vp_noise import (MeasuredPart, NoiseStudy, add_relative_noise,
                                             monte_carlo_coupling)
from substruct.case.channels import parse_channels

VP = ("x", "y", "z", "rx", "ry", "rz")
PAIRS = tuple((f"A@J:{c}", f"B@J:{c}") for c in VP)
J_A = tuple(f"A@J:{c}" for c in VP)


def _table(seed):
    rng = np.random.default_rng(seed)
    rows = []
    spots = [(0.025, 0.012, -0.008), (-0.01, 0.025, 0.015), (0.005, -0.014, 0.025)]
    for s, spot in enumerate(spots):
        axes = np.linalg.qr(rng.normal(size=(3, 3)))[0]
        for a in range(3):
            rows.append(dict(name=f"S{s}{'xyz'[a]}", node=s + 1, x=spot[0], y=spot[1],
                             z=spot[2], dx=axes[0, a], dy=axes[1, a], dz=axes[2, a],
                             kind="sensor"))
    for h in range(9):
        p, d = rng.uniform(-0.025, 0.025, 3), rng.normal(size=3)
        rows.append(dict(name=f"H{h}", node=10 + h, x=p[0], y=p[1], z=p[2], dx=d[0], dy=d[1],
                         dz=d[2], kind="impact"))
    return parse_channels(rows, "lab")


OMEGA = np.linspace(10.0, 1000.0, 6)


def _joint(rng):
    X = rng.normal(size=(len(OMEGA), 6, 6)) + 1j * rng.normal(size=(len(OMEGA), 6, 6))
    return (X + X.transpose(0, 2, 1)) * 1e-6 + 20e-6 * np.eye(6)


@pytest.fixture(scope="module")
def parts():
    rng = np.random.default_rng(0)
    out = []
    for name in ("A", "B"):
        table = _table(1 if name == "A" else 2)
        sensors = [c.name for c in table.of_kind("sensor")]
        impacts = [c.name for c in table.of_kind("impact")]
        vpt = virtual_point_transform(table, [VirtualPoint("J", (0, 0, 0), tuple(sensors),
                                                           tuple(impacts))], sensors, impacts)
        Ru = idm_rows(table.positions(sensors), table.directions(sensors), (0, 0, 0))
        Rf = idm_rows(table.positions(impacts), table.directions(impacts), (0, 0, 0))
        out.append(MeasuredPart(name, OMEGA, Ru @ _joint(rng) @ Rf.T, vpt))
    return tuple(out)


def _study(parts, level, **kw):
    return NoiseStudy(parts, PAIRS, J_A[:3], J_A, level, **kw)


def test_zero_noise_gives_the_nominal_exactly(parts):
    res = monte_carlo_coupling(_study(parts, 0.0), 4, seed=7)
    assert np.array_equal(res.mean, res.nominal)
    assert not res.std.any()
    assert np.array_equal(res.bands[1], np.abs(res.nominal))
    # the nominal is the exact coupling of the two joint receptances
    YA, YB = (p.vpt.apply(p.Y) for p in parts)
    exact = np.linalg.inv(np.linalg.inv(YA) + np.linalg.inv(YB))[:, :3, :]
    assert np.abs(res.nominal - exact).max() < 1e-8 * np.abs(exact).max()


def test_noise_is_relative_and_of_the_stated_level():
    Y = np.full((2000,), 3.0 - 4.0j)
    d = add_relative_noise(Y, 0.01, np.random.default_rng(1)) - Y
    # E|dY|^2 = eps^2 |Y|^2: the sample mean of 2000 draws within 4 standard errors (2/sqrt(n))
    assert abs(np.mean(np.abs(d) ** 2) / (0.01 * 5.0) ** 2 - 1) < 4 * 1 / np.sqrt(2000)


def test_spread_is_first_order_in_the_noise(parts):
    """The measured slope of log(spread) against log(level) between 1e-5 and 1e-4 (same
    seeds, so the same draws scaled): 1 to within the second-order term."""
    s = [np.median(monte_carlo_coupling(_study(parts, e), 40, seed=3).relative_spread())
         for e in (1e-5, 1e-4)]
    slope = np.log10(s[1] / s[0])
    assert abs(slope - 1) < 0.02, slope
    assert s[0] > 0


def test_same_seed_same_bits_in_process_and_through_a_map(parts):
    calls = []

    def task_map(function, items):  # the tasks run in reverse order, as a scheduler may
        calls.append(len(items))
        out = [None] * len(items)
        for i in reversed(range(len(items))):
            out[i] = function(pickle.loads(pickle.dumps(items[i])))  # as sent to a worker
        return out

    study = _study(parts, 1e-2)
    a = monte_carlo_coupling(study, 6, seed=11)
    b = monte_carlo_coupling(study, 6, seed=11, map=task_map)
    assert calls == [6]
    for f in ("nominal", "mean", "std", "bands"):
        assert np.array_equal(getattr(a, f), getattr(b, f)), f
    c = monte_carlo_coupling(study, 6, seed=12)
    assert not np.array_equal(a.std, c.std)


def test_regularisation_and_weakening_reduce_the_spread(parts):
    """At 1% noise the rotations observed over 25 mm amplify it; Tikhonov (alpha = 1e-2,
    rotations scaled by 25 mm) and dropping the rotations from the interface lower the
    median spread of the joint's translations (measured: see the numbers asserted)."""
    n, seed, eps = 30, 5, 1e-2
    plain = np.median(monte_carlo_coupling(_study(parts, eps), n, seed).relative_spread())
    tik = np.median(monte_carlo_coupling(
        _study(parts, eps, reg=Regularisation("tikhonov", alpha=1e-2), length=0.025), n,
        seed).relative_spread())
    rot = ("rx", "ry", "rz")
    weak = NoiseStudy(parts, PAIRS, J_A[:3], J_A[:3], eps, weaken_compatibility=rot,
                      weaken_equilibrium=rot)
    plain3 = np.median(monte_carlo_coupling(
        NoiseStudy(parts, PAIRS, J_A[:3], J_A[:3], eps), n, seed).relative_spread())
    ball = np.median(monte_carlo_coupling(weak, n, seed).relative_spread())
    print(f"spread at 1%: plain {plain:.3g}, tikhonov {tik:.3g}; translations {plain3:.3g}, "
          f"weakened {ball:.3g}")
    assert tik < 0.7 * plain
    assert ball < 0.7 * plain3


def test_refused_settings(parts):
    with pytest.raises(ValueError, match="samples"):
        monte_carlo_coupling(_study(parts, 1e-2), 1, seed=0)
    with pytest.raises(ValueError, match="noise level"):
        _study(parts, -1e-2)
    with pytest.raises(ValueError, match="percentiles"):
        monte_carlo_coupling(_study(parts, 1e-2), 3, seed=0, percentiles=(101,))
