"""Modes tracked through a study (collect: track) and their derivatives with respect to the
study's parameter (collect: derivatives): two oscillators k1 (varied) and k2 = 1000 of unit
mass, joined by a spring kc, against the closed form

    lambda_+- = (k1 + k2 + 2 kc)/2 +- sqrt((k1 - k2)^2 + 4 kc^2)/2,
    d lambda_+- / d k1 = (1 +- (k1 - k2) / sqrt((k1 - k2)^2 + 4 kc^2)) / 2,

a veering at k1 = k2 (gap 2 kc in lambda, the shapes exchanged) when kc > 0 and a crossing
when the oscillators are apart; damped roots' derivatives against central differences."""

import h5py
import numpy as np
import pytest

from cli_helpers import assert_one_line_error, run
from substruct.case.loader import parse_case
from substruct.io.study_file import load_study
from substruct.studies.study_run import run_study
from substruct.studies.study_tracking import TrackedStudy

K2 = 1000.0


def case_text(kc: float | None, grid: str, collect: str = "{frequencies: 2, "
              "damping_ratios: true, track: true, derivatives: true}", c: float = 0.0,
              pictures: bool = False) -> str:
    spring = f"  - {{name: s, type: spring, stiffness: {kc}}}\n" if kc else ""
    links = "connections:\n  - [a@mass, s@i]\n  - [s@j, b@mass]\n" if kc else ""
    return f"""name: pair
units: N, m, kg, s
parameters: {{k1: 900, c: {c}}}
substructures:
  - {{name: a, type: fixed-free, mass: 1, stiffness: k1, damping: c}}
  - {{name: b, type: fixed-free, mass: 1, stiffness: {K2}}}
{spring}{links}analysis:
  modes: {{count: 2}}
output: {{pictures: {str(pictures).lower()}}}
study:
  grid:
    parameters:
      - {grid}
  collect: {collect}
"""


def closed_form(k1, kc):
    root = np.sqrt((k1 - K2) ** 2 + 4 * kc ** 2)[:, None]
    sign = np.array([-1.0, 1.0])
    lam = (k1 + K2 + 2 * kc)[:, None] / 2 + sign * root / 2
    dlam = (1 + sign * (k1 - K2)[:, None] / root) / 2
    return np.sqrt(lam), dlam / (2 * np.sqrt(lam))


def test_veering_of_coupled_oscillators():
    kc = 20.0
    r = run_study(parse_case(case_text(kc, "{parameter: k1, start: 800, stop: 1200, num: 21}"),
                             "pair.yaml"))
    t = r.tracking
    assert isinstance(t, TrackedStudy), t
    w, dw = closed_form(r.table[:, 0], kc)
    scale = w.max()
    np.testing.assert_allclose(t.frequency, w, rtol=0, atol=1e-10 * scale)
    assert t.crossings == [] and t.veerings == [(10, 0, 1)]
    assert r.table[10, 0] == 1000.0
    gap = t.frequency[10, 1] ** 2 - t.frequency[10, 0] ** 2
    assert gap == pytest.approx(2 * kc, rel=1e-9)
    # the shapes exchange: mode 1 is mass a's at the start, mass b's at the end
    assert t.mac.min() < 0.99
    np.testing.assert_allclose(t.tracked["frequency_derivative"], dw, rtol=0,
                               atol=1e-7 * np.abs(dw).max())
    assert np.abs(t.tracked["damping_ratio"]).max() < 1e-12


