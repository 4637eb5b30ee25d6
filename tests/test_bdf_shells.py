"""Nastran shells (CQUAD4, CTRIA3, PSHELL), bushings (CBUSH, PBUSH), EIGRL by frequency
range and INCLUDE: against the frame API's shells, closed forms and rigid-body invariance."""

from __future__ import annotations

import os

import numpy as np
import pytest

from substruct import cli
from substruct.case.bdf import parse_bulk, read_bulk
from substruct.case.bdf_fields import BdfError
from substruct.io.result_reader import load
from substruct.models.beam import Material
from substruct.models.frame import frame
from substruct.models.nastran import nastran_matrices, nastran_substructure
from substruct.models.shell_mesh import Shell

E, NU, RHO, T = 2.1e11, 0.3, 7850.0, 0.01
MAT = Material(E=E, G=E / (2 * (1 + NU)), rho=RHO)


def plate_bdf(n: int, kind: str = "CQUAD4", eigrl: str = "EIGRL,1,,,4", extra=()) -> str:
    """A 1 m square cantilever plate (x = 0 clamped), n x n elements, coupled mass."""
    lines = ["SOL 103", "CEND", "METHOD = 1", "SPC = 1", "BEGIN BULK", eigrl,
             "PARAM,COUPMASS,1", f"MAT1,1,2.1+11,,.3,{RHO}", f"PSHELL,1,1,{T},1"]
    nid = lambda i, j: 1 + i * (n + 1) + j  # noqa: E731
    for i in range(n + 1):
        for j in range(n + 1):
            lines.append(f"GRID,{nid(i, j)},,{i / n:.8f},{j / n:.8f},0.")
    eid = 1
    for i in range(n):
        for j in range(n):
            q = (nid(i, j), nid(i + 1, j), nid(i + 1, j + 1), nid(i, j + 1))
            if kind == "CQUAD4":
                lines.append(f"CQUAD4,{eid},1,{q[0]},{q[1]},{q[2]},{q[3]}")
                eid += 1
            else:
                lines += [f"CTRIA3,{eid},1,{q[0]},{q[1]},{q[2]}",
                          f"CTRIA3,{eid + 1},1,{q[0]},{q[2]},{q[3]}"]
                eid += 2
    lines.append(f"SPC1,1,123456,1,THRU,{n + 1}")
    return "\n".join(lines + list(extra) + ["ENDDATA", ""])


def api_plate(n: int, kind: str = "quad"):
    nodes = {1 + i * (n + 1) + j: (i / n, j / n, 0.0) for i in range(n + 1)
             for j in range(n + 1)}
    shells = []
    for i in range(n):
        for j in range(n):
            q = (1 + i * (n + 1) + j, 1 + (i + 1) * (n + 1) + j, 2 + (i + 1) * (n + 1) + j,
                 2 + i * (n + 1) + j)
            shells += [Shell(q, T, MAT)] if kind == "quad" else \
                [Shell((q[0], q[1], q[2]), T, MAT), Shell((q[0], q[2], q[3]), T, MAT)]
    return frame("api", nodes, [], supports={k: None for k in range(1, n + 2)}, shells=shells)


@pytest.mark.parametrize("kind, api", [("CQUAD4", "quad"), ("CTRIA3", "tri")])
def test_bdf_shells_are_the_frame_shells(kind, api):
    """CQUAD4/CTRIA3 + PSHELL (COUPMASS) give the frame API's K and M to round-off."""
    mats = nastran_matrices(parse_bulk(plate_bdf(4, kind), "p.bdf"))
    sub = nastran_substructure("p", mats, autospc=False)
    ref = api_plate(4, api)
    assert sub.dof_labels == tuple(lab.replace("ux", "1").replace("uy", "2")
                                   .replace("uz", "3").replace("rx", "4").replace("ry", "5")
                                   .replace("rz", "6") for lab in ref.dof_labels)
    assert abs(sub.K - ref.K).max() <= 1e-12 * abs(ref.K).max()
    assert abs(sub.M - ref.M).max() <= 1e-12 * abs(ref.M).max()


