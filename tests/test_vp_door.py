"""The case-file door to virtual points (``virtual_points:`` on ``type: frf``): the shipped
example through the command line against the frame computed as one piece, the options passed
to the library as given, and the refusals."""

from __future__ import annotations

import sys
from pathlib import Path

import h5py
import numpy as np
import pytest
import scipy.sparse as sp

from substruct import cli
from substruct.analysis.frf.virtual_point import VirtualPoint, virtual_point_transform
from substruct.analysis.frf.vp_coupling import Regularisation, couple_virtual_points, vp_part
from substruct.analysis.frf.vp_reduction import InterfaceReduction
from substruct.case.channel_files import read_channels
from substruct.case.channels import parse_channels
from substruct.io.result_reader import load

sys.path.insert(0, str(Path(__file__).resolve().parent))
from testlab_models import assembly, channel_matrix, node_dofs, node_rows, receptance  # noqa

ROOT = Path(__file__).resolve().parent.parent
CASE = ROOT / "cases" / "vpt_coupling.yaml"
DATA = ROOT / "cases" / "vpt_coupling"
#: the coupled receptance vs the one-frame assembly: the FE receptances themselves agree
#: between two formulations to 3.5e-10 (docs/testlab.md), coupling measured 1.9e-10
EXACT = 1e-8
VP = ("ux", "uy", "uz", "rx", "ry", "rz")


def _run(path: Path, out: Path) -> int:
    return cli.main(["run", str(path), "--out", str(out), "--quiet", "--no-pictures"])


def _case(tmp_path: Path, old: str = "", new: str = "") -> Path:
    text = CASE.read_text().replace("vpt_coupling/", f"{DATA}/")
    if old:
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / "case.yaml"
    path.write_text(text)
    return path


def _rel(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.abs(a - b).max() / np.abs(b).max())


def test_shipped_example_recovers_the_one_frame_assembly(tmp_path):
    assert _run(CASE, tmp_path / "out") == 0
    res = load(tmp_path / "out" / "vpt_coupling.h5")
    AB = assembly()
    a4x = parse_channels([node_rows("A4x", AB, 4, (1, 0, 0), "sensor")], "AB")
    b14x = parse_channels([node_rows("B14x", AB, 14, (1, 0, 0), "impact")], "AB")
    S = sp.vstack([node_dofs(AB, 1), channel_matrix(AB, a4x, ["A4x"], {})])
    F = sp.vstack([node_dofs(AB, 1), channel_matrix(AB, b14x, ["B14x"], {})])
    ref = receptance(AB, S, F, res.frf.omega)
    assert _rel(res.frf.H, ref) < EXACT
    assert res.frf.agreement["generalized-inverse"] < 1e-10
    with h5py.File(tmp_path / "out" / "vpt_coupling.h5") as f:
        g = f["virtual_points"]
        assert [g[k].attrs["part"] for k in g] == ["A", "B"]
        for k in g:  # a rigid adapter, a right table: every indicator is 1
            for name in ("overall_u", "overall_f", "specific_u", "specific_f"):
                assert np.abs(g[k][name][()] - 1).max() < 1e-8
            assert g[k]["specific_u"].shape == (9, 40)


def _library_parts():
    parts = []
    for name in ("A", "B"):
        table = read_channels(DATA / f"{name.lower()}_channels.csv")
        with np.load(DATA / f"{name.lower()}.npz") as z:
            labels, H, w = list(z["labels"]), z["H"], z["omega"]
        sensors = [c.name for c in table.of_kind("sensor")]
        impacts = [c.name for c in table.of_kind("impact")]
        vp = VirtualPoint("J", (0.0, 0.0, 0.0), tuple(s for s in sensors if s.startswith("S")),
                          tuple(h for h in impacts if h.startswith("H")))
        vpt = virtual_point_transform(table, [vp], sensors, impacts)
        Y = H[:, [labels.index(s) for s in sensors]][:, :, [labels.index(h) for h in impacts]]
        parts.append(vp_part(name, w, vpt, Y))
    return parts


LIB_PAIRS = [(f"A@J:{c}", f"B@J:{c}") for c in ("x", "y", "z", "rx", "ry", "rz")]
LIB_J = [f"A@J:{c}" for c in ("x", "y", "z", "rx", "ry", "rz")]


@pytest.mark.parametrize("block, reg, weaken", [
    ("    virtual_points:\n      weaken: [rx, ry, rz]\n", Regularisation(), ("rx", "ry", "rz")),
    ("    virtual_points:\n      regularization: {method: tikhonov, alpha: 1.0e-2, "
     "length: 0.025}\n", Regularisation("tikhonov", alpha=1e-2), ()),
    ("    virtual_points:\n      regularization: {method: tsvd, rtol: 1.0e-3, "
     "length: 0.025}\n", Regularisation("tsvd", rtol=1e-3), ())])
