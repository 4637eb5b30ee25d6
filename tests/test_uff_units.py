"""UFF datasets 151 (header) and 164 (units): the header's names and dates kept, lengths and
functions of a file in feet and pounds force turned into SI (against the foot and the pound
force by definition, 0.3048 m and 0.45359237 kg x 9.80665 m/s^2), pyuff's own 151/164 read
back; a binary 58 in millimetres and newtons (or millinewtons) read as the same file in SI to
the two roundings of the conversion; the refusals (a unit code not 1..10, factors that
contradict the code, units after the data they scale or given twice, a function whose units
are not known in a file that is not SI, units exponents that contradict the data type)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from substruct.case.channel_files import read_channels
from substruct.case.errors import CaseError
from substruct.case.frf_files import read_frf_file
from substruct.case.uff_geometry import node_positions, uff_coordinate_systems
from substruct.case.uff_records import read_uff_records
from substruct.io.uff import uff58_bytes, uff58_sets
from uff_plain import ascii58

FOOT = 0.3048                      # m, by definition
LBF = 0.45359237 * 9.80665         # N, by definition
EPS = np.finfo(float).eps
X = [10.0, 20.0]
Y = [1.0 + 1j, 2.0 - 0.5j]


def _d25(*v: float) -> str:
    return "".join(f"{x:25.16E}".replace("E", "D") for x in v)


def _header151() -> str:
    rows = ["    -1", "   151", "bracket test", "two frames on a joint", "a test lab",
            "26-Nov-26 05:53:03         0         0         0", "26-Nov-26 06:00:00",
            "some program", "26-Nov-26 06:01:02", "    -1"]
    return "\n".join(rows) + "\n"


def _units164(code=2, length=1 / FOOT, force=1 / LBF, mode=2, text="Foot (pound f)") -> str:
    rows = ["    -1", "   164", f"{code:10d}{text:<20.20}{mode:10d}",
            _d25(length, force, 1.8), _d25(459.67), "    -1"]
    return "\n".join(rows) + "\n"


def _cs2420(origin=(10.0, 0.0, 0.0)) -> str:
    rows = ["    -1", "  2420", f"{1:10d}", "part", f"{5:10d}{0:10d}{8:10d}", "cs5",
            _d25(0, 1, 0), _d25(-1, 0, 0), _d25(0, 0, 1), _d25(*origin), "    -1"]
    return "\n".join(rows) + "\n"


def _nodes2411() -> str:
    rows = ["    -1", "  2411", f"{1:10d}{5:10d}{5:10d}{8:10d}", _d25(1.0, 2.0, 3.0),
            f"{2:10d}{0:10d}{0:10d}{8:10d}", _d25(-1.0, 0.5, 4.0), "    -1"]
    return "\n".join(rows) + "\n"


def _functions(**kw) -> list[str]:
    """The square matrix of node 1 y (translation) and node 2 rx (rotation)."""
    pts = [(1, 2), (2, 4)]
    return [ascii58(X, [v * (1 + i + 2 * j) for v in Y], rsp=pts[i], ref=pts[j], **kw)
            for i in range(2) for j in range(2)]


def _file(tmp_path, *parts, name="lab.uff"):
    path = tmp_path / name
    path.write_text("".join(parts))
    return path


def test_feet_and_pounds_force_become_si(tmp_path):
    path = _file(tmp_path, _header151(), _units164(), _cs2420(), _nodes2411(), *_functions())
    omega, labels, H = read_frf_file(path)
    assert labels == ["1:y", "2:rx"]
    np.testing.assert_array_equal(omega, 2 * np.pi * np.array(X))
    raw = np.array([[np.array(Y) * (1 + i + 2 * j) for j in range(2)] for i in range(2)])
    # ft/lbf -> m/N; rad/lbf -> rad/N; ft/(ft lbf) -> 1/N; rad/(ft lbf) -> rad/(N m)
    scale = np.array([[FOOT / LBF, 1 / LBF], [1 / LBF, 1 / (LBF * FOOT)]])
    expect = raw.transpose(2, 0, 1) * scale
    assert np.abs(H - expect).max() <= 1e-14 * np.abs(expect).max()
    read = read_uff_records(path)
    where = node_positions(read, uff_coordinate_systems(read))
    # node 1: (1, 2, 3) ft in system 5 (x = +Y, y = -X, origin (10, 0, 0) ft); node 2 global
    np.testing.assert_allclose(where[1][0], np.array([8.0, 1.0, 3.0]) * FOOT, rtol=0,
                               atol=1e-15)
    np.testing.assert_allclose(where[2][0], np.array([-1.0, 0.5, 4.0]) * FOOT, rtol=0,
                               atol=1e-15)
    np.testing.assert_array_equal(where[1][1][1], [-1, 0, 0])


def test_header_kept_and_units_read_as_pyuff_writes_them(tmp_path):
    pyuff = pytest.importorskip("pyuff")
    path = tmp_path / "p.uff"
    w = pyuff.UFF(str(path))
    w.write_sets([pyuff.prepare_151(model_name="bracket", description="two frames",
                                    db_app="lab", program="writer"),
                  pyuff.prepare_164(units_code=5, units_description="mm (milli newton)",
                                    temp_mode=1, length=1000.0, force=1000.0, temp=1.0,
                                    temp_offset=273.15)], mode="add")
    with open(path, "a") as fh:
        fh.write(_cs2420() + _nodes2411() + "".join(_functions()))
    theirs = {s["type"]: s for s in pyuff.UFF(str(path)).read_sets([0, 1])}
    read = read_uff_records(path)
    assert read.header is not None and read.units is not None
    head = read.header.attributes()
    assert (head["model_name"], head["description"], head["database_program"],
            head["program"]) == ("bracket", "two frames", "lab", "writer")
    assert head["file_written"] == " ".join(
        [theirs[151]["date_file_written"], theirs[151]["time_file_written"]])
    u = read.units
    assert (u.code, u.temperature_mode, u.length, u.force, u.temperature,
            u.temperature_offset) == (theirs[164]["units_code"], theirs[164]["temp_mode"],
                                      theirs[164]["length"], theirs[164]["force"],
                                      theirs[164]["temp"], theirs[164]["temp_offset"])
    omega, labels, H = read_frf_file(path)
    raw = read_frf_file(_file(tmp_path, _cs2420(), _nodes2411(), *_functions()))[2]
    # mm/mN -> m/N (x 1); rad/mN -> rad/N (x 1e3); mm/(mN mm) = 1/mN (x 1e3); rad/(mN mm)
    # -> rad/(N m) (x 1e6)
    np.testing.assert_allclose(H / raw, np.broadcast_to([[1.0, 1e3], [1e3, 1e6]], H.shape),
                               rtol=1e-15)


def test_exponents_that_agree_with_the_data_type_are_read(tmp_path):
    """Records 8-10 fields 2-4 written as 58 Addendum A gives them (a Test.Lab habit)."""
    base = _functions()
    given = [f.replace(f"{8:10d}{0:5d}{0:5d}{0:5d}", f"{8:10d}{1:5d}{0:5d}{0:5d}")
             .replace(f"{13:10d}{0:5d}{0:5d}{0:5d}", f"{13:10d}{0:5d}{1:5d}{0:5d}")
             for f in base[:1]] + base[1:]
    a = read_frf_file(_file(tmp_path, _units164(), _cs2420(), _nodes2411(), *base, name="a.uff"))[2]
    b = read_frf_file(_file(tmp_path, _units164(), _cs2420(), _nodes2411(), *given, name="b.uff"))[2]
    np.testing.assert_array_equal(a, b)


def test_testlab_blank_temperature_mode_is_not_given():
    """LMS Test.Lab leaves dataset 164 record 1 field 3 (temperature mode) blank: read as not
    given (substruct uses no temperature); the rest of the file as pyuff reads it."""
    path = Path(__file__).parent / "data" / "uff" / "testlab_161_164_18_15_82.uff"
    read = read_uff_records(path)
    u = read.units
    assert u is not None and u.temperature_mode is None
    assert (u.code, u.description, u.length, u.force, u.temperature,
            u.temperature_offset) == (9, "USER_DEFINED", 1.0, 1.0, 1.0, -273.15)
    assert len(read.node_table) == 36
    # pyuff 2.5.8's dataset 15 of the file: nodes 1-3
    for label, xyz in ((1, (-2.4, -0.95, 0.0)), (2, (-2.6, 2.05, 0.0)), (3, (2.6, 2.05, 0.0))):
        assert read.node_table[label].xyz == xyz and read.node_table[label].def_cs == 0


@pytest.mark.parametrize("mode, message", [
    ("         x", "record 1 field 3, temperature mode 'x': not an integer"),
    ("       1.5", "record 1 field 3, temperature mode '1.5': not an integer"),
])
def test_temperature_mode_text_refused(tmp_path, mode, message):
    units = _units164().replace(f"{'Foot (pound f)':<20}{2:10d}", f"{'Foot (pound f)':<20}{mode}")
    assert units != _units164()
    with pytest.raises(ValueError, match=re.escape(message)):
        read_uff_records(_file(tmp_path, units, _nodes2411(), *_functions()))
    blank = _units164().replace(f"{'Foot (pound f)':<20}{2:10d}", f"{'Foot (pound f)':<20}")
    assert read_uff_records(_file(tmp_path, blank, _nodes2411(), *_functions(),
                                  name="b.uff")).units.temperature_mode is None


@pytest.mark.parametrize("parts, message", [
    ((_units164(code=11), _nodes2411()), "record 1 field 1, units code 11: not one of 1..10"),
    ((_units164(code=1), _nodes2411()), "record 2 field 1, length factor 3.280839895 is not "
     "that of units code 1 (SI: meter (newton): 1)"),
    ((_units164(length=0.0), _nodes2411()), "length factor"),
    ((_units164(mode=3), _nodes2411()), "record 1 field 3, temperature mode 3"),
    ((_nodes2411(), _units164()), "units after dataset 1 (2411, line 1), whose numbers they "
     "would scale"),
    ((_units164(), _units164(), _nodes2411()), "units given twice (first in dataset 1"),
    ((_header151(), _header151()), "a second header (151; first in dataset 1"),
])
def test_refused_in_one_line(tmp_path, parts, message):
    with pytest.raises(ValueError) as err:
        read_uff_records(_file(tmp_path, *parts, *_functions()))
    text = str(err.value)
    assert text.startswith("lab.uff: dataset ") and message in text and "\n" not in text, text


def test_units_after_a_function_refused_by_the_channel_reader(tmp_path):
    f = _functions()
    with pytest.raises(CaseError) as err:
        read_channels(_file(tmp_path, _nodes2411(), f[0], _units164(), *f[1:]))
    assert "units after dataset 1 (2411" in str(err.value)


def test_exponents_that_contradict_the_data_type_refused(tmp_path):
    f = _functions()
    bad = f[0].replace(f"{8:10d}{0:5d}{0:5d}{0:5d}", f"{8:10d}{2:5d}{0:5d}{0:5d}")
    with pytest.raises(ValueError) as err:
        read_frf_file(_file(tmp_path, _cs2420(), _nodes2411(), bad, *f[1:]))
    assert ("record 9 fields 2-4, units exponents (length, force, temperature) [2, 0, 0]: "
            "data type 8 at direction 2 has [1, 0, 0]") in str(err.value)


def _plain(v) -> str:
    return "".join(f"{float(x):25.16E}" for x in v) + "\n"


def _units_file(path, code: int, factors: tuple[float, float], scale_l: float,
                scale_y: float, numerator: int = 8) -> None:
    """One node with its own system, one binary function from it to itself, in the units
    given: positions times ``scale_l``, the ordinate times ``scale_y``."""
    pos = np.array([0.0125, -0.25, 0.5])
    A = np.array([[0.6, 0.8, 0.0], [-0.8, 0.6, 0.0], [0.0, 0.0, 1.0]])
    w = np.array([10.0, 20.0, 30.0])
    H = np.array([1e-6 + 2e-7j, -3e-7 + 1e-8j, 5e-8 - 2e-9j])[:, None, None]
    text = (f"    -1\n   164\n{code:10d}{'units':<20}{2:10d}\n"
            f"{factors[0]:25.17E}{factors[1]:25.17E}{1.0:25.17E}\n{273.15:25.17E}\n    -1\n"
            f"    -1\n  2420\n{1:10d}\npart\n{7:10d}{0:10d}{8:10d}\nsys\n"
            + "".join(_plain(r) for r in A) + _plain(np.array([0.001, 0.0, 0.0]) * scale_l)
            + "    -1\n"
            f"    -1\n  2411\n{5:10d}{0:10d}{7:10d}{8:10d}\n" + _plain(pos * scale_l)
            + "    -1\n")
    s = uff58_sets(w, H * scale_y, ["5:x"], ["5:x"], nodes={"5:x": (5, 1)})[0]
    s["ordinate_spec_data_type"] = numerator
    path.write_bytes(text.encode() + uff58_bytes(s))


def test_millimetres_read_as_si_records(tmp_path):
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


@pytest.mark.parametrize("code, factors, numerator, words", [
    (5, (1.0, 1000.0), 8, "dataset 1 (164, line 1): record 2 field 1, length factor 1 is not "
     "that of units code 5 (MM: mm (milli newton): 1000)"),
    (10, (1000.0, 1.0), 0, "dataset 4 (58, line 23): records 9-10 field 1, ordinate data type "
     "0 over 13: its units are not known, so it cannot be converted from units code 10 "
     "(dataset 1 (164, line 1)) to SI"),
])
def test_units_that_cannot_be_honoured_are_refused(tmp_path, code, factors, numerator,
                                                   words):
    path = tmp_path / "bad.uff"
    _units_file(path, code, factors, 1.0, 1.0, numerator)
    with pytest.raises(ValueError) as err:
        read_uff_records(path)
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith("bad.uff: dataset ") and words in msg, msg


def test_drawing_datasets_are_passed_over_and_others_refused(tmp_path):
    """Trace lines (82) and elements (2412) draw the geometry only: a file with them reads the
    same nodes and functions as the file without; a dataset that could qualify the functions
    (1858: weighting, window) is refused naming it."""
    trace = "\n".join(["    -1", "    82", f"{1:10d}{2:10d}{0:10d}", "wire", f"{1:10d}{2:10d}",
                       "    -1"]) + "\n"
    elements = "\n".join(["    -1", "  2412", f"{1:10d}{21:10d}{1:10d}{1:10d}{7:10d}{2:10d}",
                          f"{0:10d}{1:10d}{1:10d}", f"{1:10d}{2:10d}", "    -1"]) + "\n"
    plain = _file(tmp_path, _units164(), _cs2420(), _nodes2411(), *_functions(), name="a.uff")
    drawn = _file(tmp_path, _units164(), _cs2420(), _nodes2411(), trace, elements,
                  *_functions(), name="b.uff")
    (w1, l1, H1), (w2, l2, H2) = read_frf_file(plain), read_frf_file(drawn)
    assert l1 == l2
    np.testing.assert_array_equal(w1, w2)
    np.testing.assert_array_equal(H1, H2)
    qualifiers = "\n".join(["    -1", "  1858", f"{1:12d}{0:12d}{0:12d}", "    -1"]) + "\n"
    with pytest.raises(ValueError, match=r"dataset 1858 is not read"):
        read_uff_records(_file(tmp_path, _units164(), qualifiers, *_functions(), name="c.uff"))
