"""Cylindrical and spherical coordinate systems of a Universal File (substruct.case.uff_frames,
uff_geometry): points defined in global cartesian coordinates, written as (r, theta, z) or
(r, theta, phi) in a turned and shifted system (2420 and 18), read back at their cartesian
definitions; the direction codes 1-3 of a 58 at those nodes along the unit vectors e_r,
e_theta, e_z (e_phi) worked out from the cartesian position alone (no angle formula); the
same file written by pyuff; lengths of a file in millimetres scaled, angles not; a system of
dataset 18 whose three points are given in a cylindrical reference system; the refusal of a
node on the axis of a displacement system it is not defined in."""

from __future__ import annotations

import numpy as np
import pytest

from substruct.case.channel_files import read_channels
from substruct.case.errors import CaseError
from substruct.case.uff_geometry import node_positions, uff_coordinate_systems
from substruct.case.uff_records import read_uff_records
from uff_plain import ascii58

X = [10.0, 20.0]
Y = [1.0 + 1j, 2.0]
RNG = np.random.default_rng(27)
A_CYL = np.linalg.qr(RNG.normal(size=(3, 3)))[0]
A_CYL = A_CYL * np.sign(np.linalg.det(A_CYL))            # right-handed
O_CYL = np.array([0.3, -0.2, 0.7])
P_CYL = RNG.uniform(-1.0, 1.0, size=(5, 3))              # global cartesian definitions
P_SPH = RNG.uniform(-1.0, 1.0, size=(5, 3))
# the spherical system by dataset 18: origin, a point on +x, a point in the +xz plane
O_SPH = np.array([-0.4, 0.1, 0.2])
EX = np.array([1.0, 2.0, -0.5]) / np.linalg.norm([1.0, 2.0, -0.5])
EZ = np.cross(EX, [0.3, -1.0, 2.0])
EZ /= np.linalg.norm(EZ)
A_SPH = np.array([EX, np.cross(EZ, EX), EZ])


def _d25(*v: float) -> str:
    return "".join(f"{x:25.16E}".replace("E", "D") for x in v)


def _cyl(p: np.ndarray, A: np.ndarray, o: np.ndarray) -> tuple[float, float, float]:
    x, y, z = A @ (p - o)
    return float(np.hypot(x, y)), float(np.degrees(np.arctan2(y, x))), float(z)


def _sph(p: np.ndarray, A: np.ndarray, o: np.ndarray) -> tuple[float, float, float]:
    x, y, z = A @ (p - o)
    return (float(np.sqrt(x * x + y * y + z * z)),
            float(np.degrees(np.arctan2(np.hypot(x, y), z))),
            float(np.degrees(np.arctan2(y, x))))


def _expected_axes(p: np.ndarray, A: np.ndarray, o: np.ndarray, kind: int) -> np.ndarray:
    """Rows e_r, e_theta, e_z (cylindrical) or e_r, e_theta, e_phi (spherical), from the
    cartesian position: radial and azimuthal directions, then their cross product."""
    d = p - o
    axial = A[2]
    ring = d - (d @ axial) * axial                      # off the axis, in the xy plane
    e_ring = ring / np.linalg.norm(ring)
    e_az = np.cross(axial, e_ring)                      # towards +theta (cyl) / +phi (sph)
    if kind == 1:
        return np.array([e_ring, e_az, axial])
    e_r = d / np.linalg.norm(d)
    return np.array([e_r, np.cross(e_az, e_r), e_az])


def _nodes2411(nodes) -> str:
    rows = ["    -1", "  2411"]
    for label, d, u, xyz in nodes:
        rows += [f"{label:10d}{d:10d}{u:10d}{8:10d}", _d25(*xyz)]
    return "\n".join(rows + ["    -1"]) + "\n"


def _parts(scale: float = 1.0):
    cs2420 = ["    -1", "  2420", f"{1:10d}", "part", f"{4:10d}{1:10d}{8:10d}", "cyl",
              *(_d25(*r) for r in A_CYL), _d25(*(O_CYL * scale)), "    -1"]
    # dataset 18 has 13-column fields (1P6E13.5), too few digits for 1e-14: the spherical
    # system here is a 2420 (18 is checked with short decimals below)
    sph = ["    -1", "  2420", f"{1:10d}", "part", f"{6:10d}{2:10d}{8:10d}", "sph",
           *(_d25(*r) for r in A_SPH), _d25(*(O_SPH * scale)), "    -1"]
    nodes = []
    for i, p in enumerate(P_CYL):
        r, t, z = _cyl(p, A_CYL, O_CYL)
        nodes.append((10 + i, 4, 4, (r * scale, t, z * scale)))
    for i, p in enumerate(P_SPH):
        r, t, f = _sph(p, A_SPH, O_SPH)
        nodes.append((20 + i, 6, 6, (r * scale, t, f)))
    # defined in the global system, directions in the cylindrical one (angles from position)
    nodes.append((30, 0, 4, tuple(P_SPH[0] * scale)))
    heads = ["\n".join(cs2420) + "\n", "\n".join(sph) + "\n", _nodes2411(nodes)]
    return heads, [n[0] for n in nodes]