@pytest.mark.parametrize("kind, api", [("CQUAD4", "quad"), ("CTRIA3", "tri")])
def test_pshell_with_mid3_is_the_mindlin_frame_shell_and_ts_scales_its_shear(kind, api):
    """MID3 given (TS/T blank: 5/6): the frame API's ``bending="mindlin"`` shells (MITC4 /
    MITC3, shear 5/6 G T) to round-off; MID3 blank: Kirchhoff's, a different K; TS/T = 0.5
    is an element whose shear stiffness is 0.5 T G (the element function with that shear)."""
    from substruct.models.shell import ShellTerms, shell_matrices

    mid3 = plate_bdf(4, kind).replace(f"PSHELL,1,1,{T},1", f"PSHELL,1,1,{T},1,,1")
    mats = nastran_matrices(parse_bulk(mid3, "p.bdf"))
    sub = nastran_substructure("p", mats, autospc=False)
    nodes = {1 + i * 5 + j: (i / 4, j / 4, 0.0) for i in range(5) for j in range(5)}
    ref = frame("api", nodes, [], supports={k: None for k in range(1, 6)},
                shells=[Shell(s.nodes, T, MAT, bending="mindlin")
                        for s in _api_shells(4, api)])
    assert abs(sub.K - ref.K).max() <= 1e-12 * abs(ref.K).max()
    assert abs(sub.M - ref.M).max() <= 1e-12 * abs(ref.M).max()
    kirchhoff = nastran_matrices(parse_bulk(plate_bdf(4, kind), "p.bdf")).K
    assert abs(kirchhoff - mats.K).max() > 1e-3 * abs(ref.K).max()
    one = plate_bdf(1, kind).replace(f"PSHELL,1,1,{T},1", f"PSHELL,1,1,{T},1,,1,.5")
    got = nastran_matrices(parse_bulk(one, "p.bdf")).K.toarray()
    xyz = np.array([[0.0, 0, 0], [0, 1, 0], [1, 0, 0], [1, 1, 0]])  # grids 1-4
    elements = [[0, 2, 3, 1]] if kind == "CQUAD4" else [[0, 2, 3], [0, 3, 1]]
    Ke = np.zeros((24, 24))
    for el in elements:
        k, _ = shell_matrices(xyz[el], E, NU, T, RHO, terms=ShellTerms(shear=0.5 * T * MAT.G))
        dofs = np.concatenate([6 * g + np.arange(6) for g in el])
        Ke[np.ix_(dofs, dofs)] += k
    np.testing.assert_allclose(got, Ke, rtol=0, atol=1e-12 * abs(Ke).max())


def _api_shells(n: int, kind: str):
    shells = []
    for i in range(n):
        for j in range(n):
            q = (1 + i * (n + 1) + j, 1 + (i + 1) * (n + 1) + j, 2 + (i + 1) * (n + 1) + j,
                 2 + i * (n + 1) + j)
            shells += [Shell(q, T, MAT)] if kind == "quad" else \
                [Shell((q[0], q[1], q[2]), T, MAT), Shell((q[0], q[2], q[3]), T, MAT)]
    return shells


def test_pshell_bending_ratio_and_blank_mids():
    """12I/T^3 scales the bending stiffness only; MID2 blank removes bending, MID1 blank the
    membrane and drilling stiffness; lumped mass has no rotary inertia."""
    def K(pshell: str, coupled: bool = True):
        text = plate_bdf(1).replace(f"PSHELL,1,1,{T},1", pshell)
        if not coupled:
            text = text.replace("PARAM,COUPMASS,1\n", "")
        m = nastran_matrices(parse_bulk(text, "p.bdf"))
        return m.K.toarray(), m.M.toarray()

    base, _ = K(f"PSHELL,1,1,{T},1")
    bend = np.tile([False, False, True, True, True, False], 4)
    twice, _ = K(f"PSHELL,1,1,{T},1,2.")
    np.testing.assert_allclose(twice[np.ix_(bend, bend)], 2 * base[np.ix_(bend, bend)],
                               rtol=1e-13)
    np.testing.assert_allclose(twice[np.ix_(~bend, ~bend)], base[np.ix_(~bend, ~bend)],
                               rtol=1e-13)
    no_bend, _ = K(f"PSHELL,1,1,{T}")
    assert np.abs(no_bend[np.ix_(bend, bend)]).max() == 0
    no_memb, _ = K(f"PSHELL,1,,{T},1")
    assert np.abs(no_memb[np.ix_(~bend, ~bend)]).max() == 0
    _, lumped = K(f"PSHELL,1,1,{T},1", coupled=False)
    assert np.count_nonzero(lumped - np.diag(np.diag(lumped))) == 0
    np.testing.assert_allclose(np.diag(lumped)[np.tile([1, 1, 1, 0, 0, 0], 4) == 1],
                               RHO * T / 4, rtol=1e-13)
    assert np.abs(np.diag(lumped)[np.tile([0, 0, 0, 1, 1, 1], 4) == 1]).max() == 0


