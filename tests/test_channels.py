"""Channel tables (substruct/case/channels.py): CSV and YAML read and written back exactly,
and every bad row refused in one line naming the row and the column."""

from __future__ import annotations

import numpy as np
import pytest

from substruct.case.channel_files import read_channels
from substruct.case.channels import write_channels
from substruct.case.errors import CaseError

GOOD = """name,node,x,y,z,dx,dy,dz,kind
S1x,101,0.03,0.02,0.0,1,0,0,sensor
S1y,101,0.03,0.02,0.0,0,2,0,sensor
H1,201,0.04,-0.03,0.01,0,0,-3,impact
"""


def _write(tmp_path, text, name="ch.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_csv_and_yaml_read_normalised_and_written_back(tmp_path):
    t = read_channels(_write(tmp_path, GOOD))
    assert [c.name for c in t.of_kind("sensor")] == ["S1x", "S1y"]
    assert t.get("S1y").direction == (0.0, 1.0, 0.0)
    assert t.get("H1").direction == (0.0, 0.0, -1.0)
    assert t.get("H1").node == "201"
    d = t.directions(["S1x", "H1"])
    assert np.array_equal(d, [[1, 0, 0], [0, 0, -1]])
    odd = GOOD.replace("1,0,0,sensor", "0.3,0.7,-0.1,sensor")
    t2 = read_channels(_write(tmp_path, odd))
    assert abs(np.linalg.norm(t2.get("S1x").direction) - 1) < 4e-16
    write_channels(t2, tmp_path / "back.csv")
    back = read_channels(tmp_path / "back.csv")
    for a, b in zip(back.channels, t2.channels):  # a unit vector normalised again: 1 ulp
        assert (a.name, a.node, a.position, a.kind) == (b.name, b.node, b.position, b.kind)
        assert np.abs(np.subtract(a.direction, b.direction)).max() <= 2.3e-16
    yml = _write(tmp_path, "channels:\n  - {name: S1x, node: 101, x: 0.03, y: 0.02, z: 0, "
                 "dx: 1, dy: 0, dz: 0, kind: sensor}\n", "ch.yaml")
    assert read_channels(yml).get("S1x").position == (0.03, 0.02, 0.0)


@pytest.mark.parametrize("text, message", [
    (GOOD.replace(",kind\n", "\n").replace(",sensor\n", "\n").replace(",impact\n", "\n"),
     "ch.csv: line 2.kind: missing"),
    (GOOD.replace("S1y,", "S1x,"), "ch.csv: line 3.name: repeated (first at line 2), got 'S1x'"),
    (GOOD.replace("0,0,-3,impact", "0,0,0,impact"),
     "ch.csv: line 4.dx: the direction (dx, dy, dz) has zero length, got [0.0, 0.0, 0.0]"),
    (GOOD.replace("0.04,-0.03", "abc,-0.03"), "ch.csv: line 4.x: not a number, got 'abc'"),
    (GOOD.replace("0.04,-0.03", ",-0.03"), "ch.csv: line 4.x: a number is needed, got ''"),
    (GOOD.replace("0.04,-0.03", "nan,-0.03"), "ch.csv: line 4.x: not a finite number"),
    (GOOD.replace(",impact", ",hammer"), "ch.csv: line 4.kind: one of sensor, impact, "
     "got 'hammer'"),
    (GOOD.replace("S1y,101,0.03,0.02,0.0,0,2,0", "S1y,101,0.03,0.02,0.0,2,0,0"),
     "ch.csv: line 3: sensor 'S1y' is at the place and in the direction of 'S1x' (line 2): "
     "a duplicate"),
    (GOOD.replace("dz,kind", "dz,kind,gain").replace("sensor\n", "sensor,1\n")
     .replace("impact\n", "impact,1\n"), "ch.csv: line 1: unknown column"),
    (GOOD.replace("S1x,", "S 1x,"), "ch.csv: line 2.name: a name of at most"),
    (GOOD.replace("0.03,0.02,0.0,1,0,0,sensor", "0.03,0.02,0.0,1,0,0"),
     "ch.csv: line 2: 9 values expected, got 8"),
    # a field beyond the csv module's limit of 131072 characters
    (GOOD.replace("S1x,101,", "S1x,101" + " " * 200_000 + ",", 1),
     "ch.csv: line 2: not a CSV row (field larger than field limit"),
])
def test_bad_rows_are_refused_in_one_line(tmp_path, text, message):
    with pytest.raises(CaseError) as err:
        read_channels(_write(tmp_path, text))
    assert str(err.value).startswith(message), str(err.value)
    assert "\n" not in str(err.value)


def test_bad_files(tmp_path):
    with pytest.raises(CaseError, match="ch.txt: a channel file is .csv, .yaml, .yml, .uff or .unv"):
        read_channels(_write(tmp_path, GOOD, "ch.txt"))
    with pytest.raises(CaseError, match="ch.yaml: a YAML channel file is a mapping with one "
                       "key, channels"):
        read_channels(_write(tmp_path, "sensors: []\n", "ch.yaml"))
    with pytest.raises(CaseError, match=r"ch.yaml: channels.0.gain: unknown column"):
        read_channels(_write(tmp_path, "channels: [{name: a, gain: 2}]\n", "ch.yaml"))
    with pytest.raises(CaseError, match="nope.csv: cannot read the channel file"):
        read_channels(tmp_path / "nope.csv")