def _functions(labels) -> str:
    # each node's three codes as responses, one reference at the first node
    return "".join(ascii58(X, Y, rsp=(n, k), ref=(labels[0], 1))
                   for n in labels[1:] for k in (1, 2, 3))


def _check(table, labels) -> None:
    cases = [(10 + i, p, A_CYL, O_CYL, 1) for i, p in enumerate(P_CYL)]
    cases += [(20 + i, p, A_SPH, O_SPH, 2) for i, p in enumerate(P_SPH)]
    cases += [(30, P_SPH[0], A_CYL, O_CYL, 1)]
    scale = max(np.abs(P_CYL).max(), np.abs(P_SPH).max())
    for node, p, A, o, kind in cases:
        if node == labels[0] or node not in labels:
            continue
        axes = _expected_axes(p, A, o, kind)
        for k in range(3):
            c = table.get(f"{node}.{'xyz'[k]}")
            assert np.abs(c.position - p).max() <= 1e-14 * scale, (node, c.position - p)
            assert np.abs(c.direction - axes[k]).max() <= 1e-14, (node, k)


def test_cylindrical_and_spherical_read_at_their_cartesian_definitions(tmp_path):
    heads, labels = _parts()
    path = tmp_path / "curved.uff"
    path.write_text("".join(heads) + _functions(labels))
    _check(read_channels(path), labels)
    # the reference node too: its position from node_positions
    read = read_uff_records(path)
    pos, axes = node_positions(read, uff_coordinate_systems(read))[10]
    assert np.abs(pos - P_CYL[0]).max() <= 1e-14
    assert np.abs(axes - _expected_axes(P_CYL[0], A_CYL, O_CYL, 1)).max() <= 1e-14


def test_millimetres_scale_the_lengths_not_the_angles(tmp_path):
    heads, labels = _parts(scale=1000.0)
    units = ["    -1", "   164", f"{5:10d}{'mm (milli newton)':<20}{2:10d}",
             _d25(1000.0, 1000.0, 1.0), _d25(273.15), "    -1"]
    path = tmp_path / "mm.uff"
    path.write_text("\n".join(units) + "\n" + "".join(heads) + _functions(labels))
    table = read_channels(path)
    assert table.units == "m"
    _check(table, labels)


def test_spherical_system_by_three_points(tmp_path):
    # dataset 18 (6 significant digits): the points given exactly by short decimals
    pts = [(0.5, -0.25, 1.0), (1.5, -0.25, 1.0), (0.5, 0.75, 2.0)]   # +x along X; xz plane
    # e_x = +X; the xz point (0, 1, 1) from the origin: e_z = (0, 1, 1)/sqrt(2), e_y = e_z x e_x
    A = np.array([[1.0, 0, 0], [0, np.sqrt(0.5), -np.sqrt(0.5)], [0, np.sqrt(0.5),
                                                                 np.sqrt(0.5)]])
    o = np.array(pts[0])
    rows = ["    -1", "    18", f"{6:10d}{2:10d}{0:10d}{8:10d}{1:10d}", "sph",
            "".join(f"{v:13.5E}" for v in (*pts[0], *pts[1])),
            "".join(f"{v:13.5E}" for v in pts[2]), "    -1"]
    p = np.array([0.9, 0.3, -0.4])
    nodes = _nodes2411([(1, 6, 6, _sph(p, A, o)), (2, 0, 0, (0.0, 0.0, 0.0))])
    path = tmp_path / "s18.uff"
    path.write_text("\n".join(rows) + "\n" + nodes
                    + "".join(ascii58(X, Y, rsp=(1, k), ref=(2, 1)) for k in (1, 2, 3)))
    table = read_channels(path)
    axes = _expected_axes(p, A, o, 2)
    for k in range(3):
        c = table.get(f"1.{'xyz'[k]}")
        assert np.abs(c.position - p).max() <= 1e-14
        assert np.abs(c.direction - axes[k]).max() <= 1e-14


