"""Exports of parts with rotations: a frame column on a solid block (an interpolation link
over the block's top face), run, saved, read back and exported.  In the VTU and XDMF files the
frame nodes' rotations are point data of their own, equal to the mode shape's ``rx ry rz``
coordinates of each node (read by label); the displacements are its ``ux uy uz`` (nothing of
the rotations mixed in); the solid's points have zero rotation."""

from __future__ import annotations

import meshio
import numpy as np

from substruct import cli
from substruct.io import export
from substruct.io.result_reader import load

CASE = """name: rot
substructures:
  - name: block
    type: solid
    box: {lengths: [0.4, 0.4, 0.2], divisions: [2, 2, 1], origin: [-0.2, -0.2, -0.2]}
    E: 3.0e+10
    nu: 0.2
    rho: 2400
    fixed: [{box: [[-1, -1, -0.21], [1, 1, -0.19]]}]
  - name: column
    type: frame
    nodes: {1: [0, 0, 0], 2: [0, 0, 1]}
    materials: {steel: {E: 2.1e+11, G: 8.1e+10, rho: 7850}}
    sections: {tube: {A: 1.5e-3, Iy: 2.0e-6, Iz: 3.0e-6, J: 4.0e-6}}
    members: [{nodes: [1, 2], section: tube, material: steel, orientation: [1, 0, 0],
               divisions: 4}]
links:
  - {type: interpolation, reference: column@1,
     face: {part: block, plane: {point: [0, 0, 0], normal: [0, 0, 1]}}}
analysis:
  modes: {count: 4}
"""


def run(tmp_path):
    (tmp_path / "rot.yaml").write_text(CASE)
    out = tmp_path / "o"
    assert cli.main(["run", str(tmp_path / "rot.yaml"), "--out", str(out), "--quiet",
                     "--no-pictures"]) == 0
    return load(out / "rot.h5")


def by_label(result, k: int, comps: str) -> tuple[np.ndarray, np.ndarray]:
    """The frame nodes' (in drawing order) coordinates ``comps`` of mode ``k``, by label."""
    labels = {lab: j for j, lab in enumerate(result.model.dof_labels)}
    col = next(d for d in result.model.drawings if d.name == "column")
    ids = [1, 2, 3, 4, 5]  # given nodes, then those made by divisions, in order
    # the nodes come first; the points inside the beams follow (their rotations are held to
    # the beam interpolation in tests/test_frame_pictures.py)
    assert len(col.points) >= len(ids)
    shape = result.modes.shapes[:, k - 1]
    return col.points, np.array([[shape[labels[f"column.{i}:{c}"]] for c in comps]
                                 for i in ids])


def test_vtu_and_xdmf_carry_rotations_apart_from_displacements(tmp_path):
    r = run(tmp_path)
    mesh = export.combined_mesh(r.model)
    n_block = int(mesh.point_offsets[1])
    (vtu,) = export.export_modes(r, tmp_path / "vtu", "vtu")
    data = meshio.read(vtu).point_data
    xdmf, _ = export.export_modes(r, tmp_path / "xdmf", "xdmf")
    with meshio.xdmf.TimeSeriesReader(xdmf) as reader:
        reader.read_points_cells()
        steps = [reader.read_data(s)[1] for s in range(reader.num_steps)]
    for k in range(1, 5):
        _, rot = by_label(r, k, ("rx", "ry", "rz"))
        nodes = slice(n_block, n_block + len(rot))
        _, disp = by_label(r, k, ("ux", "uy", "uz"))
        scale = np.abs(r.modes.shapes[:, k - 1]).max()
        for real, imag, shape_real in (
                (data[f"mode_{k}_rotation_real"], data[f"mode_{k}_rotation_imag"],
                 data[f"mode_{k}_real"]),
                (steps[k - 1]["rotation_real"], steps[k - 1]["rotation_imag"],
                 steps[k - 1]["shape_real"])):
            assert len(real) > nodes.stop  # the column's points inside its beams
            assert np.abs(real[nodes] - rot.real).max() <= 1e-14 * scale
            assert np.abs(imag[nodes] - rot.imag).max() <= 1e-14 * scale
            assert np.abs(shape_real[nodes] - disp.real).max() <= 1e-14 * scale
            assert not np.any(real[:n_block]) and not np.any(imag[:n_block])
        assert np.abs(rot).max() > 1e-3 * scale  # the modes do turn the column's nodes


def test_parts_without_rotations_write_no_rotation_data(tmp_path):
    r = run(tmp_path)
    for d in r.model.drawings:
        d.rotations = None
    (vtu,) = export.export_modes(r, tmp_path / "vtu", "vtu", modes="1")
    assert sorted(meshio.read(vtu).point_data) == ["mode_1_imag", "mode_1_real"]
