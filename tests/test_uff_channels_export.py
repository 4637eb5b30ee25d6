"""The test geometry of a virtual-point result: kept in the result file (``/channels``) and
read back bit for bit, and written to a Universal File by ``substruct export --format uff``
(151 with the case name, 164 SI, 2411 nodes, 2420 systems, 58 functions at those nodes and direction codes), read
back by substruct's own reader and by pyuff to the same numbers: positions and directions
against the channel tables of the shipped case (read here with the csv module), receptances
against the result's."""

from __future__ import annotations

import csv
import dataclasses
from pathlib import Path

import numpy as np
import pytest

from substruct import cli
from substruct.case.frf_files import read_frf_file
from substruct.case.uff_geometry import node_positions, uff_coordinate_systems
from substruct.case.uff_records import read_uff_records
from substruct.io.result_reader import load
from substruct.io.uff import export_uff

ROOT = Path(__file__).resolve().parent.parent
CASE = ROOT / "cases" / "vpt_coupling.yaml"
CODES = {"ux": 1, "uy": 2, "uz": 3, "rx": 4, "ry": 5, "rz": 6}


def _csv(part: str) -> dict[str, tuple[np.ndarray, np.ndarray, str]]:
    path = ROOT / "cases" / "vpt_coupling" / f"{part.lower()}_channels.csv"
    with path.open(newline="") as f:
        out = {}
        for r in csv.DictReader(f):
            d = np.array([float(r["d" + k]) for k in "xyz"])
            out[r["name"]] = (np.array([float(r[k]) for k in "xyz"]), d / np.linalg.norm(d),
                              r["kind"])
        return out


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    out = tmp_path_factory.mktemp("vpuff")
    assert cli.main(["run", str(CASE), "--out", str(out), "--quiet", "--no-pictures"]) == 0
    return out, load(out / "vpt_coupling.h5")


def test_the_result_file_keeps_the_channel_tables(run):
    _, result = run
    assert list(result.channels) == ["A", "B"]
    for part, pc in result.channels.items():
        table = _csv(part)
        assert [c.name for c in pc.table.channels] == list(table)
        assert pc.table.source == f"{part.lower()}_channels.csv" and pc.table.units == ""
        for c in pc.table.channels:
            xyz, e, kind = table[c.name]
            assert c.kind == kind
            np.testing.assert_array_equal(c.position, xyz)
            np.testing.assert_allclose(c.direction, e, rtol=0, atol=2e-16)
        assert pc.points == ("J",)
        np.testing.assert_array_equal(pc.point_xyz, [[0.0, 0.0, 0.0]])


def test_the_result_file_round_trips_the_geometry_exactly(run, tmp_path):
    from substruct.case.loader import load_case
    from substruct.io.hdf5 import save

    case = load_case(CASE)
    _, result = run
    for s in case.substructures:  # the case's own tables, as the run used them
        assert result.channels[s.name].table.channels == s.virtual_points.table().channels
    save(result, tmp_path / "again.h5")
    back = load(tmp_path / "again.h5")
    for part, pc in result.channels.items():
        assert back.channels[part].table == pc.table
        np.testing.assert_array_equal(back.channels[part].point_xyz, pc.point_xyz)


def _expected(result, name):
    """(global position, global direction) of a point, from the channel tables."""
    part, _, local = name.partition("@")
    pc = result.channels[part]
    kind, _, rest = local.partition(":")
    if kind == "vp":
        point, _, comp = rest.rpartition(":")
        return pc.point_xyz[pc.points.index(point)], CODES[comp]
    c = pc.table.get(rest)
    return np.array(c.position), np.array(c.direction)


def test_export_writes_nodes_systems_and_direction_codes(run):
    out, result = run
    path = out / "vp.unv"
    assert cli.main(["export", str(out / "vpt_coupling.h5"), "--format", "uff", "--out",
                     str(path)]) == 0
    read = read_uff_records(path)
    assert read.header is not None and read.header.model_name == "vpt_coupling"
    assert read.units is not None and (read.units.code, read.units.length,
                                       read.units.force) == (1, 1.0, 1.0)
    where = node_positions(read, uff_coordinate_systems(read))
    frf = result.frf
    assert len(read.functions) == len(frf.outputs) * len(frf.inputs)
    f_hz = frf.omega / (2 * np.pi)
    for k, f in enumerate(read.functions):
        i, j = divmod(k, len(frf.inputs))
        np.testing.assert_array_equal(f.y, frf.H[:, i, j])
        np.testing.assert_array_equal(f.x, f_hz)
        for node, code, name in ((f.rsp_node, f.rsp_dir, frf.outputs[i]),
                                 (f.ref_node, f.ref_dir, frf.inputs[j])):
            xyz, direction = _expected(result, name)
            pos, A = where[node]
            np.testing.assert_array_equal(pos, xyz)
            if isinstance(direction, int):      # a virtual-point coordinate: global axes
                assert code == direction and np.array_equal(A, np.eye(3))
            else:                                # a channel: +x of its own system
                assert code == 1
                np.testing.assert_array_equal(A[0], direction)
    # pyuff, an independent reader, finds the same nodes, systems and functions
    pyuff = pytest.importorskip("pyuff")
    sets = pyuff.UFF(str(path)).read_sets()
    by_type: dict[int, list] = {}
    for s in sets:
        by_type.setdefault(s["type"], []).append(s)
    assert by_type[151][0]["model_name"] == "vpt_coupling"
    assert by_type[164][0]["units_code"] == 1 and by_type[164][0]["length"] == 1.0
    nodes = by_type[2411][0]
    cs = {int(lab): m for lab, m in zip(by_type[2420][0]["CS_sys_labels"],
                                        by_type[2420][0]["CS_matrices"])}
    for k, s in enumerate(by_type[58]):
        i, j = divmod(k, len(frf.inputs))
        np.testing.assert_array_equal(s["data"], frf.H[:, i, j])
        at = list(nodes["node_nums"]).index(s["rsp_node"])
        xyz, direction = _expected(result, frf.outputs[i])
        np.testing.assert_array_equal([nodes["x"][at], nodes["y"][at], nodes["z"][at]], xyz)
        if not isinstance(direction, int):
            np.testing.assert_array_equal(cs[int(nodes["disp_cs"][at])][0], direction)
            np.testing.assert_array_equal(cs[int(nodes["disp_cs"][at])][3], xyz)


