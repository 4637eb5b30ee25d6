"""Mode pictures of frames: beams drawn as curves bent by their end rotations, shells as
surfaces, links as spiders (substruct/builder/frame_drawing.py).

* The frame-with-plate case draws its modes, and at every node the drawn displacement is the
  mode's translation there (one common scale for the whole picture).
* A rigid motion ``a + theta x x`` of a free frame is drawn exactly at every point of every
  beam, the points inside the elements included (the Hermite interpolation reproduces it).
* A cantilever under a tip load (Euler-Bernoulli: the nodal solution is exact and the
  deflection a cubic) is drawn inside its elements on the closed form
  ``w(x) = P x^2 (3 L - x) / (6 E I)``.
* Each rigid link is a spider from its independent node to its dependent, moving with their
  translations.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import scipy.sparse.linalg as spla

import substruct
from substruct.assembly.stack import PointRef
from substruct.builder.model import assemble_case
from substruct.builder.frame_drawing import BEAM_SEGMENTS, beam_curves
from substruct.models.beam import Material, Section
from substruct.models.frame import Beam, frame
from substruct.viz.layout import deformed, layout
from substruct.viz.mode_picture import render_modes

CASES = Path(__file__).resolve().parents[1] / "cases"
STEEL = Material(E=2.1e11, G=8.1e10, rho=7850.0)
TUBE = Section(A=4.44e-4, Iy=1.01e-7, Iz=1.3e-7, J=1.64e-7)


def _drawn(sub, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Points and displacements of a frame's beam-curve drawing for coordinates ``u``."""
    points, disp, _ = _drawn_with_rotations(sub, u)
    return points, disp


