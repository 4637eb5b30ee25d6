"""The test's channel geometry in the results file and through a Universal File: the shipped
virtual-point coupling (cases/vpt_coupling.yaml) run, its result holds each part's channel
table and virtual points exactly as the CSV tables give them; ``substruct export --format
uff`` writes 151, 164, 2420, 2411 and 58 datasets that read back (substruct.case.uff_records,
substruct.case.uff_geometry) to the same positions, directions and receptances bit for bit.
The 164 units dataset is honoured: a file in millimetres and newtons reads as the same file
in SI (to the two roundings of the conversion), and codes or factors that cannot be honoured
are refused in one line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from substruct import cli
from substruct.case.channel_files import read_channels
from substruct.case.uff_geometry import node_positions, uff_coordinate_systems
from substruct.case.uff_records import read_uff_records
from substruct.io.result_reader import load
from substruct.io.uff import uff58_bytes, uff58_sets

ROOT = Path(__file__).resolve().parent.parent
CASE = ROOT / "cases" / "vpt_coupling.yaml"
DATA = ROOT / "cases" / "vpt_coupling"
EPS = np.finfo(float).eps


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("uffch")
    case = tmp / "vpt_coupling.yaml"
    case.write_text(CASE.read_text().replace("vpt_coupling/", f"{DATA}/"))
    assert cli.main(["run", str(case), "--out", str(tmp / "out"), "--quiet",
                     "--no-pictures"]) == 0
    h5 = tmp / "out" / "vpt_coupling.h5"
    assert cli.main(["export", str(h5), "--format", "uff", "--out", str(tmp / "x.uff")]) == 0
    return load(h5), tmp / "x.uff"


def test_the_result_holds_the_channel_tables(exported):
    res, _ = exported
    for part in ("A", "B"):
        geo = res.virtual_points[part].geometry
        table = read_channels(DATA / f"{part.lower()}_channels.csv")
        assert geo.names == [c.name for c in table.channels]
        assert geo.kinds == [c.kind for c in table.channels]
        assert np.array_equal(geo.positions, table.positions(geo.names))
        assert np.array_equal(geo.directions, table.directions(geo.names))
        assert geo.point_names == ["J"] and np.array_equal(geo.point_positions, np.zeros((1, 3)))


def test_the_uff_export_reads_back_exactly(exported):
    res, path = exported
    uff = read_uff_records(path)
    assert uff.header is not None and uff.header.model == "vpt_coupling"
    assert uff.units is not None and uff.units.code == 1 and uff.units.is_si
    where = node_positions(uff, uff_coordinate_systems(uff))
    node = 0
    for part in ("A", "B"):
        geo = res.virtual_points[part].geometry
        for pos, d in zip(geo.positions, geo.directions):
            node += 1
            got_pos, A = where[node]
            assert np.array_equal(got_pos, pos) and np.array_equal(A[0], d)
        node += 1                                     # the virtual point J
        assert np.array_equal(where[node][0], geo.point_positions[0])
        assert np.array_equal(where[node][1], np.eye(3))
    frf = res.frf
    assert len(uff.functions) == len(frf.outputs) * len(frf.inputs)
    k = 0
    for i, out in enumerate(frf.outputs):
        for j, inp in enumerate(frf.inputs):
            f = uff.functions[k]
            k += 1
            assert np.array_equal(f.y, frf.H[:, i, j]), (out, inp)
            assert np.array_equal(f.x, frf.omega / (2 * np.pi))
    # a channel's direction code is +1 (its own system's x axis); J's are 1..6 in global axes
    a4x = frf.outputs.index("A@ch:A4x")
    f = uff.functions[a4x * len(frf.inputs)]
    assert f.rsp_dir == 1 and np.array_equal(
        where[f.rsp_node][1][0], res.virtual_points["A"].geometry.channel("A4x")[1])
    assert [uff.functions[r * len(frf.inputs)].rsp_dir for r in range(6)] == [1, 2, 3, 4, 5, 6]


def _d25(values) -> str:
    return "".join(f"{float(v):25.16E}" for v in values) + "\n"


def _units_file(path: Path, code: int, factors: tuple[float, float], scale_l: float,
                scale_y: float, numerator: int = 8, extra: str = "") -> None:
    """One node with its own system, one function from it to itself, in the units given:
    positions times ``scale_l``, the ordinate times ``scale_y``."""
    pos = np.array([0.0125, -0.25, 0.5])
    A = np.array([[0.6, 0.8, 0.0], [-0.8, 0.6, 0.0], [0.0, 0.0, 1.0]])
    w = np.array([10.0, 20.0, 30.0])
    H = np.array([1e-6 + 2e-7j, -3e-7 + 1e-8j, 5e-8 - 2e-9j])[:, None, None]
    text = (f"    -1\n   164\n{code:10d}{'units':<20}{2:10d}\n"
            f"{factors[0]:25.17E}{factors[1]:25.17E}{1.0:25.17E}\n{273.15:25.17E}\n    -1\n"
            + extra +
            f"    -1\n  2420\n{1:10d}\npart\n{7:10d}{0:10d}{8:10d}\nsys\n"
            + "".join(_d25(r) for r in A) + _d25(np.array([0.001, 0.0, 0.0]) * scale_l)
            + "    -1\n"
            f"    -1\n  2411\n{5:10d}{0:10d}{7:10d}{8:10d}\n" + _d25(pos * scale_l) + "    -1\n")
    s = uff58_sets(w, H * scale_y, ["5:x"], ["5:x"], nodes={"5:x": (5, 1)})[0]
    s["ordinate_spec_data_type"] = numerator
    path.write_bytes(text.encode() + uff58_bytes(s))


def test_units_are_converted_to_si(tmp_path):
    si, mm = tmp_path / "si.uff", tmp_path / "mm.uff"
    _units_file(si, 1, (1.0, 1.0), 1.0, 1.0)
    _units_file(mm, 10, (1000.0, 1.0), 1000.0, 1000.0)   # mm and newton: H in mm/N
    a, b = read_uff_records(si), read_uff_records(mm)
    assert b.units is not None and b.units.code == 10 and not b.units.is_si
    np.testing.assert_allclose(b.functions[0].y, a.functions[0].y, rtol=4 * EPS, atol=0)
    pa = node_positions(a, uff_coordinate_systems(a))[5][0]
    pb = node_positions(b, uff_coordinate_systems(b))[5][0]
    np.testing.assert_allclose(pb, pa, rtol=4 * EPS, atol=4 * EPS * np.abs(pa).max())
    # millimetre and millinewton: lengths / 1000, receptances (mm/mN = m/N) unchanged
    c = tmp_path / "mmn.uff"
    _units_file(c, 5, (1000.0, 1000.0), 1000.0, 1.0)
    uc = read_uff_records(c)
    assert np.array_equal(uc.functions[0].y, a.functions[0].y)


@pytest.mark.parametrize("code, factors, numerator, extra, words", [
    (11, (1.0, 1.0), 8, "", "record 1 field 1: units code 11 is not one of the "
     "specification's systems (1-10)"),
    (5, (1.0, 1000.0), 8, "", "record 2: the length factor of units code 5 (MM (millimetre, "
     "millinewton)) is 1000.0, not 1.0"),
    (9, (0.0, 1.0), 8, "", "record 2: the length factor must be positive and finite, not 0.0"),
    (10, (1000.0, 1.0), 0, "", "records 9-10: an ordinate of data type 0 over 13 cannot be "
     "converted from units code 10"),
    (10, (1000.0, 1.0), 8, f"    -1\n   164\n{1:10d}{'SI':<20}{2:10d}\n"
     f"{1.0:25.17E}{1.0:25.17E}{1.0:25.17E}\n{0.0:25.17E}\n    -1\n",
     "units code 1 differ from those of dataset 1"),
])
def test_units_that_cannot_be_honoured_are_refused(tmp_path, code, factors, numerator,
                                                   extra, words):
    path = tmp_path / "bad.uff"
    _units_file(path, code, factors, 1.0, 1.0, numerator, extra)
    with pytest.raises(ValueError) as err:
        read_uff_records(path)
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith("bad.uff: dataset ") and words in msg, msg


def test_a_second_model_header_is_refused(tmp_path):
    path = tmp_path / "two.uff"
    head = "    -1\n   151\nmodel\ndescription\nprogram\n    -1\n"
    _units_file(path, 1, (1.0, 1.0), 1.0, 1.0, extra=head + head)
    with pytest.raises(ValueError, match="a second model header"):
        read_uff_records(path)
    one = tmp_path / "one.uff"
    _units_file(one, 1, (1.0, 1.0), 1.0, 1.0, extra=head)
    h = read_uff_records(one).header
    assert h is not None and (h.model, h.description, h.program) == \
        ("model", "description", "program")