def test_uncoupled_modes_cross():
    """Without the spring the modes are sqrt(k1) (mass a) and sqrt(k2) (mass b): tracked by
    shape, each keeps its own, and they cross once between k1 = 989.5 and 1010.5."""
    r = run_study(parse_case(case_text(None, "{parameter: k1, start: 800, stop: 1200, num: 20}"),
                             "pair.yaml"))
    t = r.tracking
    assert isinstance(t, TrackedStudy), t
    k1 = r.table[:, 0]
    np.testing.assert_allclose(t.frequency[:, 0], np.sqrt(k1), rtol=1e-12)
    np.testing.assert_allclose(t.frequency[:, 1], np.sqrt(K2), rtol=1e-12)
    s = int(np.flatnonzero(k1 < K2)[-1])
    assert t.crossings == [(s, 0, 1)] and t.veerings == []
    np.testing.assert_allclose(t.mac, 1.0, atol=1e-12)
    # the sorted frequencies are not the tracks: they exchange at the crossing
    assert np.all(r.values["frequency"][:, 0] <= r.values["frequency"][:, 1])
    np.testing.assert_allclose(t.tracked["frequency_derivative"][:, 0], 0.5 / np.sqrt(k1),
                               rtol=1e-7)
    np.testing.assert_allclose(t.tracked["frequency_derivative"][:, 1], 0.0,
                               atol=1e-9 / np.sqrt(K2))


def test_damped_derivatives_against_finite_differences():
    """Damped, not proportionally (a dashpot c = 3 on mass a only; zeta up to 5 %): ds/dp = -phi^T (s^2 M' + s C' + K') phi / phi^T (2 s M + C)
    phi, d omega/dp = Re(conj(s) ds/dp)/|s|, against (omega(p + h) - omega(p - h)) / 2h of the
    study's own roots, h = 0.01: truncation h^2 omega'''/6 < 1e-12; the roots, accurate to
    about 1e-12 omega, give the quotient to 1e-12 omega / h = 3e-9, 2e-7 of the derivative
    (observed 7e-10)."""
    h = 0.01
    points = [900.0, 990.0, 1000.0, 1100.0]
    values = sorted(p + d for p in points for d in (-h, 0.0, h))
    r = run_study(parse_case(case_text(20.0, f"{{parameter: k1, values: {values}}}", c=3.0),
                             "pair.yaml"))
    assert not r.failed, r.errors
    w = r.values["frequency"]
    d = r.values["frequency_derivative"]
    assert r.values["damping_ratio"].max() > 0.04
    for i in range(len(points)):
        fd = (w[3 * i + 2] - w[3 * i]) / (2 * h)
        np.testing.assert_allclose(d[3 * i + 1], fd, rtol=0, atol=1e-6 * np.abs(fd).max())
    # damping changes the derivative (the undamped closed form is not it)
    undamped = closed_form(np.array(points), 20.0)[1]
    assert np.abs(d[1::3] - undamped).max() > 1e-3 * np.abs(undamped).max()


def test_cli_writes_tracks_and_picture(capsys, tmp_path):
    path = tmp_path / "pair.yaml"
    path.write_text(case_text(20.0, "{parameter: k1, start: 800, stop: 1200, num: 11}",
                              pictures=True))
    code, out, err = run(capsys, "study", path, "--out", tmp_path / "out")
    assert code == 0, err
    assert "veering of tracks 1 and 2 at k1 = 1000" in out
    png = tmp_path / "out" / "pair_study_tracked.png"
    assert png.stat().st_size > 10_000
    back = load_study(tmp_path / "out" / "pair_study.h5")
    assert isinstance(back.tracking, TrackedStudy) and back.tracking.veerings == [(5, 0, 1)]
    with h5py.File(tmp_path / "out" / "pair_study.h5") as f:
        assert f["tracking/frequency"].shape == (11, 2)
        assert f["tracking"].attrs["parameter"] == "k1"


@pytest.mark.parametrize("grid, collect, fragments", [
    ("{parameter: k1, values: [900, 1000]}\n      - {parameter: c, values: [0, 1]}",
     "{frequencies: 2, track: true}", ("study.collect.track", "one parameter")),
    ("{parameter: k1, values: [900, 1000]}\n      - {parameter: c, values: [0, 1]}",
     "{frequencies: 2, derivatives: true}", ("study.collect.derivatives", "one parameter")),
    ("{parameter: k1, values: [900, 1000]}", "{track: true}",
     ("study.collect.track", "needs collect.frequencies")),
])
def test_refused(capsys, tmp_path, grid, collect, fragments):
    path = tmp_path / "pair.yaml"
    path.write_text(case_text(20.0, grid, collect))
    code, out, err = run(capsys, "study", path, "--out", tmp_path / "out")
    assert_one_line_error(code, out, err, *fragments)
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())
