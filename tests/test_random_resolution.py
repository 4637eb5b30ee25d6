"""A random response's RMS on a grid that steps over a resonance is refused (exit 1), not
printed: the trapezoid rule's error on the mean square is estimated from the three samples at
each peak of the response PSD (substruct.analysis.frf.psd_resolution) and held to
``analysis.random.rms_tolerance`` (default 1e-2).

The reference is the closed form of a single-DOF oscillator under a white force PSD ``S0``
(one-sided, per Hz): ``int_0^inf S0 |H|^2 df = S0 / (4 k c)``, less the band below the grid's
first frequency, where ``|H| = 1/k`` to ``(f/f_n)^2``."""

import numpy as np
import pytest

from cli_helpers import run
from substruct.analysis.frf.psd_resolution import quadrature_error

M, K, C, S0 = 2.0, 8.0e5, 40.0, 1.0          # f_n = 100.7 Hz, zeta = 0.0158


def sampled(n: int, scale: float = 1.0):
    """The oscillator's displacement PSD on ``n`` log-spaced frequencies over 1-1e4 Hz, and
    the true relative error of the trapezoid rule on it; ``scale`` multiplies the stiffness
    and the damping by ``scale^2`` and ``scale`` (every frequency by ``scale``) and the PSD
    level by ``scale^4``."""
    k, c = K * scale ** 2, C * scale
    f = np.geomspace(1.0, 1e4, n) * scale
    w = 2 * np.pi * f
    S = S0 * scale ** 4 / np.abs(k - w ** 2 * M + 1j * w * c) ** 2
    exact = S0 * scale ** 4 / (4 * k * c) - S0 * scale ** 4 * f[0] / k ** 2
    return f, S, abs(np.trapezoid(S, f) / exact - 1)


@pytest.mark.parametrize("n", [50, 100, 200, 500, 1000, 4000])
def test_estimate_flags_every_grid_whose_error_is_beyond_one_percent(n):
    f, S, true = sampled(n)
    est = quadrature_error(f, S[:, None])[0]
    if true > 1e-2:               # 50, 100, 200 points: 74 %, 50 %, 15 % of the mean square
        assert est.error > 1e-2, (true, est)
    else:                         # a bound, not a guess: at least the true error of the peak
        assert true / 2 <= est.error + 1e-6 and est.error < 2e-2, (true, est)
    if n >= 1000:                 # 2.5e-5 true at 1000 points (the band's ends: 1e-6)
        assert est.error < 1e-4
    if n >= 200:                  # the peak found is the oscillator's (fitted from samples
        # within a few half-widths: 50 points are 19 Hz apart there, 12 half-widths)
        assert abs(est.f0 / 100.66 - 1) < 0.02 and abs(est.gamma / 1.5915 - 1) < 0.1


def test_estimate_does_not_depend_on_the_scale():
    for n in (200, 500, 1000):
        a = quadrature_error(*sampled(n)[:1], sampled(n)[1][:, None])[0]
        f, S, _ = sampled(n, scale=1e3)
        b = quadrature_error(f, S[:, None])[0]
        assert abs(b.error - a.error) <= 1e-9 * max(a.error, 1e-300) + 1e-15
        assert abs(b.f0 / a.f0 / 1e3 - 1) < 1e-9


CASE = """name: coarse
units: N, m, kg, s
substructures:
  - {name: a, type: fixed-free, mass: 2.0, stiffness: 8.0e+5, damping: 40.0}
analysis:
  random:
    frequencies: {start: 1, stop: 10000, num: NUM, spacing: log}
    forces:
      - {at: a@mass, psd: [[1, 1.0], [10000, 1.0]]}
    outputs: [a@mass]
    quantity: displacement
EXTRA
output: {pictures: false}
"""


def test_coarse_grid_is_refused_in_one_line(capsys, tmp_path):
    path = tmp_path / "coarse.yaml"
    path.write_text(CASE.replace("NUM", "100").replace("EXTRA\n", ""))
    code, out, err = run(capsys, "run", path, "--out", tmp_path / "out")
    assert code == 1 and err.count("\n") == 1 and "Traceback" not in err, err
    assert "analysis.random.frequencies" in err and "a@mass near 100" in err
    assert not (tmp_path / "out" / "coarse.h5").exists()
    # accepted when asked for (rms_tolerance: 1 accepts any grid), the RMS then 29 % low
    path.write_text(CASE.replace("NUM", "100").replace("EXTRA", "    rms_tolerance: 1"))
    code, out, err = run(capsys, "run", path, "--out", tmp_path / "out")
    assert code == 0, err
    # a grid fine enough passes by default, with the closed form's RMS
    path.write_text(CASE.replace("NUM", "1000").replace("EXTRA\n", ""))
    code, out, err = run(capsys, "run", path, "--out", tmp_path / "out", "--force")
    assert code == 0, err
    rms = float(next(line for line in out.splitlines()
                     if line.strip().startswith("a@mass")).split()[1])
    assert abs(rms / np.sqrt(S0 / (4 * K * C) - S0 / K ** 2) - 1) < 5e-5
