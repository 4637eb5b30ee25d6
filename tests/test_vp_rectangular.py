"""A virtual-points part measured as sensors x impacts only (substruct.case.frf_files.
read_measured_file): an ``.npz`` with ``outputs`` and ``inputs`` cut from the shipped square
file gives the shipped case's coupled receptance and consistency indicators exactly (the same
numbers enter the same transformation); a Universal File of 58 functions with its nodes (2411)
and coordinate systems (2420), named as both the receptances and the channel table, gives the
result of the CSV table and the ``.npz``; the refusals (a sensor x impact function missing, a
sensor that is not an output)."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

from substruct import cli
from substruct.analysis.frf.virtual_point import VirtualPoint, virtual_point_transform
from substruct.case.channel_files import read_channels
from substruct.io.result_reader import load
from substruct.io.uff import uff58_sets, write_uff
from substruct.io.uff_channels import ChannelNodes, channel_frame, geometry_sets

ROOT = Path(__file__).resolve().parent.parent
CASE = ROOT / "cases" / "vpt_coupling.yaml"
DATA = ROOT / "cases" / "vpt_coupling"
sys.path.insert(0, str(Path(__file__).resolve().parent))


def _run(path: Path, out: Path) -> int:
    return cli.main(["run", str(path), "--out", str(out), "--quiet", "--no-pictures"])


def _result(path: Path, out: Path):
    assert _run(path, out) == 0
    res = load(out / f"{path.stem}.h5")
    with h5py.File(out / f"{path.stem}.h5") as f:
        ind = {f"{k}/{n}": f["virtual_points"][k][n][()] for k in f["virtual_points"]
               for n in ("overall_u", "overall_f", "specific_u", "specific_f")}
    return res, ind


def _square(tmp_path: Path):
    text = CASE.read_text().replace("vpt_coupling/", f"{DATA}/")
    path = tmp_path / "square.yaml"
    path.write_text(text.replace("name: vpt_coupling", "name: square"))
    return _result(path, tmp_path / "sq")


def _cut(part: str, where: Path) -> tuple[list[str], list[str], np.ndarray, np.ndarray]:
    table = read_channels(DATA / f"{part}_channels.csv")
    sensors = [c.name for c in table.of_kind("sensor")]
    impacts = [c.name for c in table.of_kind("impact")]
    with np.load(DATA / f"{part}.npz") as z:
        labels, H, w = list(z["labels"]), z["H"], z["omega"]
    rows = [labels.index(s) for s in sensors]
    cols = [labels.index(h) for h in impacts]
    Y = H[:, rows][:, :, cols]
    np.savez(where, H=Y, outputs=np.array(sensors), inputs=np.array(impacts), omega=w)
    return sensors, impacts, Y, w


def test_rectangular_npz_equals_the_square_file(tmp_path):
    ref, ref_ind = _square(tmp_path)
    text = CASE.read_text().replace("vpt_coupling/", f"{DATA}/")
    for part in ("a", "b"):
        _cut(part, tmp_path / f"{part}_rect.npz")
        text = text.replace(f"{DATA}/{part}.npz", str(tmp_path / f"{part}_rect.npz"))
    path = tmp_path / "rect.yaml"
    path.write_text(text.replace("name: vpt_coupling", "name: rect"))
    res, ind = _result(path, tmp_path / "rect")
    np.testing.assert_array_equal(res.frf.H, ref.frf.H)
    np.testing.assert_array_equal(res.frf.omega, ref.frf.omega)
    assert ind.keys() == ref_ind.keys()
    for k in ind:
        np.testing.assert_array_equal(ind[k], ref_ind[k])


def _uff_part(part: str, where: Path) -> dict[str, str]:
    """The part as one Universal File: a node per channel at its position whose displacement
    system (2420) has the channel's direction as +x, and a 58b per sensor x impact; returns
    the channel names of the CSV table -> ``<node>.x``."""
    table = read_channels(DATA / f"{part}_channels.csv")
    sensors, impacts, Y, w = _cut(part, where.with_suffix(".npz"))
    nodes = ChannelNodes()
    names: dict[str, str] = {}
    for k, c in enumerate(table.channels, start=1):
        pos = np.array(c.position)
        nodes.xyz[k], nodes.disp_cs[k] = pos, k
        nodes.systems[k] = (channel_frame(c.direction), pos)
        nodes.where[c.name] = (k, 1)
        names[c.name] = f"{k}.x"
    sets = geometry_sets(nodes, f"part {part}") + uff58_sets(w, Y, sensors, impacts,
                                                           nodes=nodes.where)
    write_uff(where, sets)
    return names


def _renamed(text: str, names: dict[str, str], part: str) -> str:
    """The part's block and its points of the case with the channels renamed."""
    head, _, rest = text.partition(f"  - name: {part.upper()}\n")
    block, sep, tail = rest.partition("\n  - name: ") if part == "a" else \
        rest.partition("\nconnections:")
    block = re.sub(r"(?<=[\[ ])([A-Za-z0-9_]+)(?=[,\]])",
                   lambda m: names.get(m.group(1), m.group(1)), block)
    if part == "a":
        tail = tail.replace("A@ch:A4x", f"A@ch:{names['A4x']}")
    else:
        tail = tail.replace("B@ch:B14x", f"B@ch:{names['B14x']}")
    return head + f"  - name: {part.upper()}\n" + block + sep + tail


