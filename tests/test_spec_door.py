"""The case-file door of the specification analyses (substruct/run/spec_route.py):
analysis.random, analysis.srs and analysis.frf.loss_factor, run through ``substruct run`` and
checked against single-DOF closed forms."""

from pathlib import Path

import h5py
import numpy as np
import pytest

from cli_helpers import assert_one_line_error, run
from substruct.analysis.frf.random import miles_absolute_rms

ROOT = Path(__file__).resolve().parent.parent
M, K = 1.0, 1.0e5
WN = np.sqrt(K / M)
FN = WN / (2 * np.pi)
ZETA = 0.05
C = 2 * ZETA * np.sqrt(K * M)

SDOF = f"""name: sdof
units: N, m, kg, s
substructures:
  - {{name: s, type: free-free, mass: {M}, stiffness: {K}, damping: {C}}}
constraints:
  - {{name: table, terms: {{s@boundary: 1}}}}
output: {{pictures: false}}
analysis:
"""


def _run(capsys, tmp_path, text, name="case.yaml"):
    path = tmp_path / name
    path.write_text(text)
    code, out, err = run(capsys, "run", path, "--out", tmp_path / "out", "--force")
    return code, out, err, tmp_path / "out" / "sdof.h5"


def test_random_base_case_rms_is_miles(capsys, tmp_path):
    """cases/random_base.yaml: the absolute acceleration's RMS is Miles' exact form
    sqrt(pi/2 f_n Q W (1 + 1/Q^2)) less the band below the table's 1 Hz (where |T| = 1 to
    (1/50)^2, so W x 1 Hz) and above 2000 Hz (|T|^2 ~ (2 zeta f_n / f)^2: 4 zeta^2 f_n^2 W /
    2000 Hz); the trapezoid rule on 4000 log-spaced frequencies (0.1 Hz steps in the 5 Hz
    half-power band) adds < 1e-4; the base's own RMS is sqrt(W x 1999 Hz) exactly."""
    code, out, err = run(capsys, "run", ROOT / "cases/random_base.yaml", "--out", tmp_path)
    assert code == 0, err
    assert "3 rms" in out and "0.27 %" in out
    with h5py.File(tmp_path / "random_base.h5") as f:
        g = f["random"]
        rms = g["rms"][()]
        assert [s.decode() for s in g["outputs"][()]] == ["sdof@mass", "sdof@boundary"]
        assert g["psd"].shape == (4000, 2, 2)
        agreement = dict(g["agreement"].attrs)
    W, Q, fn = 3.8468, 10.0, np.sqrt(1e5) / (2 * np.pi)
    ms = miles_absolute_rms(fn, Q, W) ** 2 - W * 1.0 - 4 * ZETA ** 2 * fn ** 2 * W / 2000
    assert abs(rms[0] / np.sqrt(ms) - 1) < 3e-4, (rms[0], np.sqrt(ms))
    assert abs(rms[1] / np.sqrt(W * 1999) - 1) < 1e-9
    assert agreement["null-space"] < 1e-6 and agreement["relative-coordinates"] < 1e-6


def test_random_force_psd_displacement_rms(capsys, tmp_path):
    """A white force PSD W on the mass: int |H|^2 df = Q / (4 w_n^3 m^2) (Miles' integral), the
    static flat part below 1 Hz (W / k^2 x 1 Hz) left out; the table is log-log interpolated
    between its two equal rows, so flat."""
    W = 2.0
    text = SDOF + """  random:
    frequencies: {start: 1, stop: 5000, num: 4000, spacing: log}
    forces:
      - {at: s@mass, psd: [[0.5, 2.0], [8000, 2.0]]}
    outputs: [s@mass]
    quantity: displacement
"""
    code, out, err, h5 = _run(capsys, tmp_path, text)
    assert code == 0, err
    with h5py.File(h5) as f:
        rms = f["random/rms"][()]
        np.testing.assert_allclose(f["random/input_psd"][()], W, rtol=1e-12)
    ms = W * (1 / (2 * ZETA)) / (4 * WN ** 3 * M ** 2) - W / K ** 2 * 1.0
    assert abs(rms[0] / np.sqrt(ms) - 1) < 3e-4, (rms[0], np.sqrt(ms))