def test_weakening_and_regularization_reach_the_coupling(tmp_path, block, reg, weaken):
    """The door's result is the library's with the same options (and differs from the
    plain coupling by more than round-off, so the options are not lost)."""
    path = _case(tmp_path, "    virtual_points:\n", block)  # on both parts
    assert _run(path, tmp_path / "out") == 0
    H = load(tmp_path / "out" / "vpt_coupling.h5").frf.H[:, :6, :6]
    parts = _library_parts()
    lib = couple_virtual_points(parts, LIB_PAIRS, reg, weaken, weaken, length=0.025)
    ref = lib.part.block(LIB_J, LIB_J)
    plain = couple_virtual_points(parts, LIB_PAIRS).part.block(LIB_J, LIB_J)
    assert _rel(H, ref) < 1e-12
    assert _rel(plain, ref) > 1e-6


@pytest.mark.parametrize("setting, reduction", [
    ("keep: 6", InterfaceReduction(keep=6)), ("keep: 4", InterfaceReduction(keep=4)),
    ("tolerance: 0.2", InterfaceReduction(tolerance=0.2))])
def test_interface_reduction_reaches_the_coupling(tmp_path, setting, reduction):
    """``interface: {reduction: svd, ...}`` on both parts: the library's coupling with the
    same reduction; six of six kept is the plain coupling to round-off (the interface
    receptance's condition number is below 1e4 here), fewer differ from it."""
    block = f"    virtual_points:\n      interface: {{reduction: svd, {setting}, length: 0.025}}\n"
    path = _case(tmp_path, "    virtual_points:\n", block)
    assert _run(path, tmp_path / "out") == 0
    res = load(tmp_path / "out" / "vpt_coupling.h5")
    assert "svd-reduced" in res.frf.method
    H = res.frf.H[:, :6, :6]
    parts = _library_parts()
    lib = couple_virtual_points(parts, LIB_PAIRS, length=0.025, reduction=reduction)
    assert np.array_equal(H, lib.part.block(LIB_J, LIB_J))
    plain = couple_virtual_points(parts, LIB_PAIRS).part.block(LIB_J, LIB_J)
    if reduction.keep == 6:
        assert _rel(H, plain) < 1e-11
    else:
        assert _rel(H, plain) > 1e-3


@pytest.mark.parametrize("old, new, field", [
    ("[A@vp:J:rz, B@vp:J:rz]", "[A@ch:A4x, B@vp:J:rz]", "connections[5][0]"),
    ("B@ch:B14x]", "A@ch:A4x]", "analysis.frf.inputs[6]"),     # a sensor as an input
    ("A@ch:A4x]", "B@ch:B14x]", "analysis.frf.outputs[6]"),    # an impact as an output
    ("          impacts: [H1, H2, H3, H4, H5, H6, H7, H8, H9]\n  - name: B",
     "          impacts: [H1, H2, H3, H4, H5, H6, H7, H8, H9]\n"
     "      regularization: {method: tsvd, alpha: 0.1, length: 0.025}\n  - name: B",
     "substructures.A.virtual_points.regularization.alpha"),
    ("          impacts: [H1, H2, H3, H4, H5, H6, H7, H8, H9]\n  - name: B",
     "          impacts: [H1, H2, H3, H4, H5, H6, H7, H8, H9]\n"
     "      interface: {reduction: svd, keep: 7, length: 0.025}\n  - name: B",
     "substructures.A.virtual_points.interface.keep"),
    ("          impacts: [H1, H2, H3, H4, H5, H6, H7, H8, H9]\n  - name: B",
     "          impacts: [H1, H2, H3, H4, H5, H6, H7, H8, H9]\n"
     "      interface: {reduction: svd, keep: 4, tolerance: 0.1, length: 0.025}\n  - name: B",
     "substructures.A.virtual_points.interface.reduction"),
    ("          impacts: [H1, H2, H3, H4, H5, H6, H7, H8, H9]\n  - name: B",
     "          impacts: [H1, H2, H3, H4, H5, H6, H7, H8, H9]\n"
     "      interface: {reduction: svd, keep: 4, length: 0.05}\n"
     "      regularization: {method: tsvd, rtol: 0.001, length: 0.025}\n  - name: B",
     "substructures.A.virtual_points.interface.length")])
def test_refused_in_one_line(tmp_path, capsys, old, new, field):
    path = _case(tmp_path, old, new)
    assert _run(path, tmp_path / "out") == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and f": {field}: " in err, err
    assert not (tmp_path / "out" / "vpt_coupling.h5").exists()