def test_eigrl_frequency_range_keeps_the_modes_in_the_band(tmp_path):
    """EIGRL V1 V2 (Hz): the modes written are exactly those of the full run inside the band
    (ND blank: all of them; ND = 1: the lowest one in it)."""
    full = tmp_path / "full"
    full.mkdir()
    (full / "p.bdf").write_text(plate_bdf(6, eigrl="EIGRL,1,,,12"))
    assert cli.main(["run", str(full / "p.bdf"), "--out", str(full), "--quiet",
                     "--no-pictures"]) == 0
    omega = load(full / "p.h5").modes.omega
    f = omega / (2 * np.pi)
    v1, v2 = (f[1] + f[2]) / 2, (f[5] + f[6]) / 2  # modes 3 - 6
    for eig, expect in ((f"EIGRL,1,{v1:.6f},{v2:.6f}", omega[2:6]),
                        (f"EIGRL,1,{v1:.6f},{v2:.6f},1", omega[2:3])):
        band = tmp_path / f"band{len(expect)}"
        band.mkdir()
        (band / "p.bdf").write_text(plate_bdf(6, eigrl=eig))
        assert cli.main(["run", str(band / "p.bdf"), "--out", str(band), "--quiet",
                         "--no-pictures"]) == 0
        got = load(band / "p.h5").modes.omega
        np.testing.assert_allclose(got, expect, rtol=1e-9)


def _bush_model(cbush: str, pbush: str = "PBUSH,5,K,1.+3,2.+3,3.+3,4.+3,5.+3,6.+3",
                extra: str = "") -> str:
    return "\n".join(["GRID,1,,0.,0.,0.", "GRID,2,,1.,0.5,0.2", "CORD2R,7,,0.,0.,0.,0.,.6,.8,"
                      "\n,1.,0.,0.", cbush, pbush, extra, ""])


def test_cbush_grounded_in_a_coordinate_system_and_between_grids():
    """A grounded CBUSH in a rotated CORD2R: K's eigenvalues are K1 - K6 with the system's
    axes as eigenvectors; between two grids (axes GA -> GB and X, spring at S) a rigid motion
    of both grids stores no energy and a relative one the spring's."""
    bulk = parse_bulk(_bush_model("CBUSH,3,5,1,,,,,7"), "b.bdf")
    K = nastran_matrices(bulk).K.toarray()[:6, :6]
    axes = bulk.bushes[0].axes
    assert axes is not None
    T = np.kron(np.eye(2), axes)
    np.testing.assert_allclose(T @ K @ T.T, np.diag([1e3, 2e3, 3e3, 4e3, 5e3, 6e3]),
                               atol=1e-9 * 6e3)
    bulk = parse_bulk(_bush_model("CBUSH,3,5,1,2,0.,0.,1.\n,.3"), "b.bdf")
    K = nastran_matrices(bulk).K.toarray()
    x = np.array([[0.0, 0.0, 0.0], [1.0, 0.5, 0.2]])
    for th in np.eye(3):
        q = np.concatenate([np.concatenate([np.cross(th, p), th]) for p in x])
        assert np.abs(K @ q).max() < 1e-12 * np.abs(K).max()
    q = np.zeros(12)
    q[6:9] = x[1] / np.linalg.norm(x[1])  # GB moves along the axis: K1 alone
    assert q @ K @ q == pytest.approx(1e3, rel=1e-12)


