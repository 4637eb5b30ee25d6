"""The test-lab pictures of ``substruct run`` (substruct.viz.testlab_picture) on the shipped
transfer-path case: the files are written beside the result (and not with --no-pictures),
and the curves drawn are the numbers of the result file."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from substruct import cli
from substruct.io.result_reader import load
from substruct.viz.testlab_picture import draw_consistency, draw_paths, draw_validation

ROOT = Path(__file__).resolve().parent.parent
CASE = ROOT / "cases" / "vpt_coupling_tpa.yaml"


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    out = tmp_path_factory.mktemp("lab")
    assert cli.main(["run", str(CASE), "--out", str(out), "--quiet"]) == 0
    return out, load(out / "vpt_coupling_tpa.h5")


def _lines(fig):
    return {line.get_label(): line for ax in fig.axes for line in ax.get_lines()}


def test_the_pictures_are_written(run):
    import matplotlib.image

    out, _ = run
    names = sorted(p.name for p in out.iterdir())
    assert names == ["vpt_coupling_tpa.h5", "vpt_coupling_tpa_consistency.png",
                     "vpt_coupling_tpa_frf.png", "vpt_coupling_tpa_paths.png",
                     "vpt_coupling_tpa_validation.png",
                     "vpt_coupling_tpa_vp_geometry.png"]
    for png in out.glob("*.png"):
        assert matplotlib.image.imread(png)[..., :3].std() > 0.01  # not blank


def test_the_consistency_curves_are_the_indicators(run):
    _, res = run
    w = res.frf.omega
    fig = draw_consistency(res)
    assert len(fig.axes) == 2  # A and B
    for ax, (part, ind) in zip(fig.axes, res.virtual_points.items()):
        lines = {line.get_label(): line for line in ax.get_lines()}
        assert part in ax.get_title()
        np.testing.assert_array_equal(lines["J: sensors (overall)"].get_xdata(), w)
        np.testing.assert_array_equal(lines["J: sensors (overall)"].get_ydata(),
                                      ind.overall_u["J"])
        np.testing.assert_array_equal(lines["J: impacts (overall)"].get_ydata(),
                                      ind.overall_f["J"])
        np.testing.assert_array_equal(lines["_sensor S2y"].get_ydata(), ind.specific_u["S2y"])
        np.testing.assert_array_equal(lines["_impact H7"].get_ydata(), ind.specific_f["H7"])


def test_the_path_and_validation_curves_are_the_results(run):
    _, res = run
    tpa = res.tpa
    fig = draw_paths(res)
    assert len(fig.axes) == len(tpa.targets)
    for t, ax in enumerate(fig.axes):
        lines = {line.get_label(): line for line in ax.get_lines()}
        top = np.cumsum(np.abs(tpa.contributions[:, t]), axis=1)
        for j, path in enumerate(tpa.interface):
            np.testing.assert_array_equal(lines[path].get_ydata(), top[:, j])
        np.testing.assert_array_equal(lines["|prediction| (sum with phases)"].get_ydata(),
                                      np.abs(tpa.predicted[:, t]))
        # the stack's top is at least the prediction (triangle inequality)
        assert np.all(top[:, -1] >= np.abs(tpa.predicted[:, t]) * (1 - 1e-12))
    lines = _lines(draw_validation(res))
    for t, name in enumerate(tpa.targets):
        np.testing.assert_array_equal(lines[f"{name} measured"].get_ydata(),
                                      np.abs(tpa.measured[:, t]))
        np.testing.assert_array_equal(lines[f"{name} predicted"].get_ydata(),
                                      np.abs(tpa.predicted[:, t]))
    np.testing.assert_array_equal(lines["relative error"].get_ydata(), tpa.error)