def _drawn_with_rotations(sub, u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points, displacements and rotations of a frame's beam-curve drawing."""
    g = sub.geometry
    points, _, interp, rot = beam_curves(sub, np.asarray(g.points, float), list(g.cells),
                                         g.interp, g.rotations)
    assert rot is not None and rot.shape == interp.shape
    return points, (interp @ u).reshape(-1, 3), (rot @ u).reshape(-1, 3)


def test_frame_plate_case_draws_its_modes_at_the_nodes_translations(tmp_path: Path) -> None:
    case = substruct.load_case(CASES / "frame_plate.yaml", ["output.pictures=false"])
    result = substruct.run_case(case)
    png = substruct.plot_modes(result, tmp_path / "modes.png", n_modes=2)
    assert png.stat().st_size > 10_000
    lay = layout(result.model.drawings)
    names = [d.name for d in lay.drawings]
    asm = assemble_case(case).assembly  # the run's model: its stacked coordinates
    assert [d.kind for d in lay.drawings].count("link") == 4
    for k in range(2):
        shape = result.modes.shapes[:, k].real
        pos, _ = deformed(lay, shape)
        drawn, expected = [], []
        for sub in asm.substructures:
            off = lay.mesh.point_offsets[names.index(sub.name)]
            block = shape[asm.block(sub.name)]
            col = {label: j for j, label in enumerate(sub.dof_labels)}
            for n, node in enumerate(sub.meta["node_ids"]):
                drawn.append(pos[off + n] - lay.points[off + n])
                expected.append([block[col[f"{node}:{c}"]] if f"{node}:{c}" in col else 0.0
                                 for c in ("ux", "uy", "uz")])
        drawn, expected = np.asarray(drawn), np.asarray(expected)
        scale = float(np.sum(drawn * expected) / np.sum(expected * expected))
        assert abs(scale) > 0
        assert np.abs(drawn - scale * expected).max() <= 1e-12 * np.abs(drawn).max()


def _portal() -> tuple:
    nodes = {1: [0, 0, 0], 2: [0.3, 0.2, 1.5], 3: [1.8, 0.4, 1.7], 4: [2.0, 1.1, 0.2]}
    beams = [Beam((1, 2), TUBE, STEEL, (1, 0, 0), divisions=3),
             Beam((2, 3), TUBE, STEEL, (0, 0, 1), divisions=2),
             Beam((3, 4), TUBE, STEEL, (0, 1, 0), divisions=3)]
    return nodes, beams


def test_a_rigid_motion_is_drawn_exactly_along_every_beam() -> None:
    nodes, beams = _portal()
    sub = frame("portal", nodes, beams)
    a, theta = np.array([0.3, -0.2, 0.5]), np.array([0.04, -0.07, 0.02])
    xyz = sub.meta["node_xyz"]
    field = np.hstack([a + np.cross(theta, xyz), np.tile(theta, (len(xyz), 1))])  # (nodes, 6)
    ids = sub.meta["node_ids"]
    u = np.array([field[ids.index(int(lab.split(":")[0])),
                        ("ux", "uy", "uz", "rx", "ry", "rz").index(lab.split(":")[1])]
                  for lab in sub.dof_labels])
    points, disp, rot = _drawn_with_rotations(sub, u)
    assert len(points) == len(xyz) + 8 * (BEAM_SEGMENTS - 1)
    exact = a + np.cross(theta, points)
    assert np.abs(disp - exact).max() <= 1e-13 * np.abs(exact).max()
    # the exported rotation of every drawn point is the rigid rotation, inside the beams too
    assert np.abs(rot - theta).max() <= 1e-13 * np.abs(theta).max()


def test_a_cantilever_under_a_tip_load_is_drawn_on_the_cubic() -> None:
    L, P = 2.0, 150.0
    d = np.array([1.0, 2.0, 0.5]) / np.linalg.norm([1.0, 2.0, 0.5])  # the beam's axis
    sub = frame("cantilever", {1: [0, 0, 0], 2: (L * d).tolist()},
                [Beam((1, 2), TUBE, STEEL, (0, 0, 1), divisions=3)], supports={1: "123456"})
    y = np.cross([0, 0, 1], d)
    y /= np.linalg.norm(y)  # across the axis and the orientation (0, 0, 1): local z, so Iy
    f = np.zeros(sub.n_dof)
    for c, comp in enumerate(("ux", "uy", "uz")):
        f[list(sub.dof_labels).index(f"2:{comp}")] = P * y[c]
    u = spla.spsolve(sub.K.tocsc(), f)
    points, disp, rot = _drawn_with_rotations(sub, u)
    x = points @ d
    exact = np.outer(P * x**2 * (3 * L - x) / (6 * STEEL.E * TUBE.Iy), y)
    assert np.abs(disp - exact).max() <= 1e-9 * np.abs(exact).max()
    # the bending rotation is d x w'(x): w' = P x (2 L - x) / (2 E I) along y
    slope = np.outer(P * x * (2 * L - x) / (2 * STEEL.E * TUBE.Iy), np.cross(d, y))
    assert np.abs(rot - slope).max() <= 1e-9 * np.abs(slope).max()
    assert np.isclose(x.max(), L) and len(points) == 4 + 3 * (BEAM_SEGMENTS - 1)


def test_links_are_spiders_moving_with_their_nodes() -> None:
    model = assemble_case(substruct.load_case(CASES / "frame_plate.yaml",
                                              ["output.pictures=false"]))
    spiders = {d.name: d for d in model.drawings if d.kind == "link"}
    assert sorted(spiders) == [f"bracket{k}" for k in range(1, 5)]
    asm = model.assembly
    cols = asm.substructures[[s.name for s in asm.substructures].index("columns")]
    deck = asm.substructures[[s.name for s in asm.substructures].index("deck")]
    for k, (top, corner) in enumerate([(5, 11), (6, 12), (7, 13), (8, 14)], start=1):
        d = spiders[f"bracket{k}"]
        np.testing.assert_allclose(d.points, [cols.position({"node": top}),
                                              deck.position({"node": corner})], atol=1e-15)
        assert d.cells[0][0] == "line" and d.cells[0][1].tolist() == [[0, 1]]
        rows = d.interp.toarray()
        for j, (name, node) in enumerate((("columns", top), ("deck", corner))):
            for c, comp in enumerate(("ux", "uy", "uz")):
                ref = asm.row(PointRef(name, f"{node}:{comp}")).toarray()
                np.testing.assert_array_equal(rows[3 * j + c], ref[0])


def test_links_to_solids_and_between_coincident_nodes_are_drawn() -> None:
    """The interpolation link onto the block's nodes (solid points by position) and the rigid
    link from the column top to the Nastran arm's root (two nodes at one place) draw."""
    case = substruct.load_case(CASES / "frame_solid_links.yaml", ["output.pictures=false"])
    result = substruct.run_case(case)
    spiders = {d.name: d for d in result.model.drawings if d.kind == "link"}
    assert len(spiders["column_foot"].points) == 1 + len(case.links[0].nodes)
    arm = spiders["arm_root"].points
    assert len(arm) == 2 and np.linalg.norm(arm[1] - arm[0]) <= 1e-12
    image = render_modes(result, n_modes=1)
    assert image.ndim == 3 and len(np.unique(image.reshape(-1, image.shape[2]), axis=0)) > 50
