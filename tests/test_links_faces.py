"""Beam-to-solid links: the nodes of a solid face chosen by a region, against independent
references.

* tributary areas of a graded face grid are the products of the half-spacings (closed form),
  and sum to the face's area; a plane picks the nodes the box picks;
* an interpolation link over a face with area weights gives the reference node the weighted
  least-squares rigid fit of the face's translations (``numpy.linalg.lstsq`` of the defining
  equations);
* a beam joined to the free face of a clamped solid block by an interpolation link, against
  the same joint meshed in solids (block + bar, quadratic hexahedra): the difference of the
  first bending frequency shrinks as the bar gets slender (measured: 0.60%, 0.30%, 0.15% at
  ``L/h = 5, 10, 20``, the joint's ``h/L``);
* a rigid spider (``type: rigid`` with ``face:``) moves every face node with the rigid motion
  of its node in each coupled mode, and the three formulations agree;
* in a case file, ``face:`` gives the links of the nodes listed one by one; a face whose nodes
  lie on one line cannot carry the rotation about it: exit 2, one line, nothing written.
"""

from __future__ import annotations

import copy
import pathlib

import numpy as np
import pytest
from skfem import MeshHex

from substruct import cli
from substruct.analysis.api import modes
from substruct.assembly import PointRef as P
from substruct.assembly import assemble
from substruct.assembly.faces import FaceRegion, face_node_refs, face_nodes, tributary_areas
from substruct.assembly.links import LinkError, NodeRef, interpolation_link, link_constraints
from substruct.builder.model import assemble_case
from substruct.case.loader import load_case
from substruct.case.yaml_io import load_yaml
from substruct.models.beam import Material, Section
from substruct.models.frame import Beam, frame
from substruct.models.solid import solid_from_mesh

E, NU, RHO, H = 2.1e11, 0.3, 7850.0, 0.1
G = E / (2 * (1 + NU))
CLAMP = [{"box": [[0, -H, -H], [0, H, H]]}]
CASES = pathlib.Path(__file__).resolve().parents[1] / "cases"


def skew(r: np.ndarray) -> np.ndarray:
    return np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])


def graded_block():
    xs, ys, zs = np.array([0.0, 0.3, 1.0]), np.array([0.0, 0.1, 0.4, 1.0]), \
        np.array([-0.5, 0.0, 0.2, 0.7])
    block = solid_from_mesh("block", MeshHex.init_tensor(xs, ys, zs), 1e9, 0.25, 1000.0,
                            fixed=[{"box": [[0, 0, -0.5], [0, 1, 0.7]]}])
    return block, ys, zs


def half_spacings(x: np.ndarray) -> np.ndarray:
    d = np.diff(x)
    return np.r_[d[0] / 2, (d[:-1] + d[1:]) / 2, d[-1] / 2]


def test_tributary_areas_are_the_half_spacings_and_a_plane_picks_the_box():
    block, ys, zs = graded_block()
    picked = face_nodes(block, FaceRegion(box=[[1, -9, -9], [1, 9, 9]]))
    plane = face_nodes(block, FaceRegion(point=[1, 0, 0], normal=[-2, 0, 0]))
    assert np.array_equal(picked, plane) and picked.size == len(ys) * len(zs)
    area = tributary_areas(block, picked)
    xyz = block.geometry.points[picked]
    wy = dict(zip(ys, half_spacings(ys)))
    wz = dict(zip(zs, half_spacings(zs)))
    expect = np.array([wy[y] * wz[z] for _, y, z in xyz])
    assert np.allclose(area, expect, rtol=1e-12, atol=0)
    assert abs(area.sum() - 1.0 * 1.2) < 1e-12
    # a plane with a tolerance picks two layers; part of a plane is picked by plane and box
    assert face_nodes(block, FaceRegion(point=[0.65, 0, 0], normal=[1, 0, 0],
                                        tolerance=0.36)).size == 2 * picked.size
    sub = face_nodes(block, FaceRegion(box=[[0, 0, 0], [9, 0.4, 9]], point=[1, 0, 0],
                                       normal=[1, 0, 0]))
    assert sub.size == 3 * 3