@pytest.mark.parametrize("text, fragment", [
    ("CBUSH,3,5,1,2,0.,0.,1.\n,.3,,.1", "CBUSH 3: S1: spring offsets"),
    ("CBUSH,3,5,1", "CBUSH 3: CID: the element axes need CID"),
    ("CBUSH,3,5,1,,,,,7\nPBUSH,5,B,1.", r"PBUSH 5: B1: B \(damping\) is not supported"),
    ("CQUAD4,3,9,1,2,1,2", "CQUAD4 3: G1: the corners are different grids"),
    ("GRID,5,,0.,1.,0.\nCTRIA3,3,9,1,2,5", "CTRIA3 3: PID: no PSHELL or PCOMP of that id"),
    ("GRID,5,,0.,1.,0.\nCTRIA3,3,9,1,2,5\nPSHELL,9,1,.01,1,,4", "PSHELL 9: MID3"),
    ("GRID,5,,0.,1.,0.\nCTRIA3,3,9,1,2,5,,.1\nPSHELL,9,1,.01,1", "CTRIA3 3: ZOFFS"),
])
def test_bad_shell_and_bush_cards_name_the_field(text, fragment):
    with pytest.raises(BdfError, match=fragment):
        parse_bulk(_bush_model(text, "MAT1,1,2.1+11,,.3,7850.") if "PBUSH" not in text
                   else _bush_model(text.split("\n")[0], text.split("\n")[1]), "b.bdf")


def test_include_is_read_relative_and_sanitised(tmp_path):
    """INCLUDE inserts a file named relative to the including one (here in a subdirectory),
    giving the model the inline file gives; a name leading out of the directory, an absolute
    one, a loop, or nesting too deep is refused naming the statement; an error inside an
    included file names that file and its line."""
    inline = plate_bdf(2)
    (tmp_path / "parts").mkdir()
    grids = [ln for ln in inline.split("\n") if ln.startswith("GRID")]
    (tmp_path / "parts" / "grids.bdf").write_text("\n".join(grids) + "\n")
    main = inline.replace("\n".join(grids), "INCLUDE 'parts/grids.bdf'")
    (tmp_path / "m.bdf").write_text(main)
    (tmp_path / "inline.bdf").write_text(inline)
    a = nastran_matrices(read_bulk(tmp_path / "m.bdf"))
    b = nastran_matrices(read_bulk(tmp_path / "inline.bdf"))
    assert abs(a.K - b.K).max() == 0 and abs(a.M - b.M).max() == 0
    for name, fragment in (("../m.bdf", "inside its directory"),
                           ("/etc/passwd", "inside its directory"),
                           ("m.bdf", "includes itself")):
        (tmp_path / "bad.bdf").write_text(f"INCLUDE '{name}'\n")
        if name == "m.bdf":
            (tmp_path / "bad.bdf").write_text("INCLUDE 'bad.bdf'\n")
        with pytest.raises(BdfError, match=fragment):
            read_bulk(tmp_path / "bad.bdf")
    for k in range(10):
        (tmp_path / f"d{k}.bdf").write_text(f"INCLUDE 'd{k + 1}.bdf'\n")
    (tmp_path / "d10.bdf").write_text("GRID,1,,0.,0.,0.\n")
    with pytest.raises(BdfError, match="nest more than 8 deep"):
        read_bulk(tmp_path / "d0.bdf")
    outside = tmp_path.parent / f"{tmp_path.name}_outside"
    outside.mkdir()
    (outside / "x.bdf").write_text("GRID,1,,0.,0.,0.\n")
    os.symlink(outside, tmp_path / "out")
    (tmp_path / "link.bdf").write_text("INCLUDE 'out/x.bdf'\n")
    with pytest.raises(BdfError, match="a link leads out of it"):
        read_bulk(tmp_path / "link.bdf")
    (tmp_path / "parts" / "grids.bdf").write_text("GRID,1,,0,0.,0.\n")
    with pytest.raises(BdfError, match=r"parts/grids.bdf: line 1: GRID 1: X1"):
        read_bulk(tmp_path / "m.bdf", "m.bdf")
