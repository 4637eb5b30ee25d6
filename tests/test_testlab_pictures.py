"""The test-lab pictures of ``substruct run`` (substruct.viz.testlab_picture) on the shipped
transfer-path case: the files are written beside the result (and not with --no-pictures),
and the curves drawn are the numbers of the result file."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from substruct import cli
from substruct.io.result_reader import load
from substruct.viz.testlab_picture import (MAX_PAIRS, draw_consistency, draw_monte_carlo,
                                           draw_paths, draw_validation)

ROOT = Path(__file__).resolve().parent.parent
CASE = ROOT / "cases" / "vpt_coupling_tpa.yaml"
VP_CASE = ROOT / "cases" / "vpt_coupling.yaml"
ANCHOR = "          impacts: [H1, H2, H3, H4, H5, H6, H7, H8, H9]\n  - name: B"


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


@pytest.fixture(scope="module")
def noisy(tmp_path_factory):
    """The shipped coupling case with a Monte Carlo study of 3 outputs x 2 inputs."""
    tmp = tmp_path_factory.mktemp("mc")
    text = VP_CASE.read_text().replace("vpt_coupling/", f"{VP_CASE.parent / 'vpt_coupling'}/")
    block = ("      monte_carlo: {level: 0.01, samples: 8, seed: 3, percentiles: [5, 50, 95], "
             "outputs: [A@vp:J:ux, A@vp:J:uy, A@ch:A4x], inputs: [B@ch:B14x, A@vp:J:uz]}\n")
    assert ANCHOR in text
    case = tmp / "noisy.yaml"
    case.write_text(text.replace(ANCHOR, ANCHOR.replace("\n  - name: B", f"\n{block}  - name: B")))
    out = tmp / "out"
    assert cli.main(["run", str(case), "--out", str(out), "--quiet"]) == 0
    return out, load(out / "vpt_coupling.h5")


def test_the_monte_carlo_picture_is_the_study(noisy):
    import matplotlib.image

    out, res = noisy
    png = out / "vpt_coupling_monte_carlo.png"
    assert png.name in res.attrs["pictures"].split("\n")
    assert matplotlib.image.imread(png)[..., :3].std() > 0.01  # not blank
    mc = res.monte_carlo
    fig = draw_monte_carlo(res)
    pairs = [(o, i) for o in range(3) for i in range(2)]
    assert len(fig.axes) == min(len(pairs), MAX_PAIRS) == 6
    for ax, (o, i) in zip(fig.axes, pairs):
        assert mc.outputs[o] in ax.get_title() and mc.inputs[i] in ax.get_title()
        lines = {line.get_label(): line for line in ax.get_lines()}
        np.testing.assert_array_equal(lines["nominal |H|"].get_xdata(), res.frf.omega)
        # the nominal is the coupled receptance of the run at that pair
        H = res.frf.H[:, res.frf.outputs.index(mc.outputs[o]), res.frf.inputs.index(mc.inputs[i])]
        np.testing.assert_array_equal(lines["nominal |H|"].get_ydata(), np.abs(H))
        for k, q in enumerate((5, 50, 95)):
            np.testing.assert_array_equal(lines[f"{q}th percentile"].get_ydata(),
                                          mc.bands[k][:, o, i])
        lo, hi = mc.bands[0][:, o, i], mc.bands[2][:, o, i]
        assert np.all(lo <= hi) and np.any(lo < hi)  # a band, not a line, at 1 % noise
    # fewer pairs drawn than asked: the rest are named, not silently dropped
    two = draw_monte_carlo(res, max_pairs=2)
    assert len(two.axes) == 2
    assert any("4 more pair(s)" in t.get_text() for t in two.axes[-1].texts)
