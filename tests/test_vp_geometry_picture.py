"""The virtual-point geometry picture of ``substruct run`` (substruct.viz.vp_geometry_picture)
on the shipped coupling case: the file is written beside the result, and the points and
arrows drawn are the channel tables' positions and directions, read independently of the
case loader from the CSV files."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

from substruct import cli
from substruct.case.loader import load_case
from substruct.viz.vp_geometry_picture import arrow_length, draw_vp_geometry, vp_geometry

ROOT = Path(__file__).resolve().parent.parent
CASE = ROOT / "cases" / "vpt_coupling.yaml"


def _table(path: Path) -> dict[str, tuple[np.ndarray, np.ndarray, str]]:
    with path.open(newline="") as f:
        return {r["name"]: (np.array([float(r[k]) for k in "xyz"]),
                            np.array([float(r["d" + k]) for k in "xyz"]), r["kind"])
                for r in csv.DictReader(f)}


@pytest.fixture(scope="module")
def out(tmp_path_factory):
    out = tmp_path_factory.mktemp("vpgeo")
    assert cli.main(["run", str(CASE), "--out", str(out), "--quiet"]) == 0
    return out


def test_the_picture_is_written_by_run(out):
    import matplotlib.image

    png = out / "vpt_coupling_vp_geometry.png"
    assert png.is_file()
    assert matplotlib.image.imread(png)[..., :3].std() > 0.01  # not blank
    from substruct.io.result_reader import load
    assert "vpt_coupling_vp_geometry.png" in load(out / "vpt_coupling.h5").attrs["pictures"]


def test_no_picture_with_no_pictures(tmp_path):
    assert cli.main(["run", str(CASE), "--out", str(tmp_path), "--quiet",
                     "--no-pictures"]) == 0
    assert not list(tmp_path.glob("*.png"))


def test_the_drawn_points_and_arrows_are_the_channel_tables():
    case = load_case(CASE)
    geo = vp_geometry(case)
    assert list(geo) == ["A", "B"]
    fig = draw_vp_geometry(geo)
    assert len(fig.axes) == 2
    for ax, (part, g) in zip(fig.axes, geo.items()):
        table = _table(ROOT / "cases" / "vpt_coupling" / f"{part.lower()}_channels.csv")
        assert part in ax.get_title()
        ell = arrow_length(g)
        assert ell > 0
        points = {c.get_label(): c for c in ax.collections}
        for kind, names in (("sensor", g.sensors), ("impact", g.impacts)):
            want = [n for n, (_, _, k) in table.items() if k == kind]
            assert names == want
            xyz = np.array([table[n][0] for n in names])
            d = np.array([table[n][1] for n in names])
            drawn = np.column_stack(points[f"{kind}s"]._offsets3d)
            np.testing.assert_allclose(drawn, xyz, rtol=0, atol=1e-15)
            # each arrow's shaft (matplotlib stores it tip first): from the position along
            # the direction, length ell
            segs = np.asarray(points[f"{kind} directions"]._segments3d)[:len(names)]
            tip, tail = segs[:, 0], segs[:, -1]
            np.testing.assert_allclose(tail, xyz, rtol=0, atol=1e-15)
            np.testing.assert_allclose((tip - tail) / ell, d, rtol=0, atol=1e-12)
        vp = np.column_stack(points["virtual points"]._offsets3d)
        np.testing.assert_array_equal(vp, [[0.0, 0.0, 0.0]])
        assert ax.get_legend() is not None
        # equal aspect: the three axes' box spans are in the ratio of their data spans
        spans = np.array([np.ptp(ax.get_xlim3d()), np.ptp(ax.get_ylim3d()),
                          np.ptp(ax.get_zlim3d())])
        np.testing.assert_allclose(np.asarray(ax.get_box_aspect()) / spans,
                                   ax.get_box_aspect()[0] / spans[0], rtol=1e-6)
