"""Channel positions and directions from a Universal File (substruct.case.uff_geometry):
nodes of datasets 2411 and 15 in coordinate systems of 2420 and 18, the channels named by the
58 functions, against positions and axes worked out by hand; the refusals."""

from __future__ import annotations

import numpy as np
import pytest

from substruct.case.channel_files import read_channels
from substruct.case.errors import CaseError
from uff_plain import ascii58

C, S = np.cos(np.pi / 6), np.sin(np.pi / 6)
X = [10.0, 20.0]
Y = [1.0 + 1j, 2.0]


def _d25(*v: float) -> str:
    return "".join(f"{x:25.16E}".replace("E", "D") for x in v)


def _cs2420(label: int = 5, kind: int = 0, axes=((C, S, 0), (-S, C, 0), (0, 0, 1)),
            origin=(1.0, 2.0, 3.0)) -> str:
    rows = ["    -1", "  2420", f"{1:10d}", "part", f"{label:10d}{kind:10d}{8:10d}", "cs5",
            *(_d25(*r) for r in axes), _d25(*origin), "    -1"]
    return "\n".join(rows) + "\n"


def _cs18(label: int = 7, ref: int = 0, method: int = 1, o=(0, 0, 1), p=(0, 1, 1),
          q=(1, 1, 1)) -> str:
    rows = ["    -1", "    18", f"{label:10d}{0:10d}{ref:10d}{8:10d}{method:10d}", "cs7",
            "".join(f"{v:13.5E}" for v in (*o, *p)), "".join(f"{v:13.5E}" for v in q), "    -1"]
    return "\n".join(rows) + "\n"


def _nodes2411(nodes) -> str:
    rows = ["    -1", "  2411"]
    for label, d, u, xyz in nodes:
        rows += [f"{label:10d}{d:10d}{u:10d}{8:10d}", _d25(*xyz)]
    return "\n".join(rows + ["    -1"]) + "\n"


def _nodes15(nodes) -> str:
    rows = ["    -1", "    15"]
    rows += [f"{label:10d}{d:10d}{u:10d}{8:10d}" + "".join(f"{v:13.5E}" for v in xyz)
             for label, d, u, xyz in nodes]
    return "\n".join(rows + ["    -1"]) + "\n"


def _file(tmp_path, *parts, name="geo.uff"):
    path = tmp_path / name
    path.write_text("".join(parts))
    return path


def _good(tmp_path, **edits):
    parts = dict(
        cs5=_cs2420(), cs7=_cs18(),
        n2411=_nodes2411([(1, 5, 5, (1.0, 0.0, 0.0)), (2, 0, 7, (0.5, 0.5, 0.5))]),
        n15=_nodes15([(3, 7, 0, (1.0, 2.0, 3.0))]),
        f1=ascii58(X, Y, rsp=(1, 2), ref=(2, -3)), f2=ascii58(X, Y, rsp=(3, 1), ref=(2, -3)))
    parts.update(edits)
    return _file(tmp_path, *parts.values())


def test_positions_and_directions_in_the_nodes_coordinate_systems(tmp_path):
    table = read_channels(_good(tmp_path))
    assert [(c.name, c.kind, c.node) for c in table.channels] == [
        ("1.y", "sensor", "1"), ("2.z", "impact", "2"), ("3.x", "sensor", "3")]
    # node 1: local (1, 0, 0) in system 5 (30 degrees about z, origin (1, 2, 3)); its y axis
    np.testing.assert_allclose(table.get("1.y").position, [1 + C, 2 + S, 3], atol=1e-12)
    np.testing.assert_allclose(table.get("1.y").direction, [-S, C, 0], atol=1e-12)
    # node 2: global position, directions in system 7 (origin (0, 0, 1), +x point (0, 1, 1),
    # +xz-plane point (1, 1, 1): x = +Y, z = +X, y = z cross x = +Z; from dataset 18's three
    # points); the 58 code -3 is signed away: the channel is along +z of system 7
    np.testing.assert_allclose(table.get("2.z").position, [0.5, 0.5, 0.5], atol=1e-12)
    np.testing.assert_allclose(table.get("2.z").direction, [1, 0, 0], atol=1e-12)
    # node 3 (dataset 15): local (1, 2, 3) in system 7 -> (0,0,1) + 1 ex + 2 ey + 3 ez
    np.testing.assert_allclose(table.get("3.x").position, [3, 1, 3], atol=1e-5)
    np.testing.assert_allclose(table.get("3.x").direction, [1, 0, 0], atol=1e-12)


@pytest.mark.parametrize("edit, message", [
    (dict(cs5=_cs2420(kind=3)), "record 3 field 2, coordinate system 5 of type 3: not 0 "
     "(cartesian), 1 (cylindrical) or 2 (spherical)"),
    (dict(cs5=_cs2420(axes=((1, 0, 0), (1, 0, 0), (0, 0, 1)))),
     "are not a right-handed orthonormal triad"),
    (dict(cs7=_cs18(q=(0, 2, 1))), "are on one line: no coordinate system"),
    (dict(cs7=_cs18(method=2)), "method of definition 2 is not supported"),
    (dict(cs7=_cs18(ref=9)), "reference coordinate system 9 is not defined before it"),
    (dict(cs7=_cs2420(label=5)), "coordinate system 5 is defined twice"),
    (dict(n15=_nodes15([(3, 4, 0, (1.0, 2.0, 3.0))])),
     "node 3: record 1 field 2, definition coordinate system 4: not defined in the "
     "file (datasets 18/2420)"),
    (dict(n15=_nodes15([(4, 0, 0, (1.0, 2.0, 3.0))])),
     "record 6 fields 6 and 7 (response): node 3 has no coordinates"),
    (dict(f2=ascii58(X, Y, rsp=(3, 5), ref=(2, -3))),
     "direction 5 at node 3 is not a translation"),
    (dict(f2=ascii58(X, Y, rsp=(2, 3), ref=(1, 2))), "channel 2.z is both a response and a "
     "reference"),
])
def test_refused_in_one_line(tmp_path, edit, message):
    with pytest.raises(CaseError) as err:
        read_channels(_good(tmp_path, **edit))
    text = str(err.value)
    assert text.startswith("geo.uff: ") and message in text and "\n" not in text, text