def _kappa() -> float:
    """The largest condition number over the band of the interface receptance
    ``Y_A,JJ + Y_B,JJ`` at the virtual point, rotations scaled by the adapter's 25 mm."""
    Z = 0
    for part in ("a", "b"):
        table = read_channels(DATA / f"{part}_channels.csv")
        with np.load(DATA / f"{part}.npz") as z:
            labels, H = list(z["labels"]), z["H"]
        sensors = [c.name for c in table.of_kind("sensor") if c.name.startswith("S")]
        impacts = [c.name for c in table.of_kind("impact") if c.name.startswith("H")]
        vpt = virtual_point_transform(table, [VirtualPoint("J", (0.0, 0.0, 0.0),
                                                           tuple(sensors), tuple(impacts))],
                                      sensors, impacts)
        Y = H[:, [labels.index(x) for x in sensors]][:, :, [labels.index(x) for x in impacts]]
        Z = Z + vpt.apply(Y)
    s = np.array([1, 1, 1, 0.025, 0.025, 0.025])
    return float(np.linalg.cond(s[None, :, None] * Z * s[None, None, :]).max())


def test_uff_as_receptances_and_channel_table(tmp_path):
    ref, ref_ind = _square(tmp_path)
    text = CASE.read_text().replace("vpt_coupling/", f"{DATA}/")
    for part in ("a", "b"):
        uff = tmp_path / f"{part}.uff"
        names = _uff_part(part, uff)
        text = text.replace(f"{DATA}/{part}.npz", str(uff)).replace(
            f"{DATA}/{part}_channels.csv", str(uff))
        text = _renamed(text, names, part)
        # the table read from the file is the CSV table, renamed: positions and directions
        # travel as the doubles themselves (17 digits), the directions normalised once more
        csv, got = read_channels(DATA / f"{part}_channels.csv"), read_channels(uff)
        assert sorted(c.name for c in got.channels) == sorted(names.values())
        for c in csv.channels:
            g = got.get(names[c.name])
            assert g.kind == c.kind and g.position == c.position
            assert np.abs(np.subtract(g.direction, c.direction)).max() <= 2 * np.finfo(float).eps
    path = tmp_path / "uff.yaml"
    path.write_text(text.replace("name: vpt_coupling", "name: uff"))
    res, ind = _result(path, tmp_path / "uff")
    # the receptances travel in binary doubles, the frequencies as Hz (omega / 2 pi, within
    # the grid's tolerance, the analysis grid used); the directions to an ulp (a unit vector
    # normalised again): the coupled result to the round-off of the interface inversion,
    # 100 eps times the largest condition number of the (scaled) interface receptance, as
    # for any two couplings of the same data (the square and the cut run agree bit for bit)
    scale = np.abs(ref.frf.H).max()
    bound = 100 * np.finfo(float).eps * _kappa()
    assert np.abs(res.frf.H - ref.frf.H).max() <= bound * scale
    for k in ind:
        assert np.abs(ind[k] - ref_ind[k]).max() <= 100 * np.finfo(float).eps


@pytest.mark.parametrize("edit, message", [
    ("drop", "lacks the function of response 1:x to reference 10:x: the virtual points need "
     "every sensor x impact"),
    ("sensor", "sensor 'S1x' is not among the outputs of a_rect.npz"),
])
def test_refused_in_one_line(tmp_path, capsys, edit, message):
    text = CASE.read_text().replace("vpt_coupling/", f"{DATA}/")
    if edit == "drop":
        uff = tmp_path / "a.uff"
        names = _uff_part("a", uff)
        raw = uff.read_bytes()
        start = raw.index(b"    -1\n    58b")       # the first function: 1.x per 10.x
        end = raw.index(b"    -1\n    58b", start + 10)
        uff.write_bytes(raw[:start] + raw[end:])
        text = _renamed(text.replace(f"{DATA}/a.npz", str(uff)).replace(
            f"{DATA}/a_channels.csv", str(uff)), names, "a")
    else:
        sensors, impacts, Y, w = _cut("a", tmp_path / "a_rect.npz")
        np.savez(tmp_path / "a_rect.npz", H=Y[:, 1:], outputs=np.array(sensors[1:]),
                 inputs=np.array(impacts), omega=w)
        text = text.replace(f"{DATA}/a.npz", str(tmp_path / "a_rect.npz"))
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    assert _run(path, tmp_path / "out") == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "\n" not in err, err
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())