def test_area_weighted_interpolation_is_the_least_squares_fit_of_its_face():
    block, _, _ = graded_block()
    ref = frame("beam", {1: (1.2, 0.3, 0.1), 2: (2.0, 0.3, 0.1)},
                [Beam((1, 2), Section(1e-4, 1e-9, 1e-9, 1e-9), Material(1e9, 4e8, 1e3),
                      (0, 1, 0))])
    picked = face_nodes(block, FaceRegion(box=[[1, -9, -9], [1, 9, 9]]))
    w = tributary_areas(block, picked)
    link = interpolation_link([block, ref], NodeRef("beam", {"node": 1}),
                              face_node_refs(block, picked), w)
    asm = assemble([block, ref], (), link_constraints([link]))
    rng = np.random.default_rng(3)
    q = rng.normal(size=asm.A.shape[1])
    xr = np.array([1.2, 0.3, 0.1])
    u, rows = [], []
    nb = block.K.shape[0]
    for k in picked:
        u.append([block.row({"node": int(k), "component": c}).toarray().ravel()
                  for c in "xyz"])
    U = np.array([[r @ q[:nb] for r in node] for node in u])
    for r, uj, wj in zip(block.geometry.points[picked] - xr, U, w):
        rows.append((np.sqrt(wj) * np.hstack([np.eye(3), -skew(r)]), np.sqrt(wj) * uj))
    fit = np.linalg.lstsq(np.vstack([a for a, _ in rows]), np.concatenate([b for _, b in rows]),
                          rcond=None)[0]
    # each row of A reads u_r,c - (fit)_c: with u_r = 0 it is minus the fitted component
    ref_cols = slice(nb, nb + 6)
    q[ref_cols] = 0.0
    assert np.abs(asm.A @ q + fit).max() < 1e-12 * np.abs(fit).max()
    with pytest.raises(LinkError, match="do not determine component"):
        line = face_nodes(block, FaceRegion(box=[[1, -9, 0.2], [1, 9, 0.2]]))
        interpolation_link([block, ref], NodeRef("beam", {"node": 1}),
                           face_node_refs(block, line))


def first_bending(L: float, joint: bool) -> float:
    """The first bending frequency of a square bar (side ``H``, length ``L``) standing out of
    the free face of a clamped block (``H x 2H x 2H``): a Timoshenko beam joined by an
    interpolation link to the face nodes under its section, or the bar meshed in solids."""
    ys = np.linspace(-H, H, 5)
    if joint:
        mesh = MeshHex.init_tensor(np.linspace(0, H, 3), ys, ys)
    else:
        mesh = MeshHex.init_tensor(np.unique(np.r_[np.linspace(0, H, 3),
                                                   np.linspace(H, H + L, int(2 * L / H) + 1)]),
                                   ys, ys)
        c = mesh.p[:, mesh.t].mean(axis=1)
        out = (c[0] > H) & ((np.abs(c[1]) > H / 2) | (np.abs(c[2]) > H / 2))
        mesh = mesh.remove_elements(np.flatnonzero(out))
    solid = solid_from_mesh("block", mesh, E, NU, RHO, order=2, fixed=CLAMP)
    if not joint:
        return float(modes(solid.M, None, solid.K, None, 1).omega[0])
    sec = Section(A=H * H, Iy=H**4 / 12, Iz=H**4 / 12, J=0.1406 * H**4, ky=5 / 6, kz=5 / 6)
    bar = frame("bar", {1: (H, 0, 0), 2: (H + L, 0, 0)},
                [Beam((1, 2), sec, Material(E=E, G=G, rho=RHO), (0, 1, 0),
                      theory="timoshenko", divisions=16)])
    picked = face_nodes(solid, FaceRegion(box=[[H, -H / 2, -H / 2], [H, H / 2, H / 2]]))
    link = interpolation_link([solid, bar], NodeRef("bar", {"node": 1}),
                              face_node_refs(solid, picked))
    asm = assemble([solid, bar], (), link_constraints([link]))
    return float(modes(asm.M, None, asm.K, asm.A, 1, checks=("null-space",)).omega[0])


