"""The FRF picture follows its grid: a log grid on a log axis (even over less than two decades),
a linear one on a linear axis; markers at the points of a sparse grid only."""

from __future__ import annotations

from pathlib import Path

import pytest

from substruct.case.loader import load_case
from substruct.run.runner import build_model, run_case
from substruct.viz.frf_picture import SPARSE_GRID, frf_figure

CASE = Path(__file__).resolve().parents[1] / "cases" / "tapered_rod.yaml"


def _axes(grid: str):
    case = load_case(CASE, [f"analysis.frf.omega={grid}", "output.pictures=false"])
    fig = frf_figure(run_case(case, model=build_model(case)))
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