def test_loss_factor_is_hysteretic(capsys, tmp_path):
    """loss_factor eta on the spring: H = 1 / (k (1 + i eta) + i w c - w^2 m) at every
    frequency (the spring's block, named by its substructure, is all of K here)."""
    eta = 0.08
    for spec in (f"{eta}", f"{{s: {eta}}}"):
        text = SDOF + f"""  frf:
    omega: {{start: 100, stop: 600, num: 41}}
    inputs: [s@mass]
    outputs: [s@mass]
    loss_factor: {spec}
    check: [kkt]
"""
        code, out, err, h5 = _run(capsys, tmp_path, text)
        assert code == 0, err
        with h5py.File(h5) as f:
            w, H = f["frf/omega"][()], f["frf/H"][()][:, 0, 0]
        exact = 1 / (K * (1 + 1j * eta) + 1j * w * C - w ** 2 * M)
        assert np.abs(H - exact).max() / np.abs(exact).max() < 1e-10


def test_srs_of_a_step_base_acceleration(capsys, tmp_path):
    """A base acceleration step a0: the relative displacement peaks at
    a0 / w_n^2 (1 + exp(-zeta pi / sqrt(1 - zeta^2))), so the pseudo-velocity is
    a0 / w_n (1 + exp(...)); read at samples it is low by at most (pi f_n dt)^2 / 2 (2e-3 at
    20 Hz, dt = 1 ms)."""
    a0, zeta = 9.81, 0.05
    text = SDOF + f"""  transient:
    t_end: 1.0
    dt: 0.001
    base:
      at: [s@boundary]
      acceleration: {{shape: step, amplitude: {a0}}}
    outputs: [s@boundary, s@mass]
  srs:
    outputs: [s@boundary]
    Q: {1 / (2 * zeta)}
    frequencies: {{start: 2, stop: 20, per_octave: 3}}
"""
    code, out, err, h5 = _run(capsys, tmp_path, text)
    assert code == 0, err
    assert "shock response spectra" in out
    with h5py.File(h5) as f:
        fn, pv, maxabs = f["srs/fn"][()], f["srs/pv"][()][0], f["srs/maxabs"][()][0]
        assert f["srs"].attrs["zeta"] == pytest.approx(zeta)
    np.testing.assert_allclose(fn, 2 * 2.0 ** (np.arange(10) / 3))
    wn = 2 * np.pi * fn
    exact = a0 / wn * (1 + np.exp(-zeta * np.pi / np.sqrt(1 - zeta ** 2)))
    bound = (np.pi * fn * 1e-3) ** 2 / 2 + 1e-9
    assert np.all(pv <= exact * (1 + 1e-9)) and np.all(pv >= exact * (1 - bound)), pv / exact
    assert np.all(maxabs > a0) and np.all(maxabs < 2 * a0)


@pytest.mark.parametrize("body, fragments", [
    ("  srs: {frequencies: {start: 1, stop: 10, num: 5}}\n  modes: {count: 1}\n",
     ("analysis.srs", "add analysis.transient")),
    ("  transient: {t_end: 0.1, dt: 0.01, outputs: [s@mass]}\n"
     "  srs: {frequencies: {start: 1, stop: 50, num: 5}}\n",
     ("analysis.srs.frequencies.stop", "10 samples a period")),
    ("  frf: {omega: [1, 2], inputs: [s@mass], outputs: [s@mass], loss_factor: {t: 0.1}}\n",
     ("analysis.frf.loss_factor.t", "not a substructure")),
    ("  random: {frequencies: [1, 2], forces: [{at: s@mass, psd: [[1, 1], [2, 1]]}],\n"
     "           outputs: [s@mass], extra: 1}\n", ("analysis.random", "extra")),
])
def test_refused_with_one_line(capsys, tmp_path, body, fragments):
    code, out, err, h5 = _run(capsys, tmp_path, SDOF + body)
    assert_one_line_error(code, out, err, *fragments)
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())
