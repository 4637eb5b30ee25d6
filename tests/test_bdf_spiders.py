"""The RBE2, RBE3 and MPC cards of a Nastran model are drawn as spiders (substruct/builder/
frame_drawing.py, ``bulk_spiders``).

``cases/solid_bracket.bdf`` (a CHEXA block, a CBAR arm, one RBE3 joint), with an RBE2 added
from the arm's tip grid 109 to a grid 110 placed in a rotated CORD2R and an MPC tying three
arm grids, is run as ``substruct run X.bdf`` runs it:

* the run's drawings hold one spider per RBE card and per MPC card between grids, named after
  the card (an MPC on one grid has none);
* its points are the grids' positions in basic coordinates, read here from the GRID cards
  (and, for grid 110, through the CORD2R by hand);
* its rows are the assembly's rows of the grids' ``ux uy uz``, so the drawn legs move with
  each mode's translations there (to 1e-12 of the mode's largest).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

import substruct
from substruct.assembly.stack import PointRef
from substruct.builder.model import assemble_case

BRACKET = Path(__file__).resolve().parents[1] / "cases" / "solid_bracket.bdf"
FACE = [27, 28, 29, 42, 43, 44, 57, 58, 59]  # the RBE3's grids, in card order
# CORD2R 7: origin (1, 0, 0), z along basic z, x along basic y (so y along -x basic); grid
# 110 at (0.2, 0.1, 0.1) in it is at (1 - 0.1, 0.2, 0.1) in basic coordinates.
EXTRA = ("CORD2R,7,,1.,0.,0.,1.,0.,1.,\n,1.,1.,0.\nGRID,110,7,.2,.1,.1\n"
         "RBE2,9001,109,123456,110\n")
# an MPC tying grid 105's uz to grid 104's and 106's (the first grid is the dependent one), and
# one on a single grid (nothing to draw)
MPC = "MPC,5,105,3,1.,104,3,-.5\n,,106,3,-.5\nMPC,5,107,1,1.,107,2,-1.\n"
GRID_110 = np.array([0.9, 0.2, 0.1])


def _grids(text: str) -> dict[int, np.ndarray]:
    """The basic positions of the GRID cards of ``text`` written without CP."""
    out = {}
    for line in text.splitlines():
        f = line.split(",")
        if f[0] == "GRID" and f[2] == "":
            out[int(f[1])] = np.array([float(v) for v in f[3:6]])
    return out


def test_each_rbe_card_is_a_spider_moving_with_its_grids(tmp_path: Path) -> None:
    text = BRACKET.read_text().replace("ENDDATA", EXTRA + MPC + "ENDDATA").replace(
        "SPC = 1\n", "SPC = 1\nMPC = 5\n")
    path = tmp_path / "bracket.bdf"
    path.write_text(text)
    case = substruct.load_case(path, ["output.pictures=false"])
    result = substruct.run_case(case)
    spiders = {d.name: d for d in result.model.drawings if d.kind == "link"}
    mpc_name = [n for n in spiders if "MPC" in n]
    assert sorted(spiders) == sorted(["bracket: RBE2 9001", "bracket: RBE3 9000", *mpc_name])
    assert len(mpc_name) == 1 and mpc_name[0].startswith("bracket: MPC 5 (line ")
    xyz = {**_grids(text), 110: GRID_110}
    asm = assemble_case(case).assembly  # the run's model: its stacked coordinates
    shapes = result.modes.shapes.real
    assert shapes.shape[1] == 6
    for name, grids in (("bracket: RBE3 9000", [101, *FACE]),
                        ("bracket: RBE2 9001", [109, 110]), (mpc_name[0], [105, 104, 106])):
        d = spiders[name]
        np.testing.assert_allclose(d.points, [xyz[g] for g in grids], rtol=0, atol=1e-15)
        assert d.cells[0][0] == "line"
        assert d.cells[0][1].tolist() == [[0, j] for j in range(1, len(grids))]
        ref = np.vstack([asm.row(PointRef("bracket", f"{g}:{c}")).toarray()
                         for g in grids for c in (1, 2, 3)])
        np.testing.assert_array_equal(d.interp.toarray(), ref)
        for k in range(shapes.shape[1]):  # the legs move with each mode's translations
            drawn = (d.interp @ shapes[:, k]).reshape(-1, 3)
            block = shapes[asm.block("bracket"), k]
            sub = asm.substructures[0]
            col = {label: j for j, label in enumerate(sub.dof_labels)}
            expected = np.array([[block[col[f"{g}:{c}"]] for c in (1, 2, 3)] for g in grids])
            assert np.abs(drawn - expected).max() <= 1e-12 * np.abs(shapes[:, k]).max()
    # the MPC holds uz(105) = (uz(104) + uz(106)) / 2 in every mode: so do its drawn legs
    for k in range(shapes.shape[1]):
        z = (spiders[mpc_name[0]].interp @ shapes[:, k]).reshape(-1, 3)[:, 2]
        assert abs(z[0] - (z[1] + z[2]) / 2) <= 1e-12 * np.abs(shapes[:, k]).max()
    # the RBE2 holds grid 110 on the rigid motion of 109: a mode moves it as u + theta x r
    u = shapes[:, 0]
    tip = np.array([asm.row(PointRef("bracket", f"109:{c}")) @ u for c in range(1, 7)]).ravel()
    leg = (spiders["bracket: RBE2 9001"].interp @ u).reshape(-1, 3)[1]
    rigid = tip[:3] + np.cross(tip[3:], GRID_110 - xyz[109])
    assert np.abs(leg - rigid).max() <= 1e-12 * np.abs(u).max()