def test_a_square_export_reads_back_as_receptances_exactly(run, tmp_path):
    _, result = run
    labels = [f"A@vp:J:{c}" for c in CODES] + ["A@ch:A4x", "A@ch:S1x", "A@ch:H3"]
    rng = np.random.default_rng(1)
    n, k = len(labels), len(result.frf.omega)
    H = rng.normal(size=(k, n, n)) + 1j * rng.normal(size=(k, n, n))
    square = dataclasses.replace(result, frf=dataclasses.replace(
        result.frf, outputs=labels, inputs=labels, H=H), modes=None)
    omega, got, back = read_frf_file(export_uff(square, tmp_path / "sq.unv"))
    np.testing.assert_allclose(omega, result.frf.omega, rtol=1e-15)
    # nodes: the point J of A first, then one per channel, in the order met
    assert got == [f"1:{c[-1] if c[0] == 'u' else c}" for c in CODES] + ["2:x", "3:x", "4:x"]
    np.testing.assert_array_equal(back, H)


def test_the_geometry_picture_is_drawn_from_the_result(run):
    from substruct.case.loader import load_case
    from substruct.viz.vp_geometry_picture import geometry_of, vp_geometry

    _, result = run
    stored, case = geometry_of(result.channels), vp_geometry(load_case(CASE))
    assert list(stored) == list(case)
    for part in stored:
        a, b = dataclasses.asdict(stored[part]), dataclasses.asdict(case[part])
        for key in a:
            np.testing.assert_array_equal(np.asarray(a[key]), np.asarray(b[key]))


@pytest.mark.parametrize("edit, message", [
    (lambda g: g["directions"].__setitem__((0, 0), 2.0), "/channels/0/directions holds a "
     "direction that is not of unit length"),
    (lambda g: g["positions"].__setitem__((1, 2), np.nan), "positions"),
    (lambda g: g["kinds"].__setitem__(0, "probe"), "kind: one of sensor, impact"),
    (lambda g: g.attrs.__setitem__("part", "B"), "part 'B' twice in /channels"),
])
def test_a_damaged_channels_group_is_refused(run, tmp_path, edit, message):
    import shutil

    import h5py

    out, _ = run
    path = tmp_path / "bad.h5"
    shutil.copy(out / "vpt_coupling.h5", path)
    with h5py.File(path, "r+") as f:
        edit(f["channels/0"])
    with pytest.raises(ValueError) as err:
        load(path)
    text = str(err.value)
    assert "not a substruct result" in text and message in text and "\n" not in text, text


def test_a_uff_table_keeps_its_units_and_header_in_the_result(run, tmp_path):
    from substruct.case.channel_geometry import PartChannels
    from substruct.case.uff_geometry import channels_from_uff
    from substruct.io.hdf5 import save
    from test_uff_units import FOOT, _cs2420, _header151, _nodes2411, _units164
    from uff_plain import ascii58

    path = tmp_path / "lab.uff"
    path.write_text(_header151() + _units164() + _cs2420() + _nodes2411()
                    + ascii58([10.0, 20.0], [1.0, 2.0], rsp=(1, 2), ref=(2, 1)))
    table = channels_from_uff(path)
    assert table.units == "m" and dict(table.header)["model_name"] == "bracket test"
    np.testing.assert_allclose(table.get("1.y").position, np.array([8.0, 1.0, 3.0]) * FOOT,
                               rtol=0, atol=1e-15)
    _, result = run
    mine = dataclasses.replace(result, channels={"A": PartChannels(table, ("J",),
                                                                   np.zeros((1, 3)))})
    save(mine, tmp_path / "uffgeo.h5")
    back = load(tmp_path / "uffgeo.h5").channels["A"]
    assert back.table == table and back.points == ("J",)