def test_written_by_pyuff(tmp_path):
    pyuff = pytest.importorskip("pyuff")
    heads, labels = _parts()
    path = tmp_path / "p.uff"
    nodes = []
    for i, p in enumerate(P_CYL):
        nodes.append((10 + i, 4, *_cyl(p, A_CYL, O_CYL)))
    for i, p in enumerate(P_SPH):
        nodes.append((20 + i, 6, *_sph(p, A_SPH, O_SPH)))
    sets = [pyuff.prepare_2420(Part_UID=1, Part_Name="lab", CS_sys_labels=[4, 6],
                               CS_types=[1, 2], CS_colors=[8, 8], CS_names=["cyl", "sph"],
                               CS_matrices=[np.vstack([A_CYL, O_CYL]),
                                            np.vstack([A_SPH, O_SPH])]),
            pyuff.prepare_2411(node_nums=[n[0] for n in nodes], def_cs=[n[1] for n in nodes],
                               disp_cs=[n[1] for n in nodes], color=[8] * len(nodes),
                               x=[n[2] for n in nodes], y=[n[3] for n in nodes],
                               z=[n[4] for n in nodes])]
    for n in labels[1:-1]:
        for k in (1, 2, 3):
            sets.append(pyuff.prepare_58(
                binary=0, func_type=4, rsp_node=n, rsp_dir=k, ref_node=labels[0], ref_dir=1,
                ord_data_type=6, num_pts=len(X), abscissa_spacing=0,
                abscissa_spec_data_type=18, ordinate_spec_data_type=8,
                orddenom_spec_data_type=13, data=np.array(Y), x=np.array(X)))
    pyuff.UFF(str(path)).write_sets(sets, mode="add")
    _check(read_channels(path), labels[:-1])


def test_a_node_on_the_axis_of_its_displacement_system_refused(tmp_path):
    heads, labels = _parts()
    on_axis = O_CYL + 0.5 * A_CYL[2]
    extra = _nodes2411([(40, 0, 4, tuple(on_axis))])
    path = tmp_path / "axis.uff"
    path.write_text("".join(heads) + extra + ascii58(X, Y, rsp=(40, 1), ref=(10, 1)))
    with pytest.raises(CaseError) as err:
        read_channels(path)
    text = str(err.value)
    assert text.startswith("axis.uff: node 40: it lies on the axis of its cylindrical "
                           "displacement coordinate system 4") and "\n" not in text, text


@pytest.mark.parametrize("scale", [1.0, 1000.0])
def test_three_points_given_in_a_cylindrical_reference(tmp_path, scale):
    # system 4: cylindrical, the global axes; system 7 by dataset 18 with the reference 4:
    # origin (r, theta, z) = (1, 90, 0) -> (0, 1, 0); +x point (1, 0, 0) -> (1, 0, 0);
    # +xz point (1, 90, 1) -> (0, 1, 1): e_x = (1, -1, 0)/sqrt 2, e_z = +Z, e_y = (1, 1, 0)/sqrt 2
    cyl = ["    -1", "  2420", f"{1:10d}", "part", f"{4:10d}{1:10d}{8:10d}", "cyl",
           _d25(1, 0, 0), _d25(0, 1, 0), _d25(0, 0, 1), _d25(0, 0, 0), "    -1"]
    pts = [(scale, 90.0, 0.0), (scale, 0.0, 0.0), (scale, 90.0, scale)]
    s18 = ["    -1", "    18", f"{7:10d}{0:10d}{4:10d}{8:10d}{1:10d}", "by points",
           "".join(f"{v:13.5E}" for v in (*pts[0], *pts[1])),
           "".join(f"{v:13.5E}" for v in pts[2]), "    -1"]
    units = ["    -1", "   164", f"{5:10d}{'mm (milli newton)':<20}{2:10d}",
             _d25(1000.0, 1000.0, 1.0), _d25(273.15), "    -1"] if scale != 1.0 else []
    nodes = _nodes2411([(1, 7, 7, (2 * scale, 3 * scale, 4 * scale)),
                        (2, 0, 0, (0.0, 0.0, 0.0))])
    path = tmp_path / "ref.uff"
    path.write_text("".join("\n".join(b) + "\n" for b in (units, cyl, s18) if b) + nodes
                    + "".join(ascii58(X, Y, rsp=(1, k), ref=(2, 1)) for k in (1, 2, 3)))
    table = read_channels(path)
    h = np.sqrt(0.5)
    want = np.array([5 * h, 1 + h, 4.0])
    axes = np.array([[h, -h, 0], [h, h, 0], [0, 0, 1]])
    for k in range(3):
        c = table.get(f"1.{'xyz'[k]}")
        assert np.abs(c.position - want).max() <= 1e-14 * np.abs(want).max()
        assert np.abs(c.direction - axes[k]).max() <= 1e-14