def test_beam_on_a_solid_face_converges_to_the_all_solid_joint():
    diff = [abs(first_bending(r * H, True) / first_bending(r * H, False) - 1)
            for r in (5, 10, 20)]
    # the joint's error is of order h/L: it halves as the bar doubles in length
    assert diff[0] > diff[1] > diff[2]
    assert 1.5 < diff[0] / diff[1] < 2.7 and 1.5 < diff[1] / diff[2] < 2.7
    assert diff[2] < 3e-3


def face_case() -> dict:
    raw = load_yaml((CASES / "frame_solid_links.yaml").read_text(), "frame_solid_links.yaml")
    raw["substructures"][2]["file"] = str(CASES / "frame_arm.bdf")
    return raw


def case_omega(raw: dict) -> np.ndarray:
    asm = assemble_case(load_case(raw)).assembly
    return modes(asm.M, None, asm.K, asm.A, 6).omega


def test_a_face_in_a_case_is_its_nodes_listed():
    raw = face_case()
    listed = copy.deepcopy(raw)
    listed["links"][0]["nodes"] = [f"block@{x},{y},0" for x in (-0.1, 0.0, 0.1)
                                   for y in (-0.1, 0.0, 0.1)]
    face = copy.deepcopy(raw)
    del face["links"][0]["nodes"]
    face["links"][0]["face"] = {"part": "block", "box": [[-0.1, -0.1, 0], [0.1, 0.1, 0]]}
    assert np.abs(case_omega(face) / case_omega(listed) - 1).max() < 1e-10
    area = copy.deepcopy(face)
    area["links"][0]["weights"] = "area"
    diff = np.abs(case_omega(area) / case_omega(face) - 1).max()
    assert 1e-6 < diff < 0.05  # other weights, another (close) joint


def test_a_rigid_spider_moves_its_face_rigidly_with_the_node():
    raw = face_case()
    raw["links"][0] = {"name": "column_foot", "type": "rigid", "independent": "column@1",
                       "components": "123",
                       "face": {"part": "block", "box": [[-0.1, -0.1, 0], [0.1, 0.1, 0]]}}
    asm = assemble_case(load_case(raw)).assembly
    res = modes(asm.M, None, asm.K, asm.A, 6, checks=("null-space", "kkt"))
    assert max(res.agreement.values()) < 1e-9
    xs = [(x, y) for x in (-0.1, 0.0, 0.1) for y in (-0.1, 0.0, 0.1)]
    for k in range(6):
        q = res.shapes[:, k]
        ref = np.array([(asm.row(P("column", f"1:{c}")) @ q)[0]
                        for c in ("ux", "uy", "uz", "rx", "ry", "rz")])
        scale = np.abs(ref[:3]).max() + 0.1 * np.abs(ref[3:]).max()
        for x, y in xs:
            u = np.array([(asm.row(P("block", {"at": [x, y, 0.0], "component": c})) @ q)[0]
                          for c in "xyz"])
            rigid = ref[:3] + np.cross(ref[3:], [x, y, 0.0])
            assert np.abs(u - rigid).max() < 1e-9 * scale


@pytest.mark.parametrize("face, message", [
    ({"part": "block", "box": [[-0.1, 0, 0], [0.1, 0, 0]]},
     "links.column_foot.face: the nodes do not determine component rx of the reference node"),
    ({"part": "block", "plane": {"point": [0, 0, 0.05], "normal": [0, 0, 1]}},
     "links.column_foot.face: the region holds no node of the part"),
    ({"part": "column", "box": [[0, 0, 0], [0, 0, 1]]},
     "links.column_foot.face.part: a face is taken from a solid or a Nastran model"),
])
def test_a_bad_face_is_one_line_and_exit_2(tmp_path, capsys, face, message):
    raw = face_case()
    del raw["links"][0]["nodes"]
    raw["links"][0]["face"] = face
    import yaml

    path = tmp_path / "case.yaml"
    path.write_text(yaml.safe_dump(raw))
    out = tmp_path / "out"
    assert cli.main(["run", str(path), "--out", str(out), "--quiet", "--no-pictures"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and message in err, err
    assert not out.exists() or not any(out.iterdir())
