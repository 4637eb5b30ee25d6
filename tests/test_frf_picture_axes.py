"""The FRF picture follows its grid: a log grid on a log axis (even over less than two decades),
a linear one on a linear axis; markers at the points of a sparse grid only."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import substruct
from substruct.case.loader import load_case
from substruct.run.runner import build_model, run_case
from substruct.viz.frf_picture import SPARSE_GRID, draw_frf

CASE = Path(__file__).resolve().parents[1] / "cases" / "tapered_rod.yaml"


def _axes(grid: str):
    case = load_case(CASE, [f"analysis.frf.omega={grid}", "output.pictures=false"])
    fig = draw_frf(run_case(case, model=build_model(case)))
    return fig.axes[0]


@pytest.mark.parametrize("grid, scale, markers", [
    ("{start: 1, stop: 50, num: 20, spacing: log}", "log", True),
    ("{start: 1, stop: 50, num: 200}", "linear", False),
])
def test_axis_and_markers_follow_the_grid(grid, scale, markers):
    ax = _axes(grid)
    assert ax.get_xscale() == scale
    curves = [ln for ln in ax.get_lines() if len(ln.get_xdata()) > 2]
    assert curves and all((ln.get_marker() not in (None, "None", "")) == markers
                          for ln in curves)
    assert (len(curves[0].get_xdata()) <= SPARSE_GRID) == markers


def _run(overrides):
    case = load_case(CASE, ["output.pictures=false", "analysis.frf.omega={start: 2, stop: 60, "
                            "num: 80}", *overrides])
    return run_case(case, model=build_model(case))


def _curves(fig):
    return [ln for ln in fig.axes[0].get_lines() if len(ln.get_xdata()) > 2]


@pytest.mark.parametrize("quantity, unit, power", [
    ("receptance", "m/N", 0), ("mobility", "m/(N s)", 1), ("accelerance", "m/(N s\u00b2)", 2)])
def test_db_magnitude_is_20_log10_of_the_stored_values(quantity, unit, power):
    """``analysis.frf.magnitude: db``: every curve is ``20 log10 |H|`` of the stored
    receptance times ``omega^p`` (p = 0, 1, 2 for receptance, mobility, accelerance), on a
    linear axis, labelled with its reference ``dB re 1 <unit>`` in the case's units."""
    base = _run(["units=N, m, kg, s"])
    result = _run(["units=N, m, kg, s", "analysis.frf.magnitude=db",
                   f"analysis.frf.quantity={quantity}"])
    fig = draw_frf(result)
    ax = fig.axes[0]
    assert ax.get_yscale() == "linear"
    assert f"dB re 1 {unit}" in ax.get_ylabel()
    frf, ref = result.frf, base.frf
    curves = _curves(fig)
    assert len(curves) == min(9, frf.H.shape[1] * frf.H.shape[2])
    pairs = [(i, j) for i in range(frf.H.shape[1]) for j in range(frf.H.shape[2])]
    for line, (i, j) in zip(curves, pairs):
        drawn = np.asarray(line.get_ydata(), dtype=float)
        stored = 20 * np.log10(np.abs(frf.H[:, i, j]))
        independent = 20 * np.log10(np.abs(ref.H[:, i, j]) * ref.omega ** power)
        assert np.allclose(line.get_xdata(), frf.omega, rtol=0, atol=0)
        assert np.abs(drawn - stored).max() < 1e-12
        assert np.abs(drawn - independent).max() < 1e-9
    # the argument overrides the case, through the public front door too
    log_fig = substruct.frf_figure(result, magnitude="log")
    assert log_fig.axes[0].get_yscale() == "log"
    assert "dB" not in log_fig.axes[0].get_ylabel()
    assert np.allclose(_curves(log_fig)[0].get_ydata(), np.abs(frf.H[:, 0, 0]), rtol=1e-15)


def test_db_single_frequency_matrix():
    """One frequency: the matrix picture shows the levels in dB."""
    case = load_case(CASE, ["output.pictures=false", "analysis.frf.omega=[7.5]",
                            "analysis.frf.magnitude=db"])
    result = run_case(case, model=build_model(case))
    image = draw_frf(result).axes[0].get_images()[0]
    assert np.allclose(image.get_array(), 20 * np.log10(np.abs(result.frf.H[0])), atol=1e-12)


def test_db_label_without_a_units_note():
    from substruct.viz.units import frf_axis_label

    assert frf_axis_label(None, db=True) == "|H|  (dB re 1 displacement / force)"
    assert frf_axis_label("N, mm, t, s", "mobility", db=True) == \
        "|H|  (dB re 1 mm/(N s); velocity / force)"
