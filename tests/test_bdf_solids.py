"""Nastran solids (CHEXA, CPENTA, CTETRA with PSOLID and MAT1), against independent references.

* a CHEXA block with COUPMASS and full integration (IN 2, ISOP FULL) gives the ``K`` and ``M``
  of substruct's own ``solid_box`` (the same trilinear hexahedra) to round-off; CTETRA the ``K`` and ``M`` of ``solid_from_mesh`` on
  the same tetrahedra;
* CPENTA on a distorted mesh, with bubble functions and fully integrated, passes the patch
  test (a linear displacement field leaves no
  force at the inner grids and stores the closed-form energy of its constant strain), has
  exactly six rigid-body modes, and its mass is ``rho V``;
* lumped mass (no COUPMASS) is diagonal, ``rho V_e / n`` on each corner's translations;
* a mixed file (a CHEXA block, a CBAR beam joined to its face by an RBE3) run with
  ``substruct run X.bdf`` has the modes of the same joint assembled from a frame beam and an
  interpolation link, and as a case whose RBE3 takes the face of the Nastran block by a box;
* some mid-side grids, IN = 3 without mid-side grids, reduced shear without bubbles, fluids,
  a missing PSOLID: one line, exit 2.
"""

from __future__ import annotations

import numpy as np
import pytest
from skfem import MeshHex, MeshTet

from substruct import cli
from substruct.analysis.api import modes
from substruct.assembly import assemble
from substruct.assembly.links import NodeRef, interpolation_link, link_constraints
from substruct.builder.model import assemble_case
from substruct.case.bdf import parse_bulk
from substruct.case.bdf_fields import BdfError
from substruct.case.loader import load_case
from substruct.io.result_reader import load
from substruct.models.beam import Material, Section
from substruct.models.frame import Beam, frame
from substruct.models.nastran import nastran_matrices, nastran_substructure
from substruct.models.solid import BoxGrid, solid_box, solid_from_mesh

E, NU, RHO = 2.1e11, 0.3, 7850.0
HEAD = ["BEGIN BULK", "MAT1,1,2.1+11,,.3,7850.", "PSOLID,1,1"]


def grids(xyz: np.ndarray, first: int = 1) -> list[str]:
    return [f"GRID,{first + k},,{float(x)!r},{float(y)!r},{float(z)!r}"
            for k, (x, y, z) in enumerate(xyz)]


def cells(card: str, conn: np.ndarray, first_grid: int = 1, first_id: int = 1) -> list[str]:
    out = []
    for e, c in enumerate(np.asarray(conn) + first_grid):
        f = [str(v) for v in c]
        out.append(f"{card},{first_id + e},1," + ",".join(f[:6]) +
                   ("\n," + ",".join(f[6:]) if len(f) > 6 else ""))
    return out


def hex_bdf(nx: int, ny: int, nz: int, L: tuple, extra: list[str] = ()) -> tuple[str, np.ndarray]:
    """A box of CHEXA, grids numbered by scikit-fem's tensor mesh, corners in Nastran order."""
    m = MeshHex.init_tensor(*(np.linspace(0, a, n + 1) for a, n in zip(L, (nx, ny, nz))))
    from skfem.io.meshio import to_meshio

    conn = to_meshio(m).cells[0].data  # meshio's (and Nastran's) corner order
    return "\n".join(HEAD + list(extra) + grids(m.p.T) + cells("CHEXA", conn) +
                     ["ENDDATA", ""]), m.p.T


def translations(sub, points: np.ndarray, labels) -> np.ndarray:
    """The matrix taking a solid's coordinates (``labels`` ``n<k>.u<c>`` at ``points``) to the
    Nastran model's."""
    P = np.zeros((sub.K.shape[0], len(labels)))
    for col, lab in enumerate(labels):
        node, comp = lab.split(".u")
        x = points[int(node[1:])]
        P[:, col] = sub.row({"at": x.tolist(), "component": "u" + comp}).toarray().ravel()
    return P


def same(A: np.ndarray, B: np.ndarray) -> float:
    return float(np.abs(A - B).max() / np.abs(B).max())


def test_chexa_block_is_the_solid_box_to_round_off():
    L = (1.0, 0.2, 0.3)
    text, _ = hex_bdf(4, 2, 3, L, ["PARAM,COUPMASS,1"])
    text = text.replace("PSOLID,1,1", "PSOLID,1,1,,2,,FULL")  # standard isoparametric
    sub = nastran_substructure("n", nastran_matrices(parse_bulk(text, "b.bdf")))
    box = solid_box("s", BoxGrid(L, (4, 2, 3)), E, NU, RHO)
    P = translations(sub, box.geometry.points, box.dof_labels)
    assert sub.K.shape == box.K.shape  # AUTOSPC removed every rotation
    assert same(P.T @ sub.K.toarray() @ P, box.K.toarray()) < 1e-13
    assert same(P.T @ sub.M.toarray() @ P, box.M.toarray()) < 1e-13


def test_ctetra_is_the_solid_tetrahedra_to_round_off():
    m = MeshTet.init_tensor(np.linspace(0, 1, 4), np.linspace(0, 0.3, 3), [0.0, 0.2, 0.45])
    text = "\n".join(HEAD + ["PARAM,COUPMASS,1"] + grids(m.p.T) + cells("CTETRA", m.t.T) +
                     ["ENDDATA"])
    sub = nastran_substructure("n", nastran_matrices(parse_bulk(text, "t.bdf")))
    ref = solid_from_mesh("s", m, E, NU, RHO)
    P = translations(sub, ref.geometry.points, ref.dof_labels)
    assert same(P.T @ sub.K.toarray() @ P, ref.K.toarray()) < 1e-13
    assert same(P.T @ sub.M.toarray() @ P, ref.M.toarray()) < 1e-13


def wedge_mesh() -> tuple[np.ndarray, np.ndarray]:
    """Two layers of wedges over a 3 x 3 grid of triangles pairs, the grid distorted."""
    rng = np.random.default_rng(5)
    n = 3
    xy = np.array([(i / n, j / n) for j in range(n + 1) for i in range(n + 1)])
    inner = (xy > 0).all(axis=1) & (xy < 1).all(axis=1)
    xy[inner] += rng.uniform(-0.08, 0.08, size=(int(inner.sum()), 2))
    tri = []
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            tri += [(a, a + 1, a + n + 2), (a, a + n + 2, a + n + 1)]
    zs = np.array([0.0, 0.17, 0.4])
    pts = np.vstack([np.c_[xy, np.full(len(xy), z) + 0.05 * xy[:, 0]] for z in zs])
    nl = len(xy)
    conn = [(a + k * nl, b + k * nl, c + k * nl, a + (k + 1) * nl, b + (k + 1) * nl,
             c + (k + 1) * nl) for k in range(len(zs) - 1) for a, b, c in tri]
    return pts, np.array(conn)


@pytest.mark.parametrize("psolid", ["PSOLID,1,1", "PSOLID,1,1,,2,,FULL"])
def test_cpenta_patch_test_rigid_modes_and_mass(psolid):
    """With bubble functions (the default) and fully integrated (IN 2, ISOP FULL)."""
    pts, conn = wedge_mesh()
    text = "\n".join(HEAD[:2] + [psolid, "PARAM,COUPMASS,1"] + grids(pts) +
                     cells("CPENTA", conn) + ["ENDDATA"])
    mats = nastran_matrices(parse_bulk(text, "w.bdf"))
    trans = np.flatnonzero(np.arange(mats.K.shape[0]) % 6 < 3)
    K = mats.K.toarray()[np.ix_(trans, trans)]
    M = mats.M.toarray()[np.ix_(trans, trans)]
    rng = np.random.default_rng(1)
    G, c = rng.normal(size=(3, 3)), rng.normal(size=3)
    u = (pts @ G.T + c).ravel()
    f = (K @ u).reshape(-1, 3)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    xy_in = ((pts[:, :2] > lo[:2] + 1e-9) & (pts[:, :2] < hi[:2] - 1e-9)).all(axis=1)
    inner = xy_in & (np.abs(pts[:, 2] - 0.17 - 0.05 * pts[:, 0]) < 1e-12)
    assert inner.sum() == 4
    assert np.abs(f[inner]).max() < 1e-9 * np.abs(f).max()
    eps = (G + G.T) / 2  # the energy of the constant strain: V (mu eps:eps + lam tr^2 / 2)
    mu, la = E / (2 * (1 + NU)), E * NU / ((1 + NU) * (1 - 2 * NU))
    energy = 0.4 * (mu * np.sum(eps * eps) + la * np.trace(eps) ** 2 / 2)
    assert abs(0.5 * u @ K @ u / energy - 1) < 1e-12
    lam = np.linalg.eigvalsh(K)
    assert np.sum(np.abs(lam) < 1e-9 * lam.max()) == 6
    ones = np.tile([1.0, 0.0, 0.0], len(pts))
    volume = 1.0 * 0.4  # the bottom and top surfaces are parallel sheared planes
    assert abs(ones @ M @ ones / (RHO * volume) - 1) < 1e-12


def test_lumped_mass_is_equal_shares_of_each_element():
    pts, conn = wedge_mesh()
    text = "\n".join(HEAD + grids(pts) + cells("CPENTA", conn) + ["ENDDATA"])
    mats = nastran_matrices(parse_bulk(text, "w.bdf"))
    coupled = nastran_matrices(parse_bulk(text.replace("PSOLID,1,1", "PSOLID,1,1\n"
                                                       "PARAM,COUPMASS,1"), "w.bdf"))
    M = mats.M.toarray()
    assert np.count_nonzero(M - np.diag(np.diag(M))) == 0
    # the element masses from the coupled matrices: rho V_e = sum of its x-x block
    share = np.zeros(len(pts))
    from substruct.models.nastran_solids import solid_blocks  # one element at a time
    for e, c in enumerate(conn):
        one = "\n".join(HEAD + ["PARAM,COUPMASS,1"] + grids(pts) + cells("CPENTA", c[None])
                        + ["ENDDATA"])
        bulk = parse_bulk(one, "one.bdf")
        _, _, _, Me = next(solid_blocks(bulk, {g: k for k, g in enumerate(sorted(bulk.grids))}))
        xs = np.arange(0, 6 * len(pts), 6)
        share[c] += Me.toarray()[np.ix_(xs, xs)].sum() / 6
    assert np.allclose(np.diag(M)[0::6], share, rtol=1e-12)
    assert np.allclose(np.diag(M)[2::6], share, rtol=1e-12)
    assert np.diag(M)[3::6].max() == 0.0
    assert abs(M.sum() / coupled.M.toarray().sum() - 1) < 1e-12


def mixed_bdf(n: int = 8) -> tuple[list[str], list[str], list[int], int]:
    """A clamped block of CHEXA and a CBAR cantilever joined to its free face by an RBE3: the
    block's lines (with its supports), the beam's and the link's lines, the face grids and the
    number of the block's grids."""
    text, xyz = hex_bdf(2, 4, 4, (0.1, 0.2, 0.2), ["PARAM,COUPMASS,1"])
    block = text.replace("ENDDATA\n", "").splitlines()
    base = len(xyz)
    clamp = [k + 1 for k, x in enumerate(xyz) if abs(x[0]) < 1e-12]
    face = [k + 1 for k, x in enumerate(xyz)
            if abs(x[0] - 0.1) < 1e-12 and abs(x[1] - 0.1) < 0.051 and abs(x[2] - 0.1) < 0.051]
    block += [f"SPC1,1,123456,{g}" for g in clamp]
    beam = [f"GRID,{base + 1 + k},,{0.1 + k * 1.0 / n!r},0.1,0.1" for k in range(n + 1)]
    beam += [f"CBAR,{1000 + k},2,{base + 1 + k},{base + 2 + k},0.,1.,0." for k in range(n)]
    beam += ["PBAR,2,1,1.-2,8.333333-6,8.333333-6,1.406-5"]
    beam += [f"RBE3,9000,,{base + 1},123456,1.,123," + ",".join(map(str, face[:2]))]
    rest = face[2:]
    beam += ["," + ",".join(map(str, rest[k:k + 8])) for k in range(0, len(rest), 8)]
    return block, beam, face, base


def test_mixed_solid_and_beam_file_runs_and_is_the_linked_assembly(tmp_path):
    block_lines, beam_lines, face, base = mixed_bdf()
    control = ["SOL 103", "CEND", "METHOD = 1", "SPC = 1"]
    path = tmp_path / "mixed.bdf"
    path.write_text("\n".join(control + block_lines + beam_lines +
                              ["EIGRL,1,,,6", "ENDDATA", ""]))
    out = tmp_path / "out"
    assert cli.main(["run", str(path), "--out", str(out), "--quiet", "--no-pictures"]) == 0
    omega = load(out / "mixed.h5").modes.omega
    assert omega.size == 6
    # the same joint: the block alone from bulk data, the beam as a frame, a link in Python
    block = nastran_substructure(
        "block", nastran_matrices(parse_bulk("\n".join(block_lines + ["ENDDATA"]), "b.bdf")))
    sec = Section(A=1e-2, Iy=8.333333e-6, Iz=8.333333e-6, J=1.406e-5)
    mat = Material(E=E, G=E / (2 * (1 + NU)), rho=RHO)
    beam = frame("beam", {1: (0.1, 0.1, 0.1), 2: (1.1, 0.1, 0.1)},
                 [Beam((1, 2), sec, mat, (0.0, 1.0, 0.0), divisions=8)])
    link = interpolation_link([block, beam], NodeRef("beam", {"node": 1}),
                              [NodeRef("block", {"node": g}) for g in face])
    asm = assemble([block, beam], (), link_constraints([link]))
    ref = modes(asm.M, None, asm.K, asm.A, 6).omega
    assert np.abs(omega / ref - 1).max() < 1e-8
    # and as a case: the block a Nastran substructure, its face chosen by a box
    (tmp_path / "block.bdf").write_text("\n".join(block_lines + ["ENDDATA", ""]))
    case = {"name": "joint", "substructures": [
        {"name": "block", "type": "nastran", "file": str(tmp_path / "block.bdf")},
        {"name": "beam", "type": "frame", "nodes": {1: [0.1, 0.1, 0.1], 2: [1.1, 0.1, 0.1]},
         "materials": {"steel": {"E": E, "G": E / (2 * (1 + NU)), "rho": RHO}},
         "sections": {"bar": {"A": 1e-2, "Iy": 8.333333e-6, "Iz": 8.333333e-6,
                              "J": 1.406e-5}},
         "members": [{"nodes": [1, 2], "section": "bar", "material": "steel",
                      "orientation": [0, 1, 0], "divisions": 8}]}],
        "links": [{"type": "interpolation", "reference": "beam@1",
                   "face": {"part": "block", "box": [[0.1, 0.05, 0.05], [0.1, 0.15, 0.15]]}}],
        "analysis": {"modes": {"count": 6}}}
    asm = assemble_case(load_case(case)).assembly
    assert np.abs(modes(asm.M, None, asm.K, asm.A, 6).omega / ref - 1).max() < 1e-8


@pytest.mark.parametrize("change, message", [
    (None, None),
    (("PSOLID,1,1", "PSOLID,1,1,,2"), "PSOLID 1: ISOP: 2 x 2 x 2 reduced shear integration"),
    (("PSOLID,1,1", "PSOLID,1,1,,THREE,,FULL"), "PSOLID 1: IN: 3 x 3 x 3 Gauss points (IN 3) "
     "are for the CHEXA with mid-side grids"),
    (("PSOLID,1,1", "PSOLID,1,1,,FOUR,,FULL"), "PSOLID 1: IN: only bubble functions"),
    (("PSOLID,1,1", "PSOLID,1,1,,BUBBLE,,FULL"), "PSOLID 1: ISOP: bubble functions"),
    (("PSOLID,1,1", "PSOLID,1,1,,,,SHEAR"), "PSOLID 1: ISOP: must be blank, REDUCED"),
    (("PSOLID,1,1", "PSOLID,1,1,,,,,PFLUID"), "PSOLID 1: FCTN: only structural solids"),
    (("PSOLID,1,1", "PSOLID,2,1"), "CHEXA 1: PID: no PSOLID of that id"),
    (("PSOLID,1,1", "PSOLID,1,1,7"), "PSOLID 1: CORDM: no such coordinate system"),
])
def test_bad_solid_cards_are_one_line_and_exit_2(tmp_path, capsys, change, message):
    text, _ = hex_bdf(1, 1, 1, (1.0, 1.0, 1.0))
    text = "SOL 103\nCEND\n" + text.replace("ENDDATA", "EIGRL,1,,,3\nENDDATA")
    if change is not None:
        text = text.replace(*change)
    if message is None:  # a CHEXA with G9 only of its twelve mid-side grids
        lines = text.splitlines()
        k = next(i for i, ln in enumerate(lines) if ln.startswith("CHEXA"))
        lines[k + 1] += ",1"
        text, message = "\n".join(lines), "CHEXA 1: G10: CHEXA needs all twelve mid-side grids"
    path = tmp_path / "bad.bdf"
    path.write_text(text)
    out = tmp_path / "out"
    assert cli.main(["run", str(path), "--out", str(out), "--quiet", "--no-pictures"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and message in err, err
    assert not out.exists() or not any(out.iterdir())


def test_a_flat_element_is_refused_naming_its_card():
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], dtype=float)
    text = "\n".join(HEAD + grids(pts) + ["CTETRA,5,1,1,2,3,4", "ENDDATA"])
    with pytest.raises(BdfError, match="CTETRA 5: the element is collapsed"):
        parse_bulk(text, "f.bdf")


CUBE = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                 [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], dtype=float)


@pytest.mark.parametrize("change, problem", [
    ((4, [0.0, 0.0, 0.0]), "collapsed"),       # G5 on G1: a zero Jacobian at both corners
    ((6, [0.0, 0.0, 1.0]), "collapsed"),       # G7 on G8
    ((6, [-1.0, -1.0, 1.0]), "folded"),        # G7 pulled across G5: corners of both signs
])
def test_a_collapsed_or_folded_hexahedron_is_refused_when_read(change, problem):
    """The corner Jacobians of the trilinear map: the unit cube's are all 1; a corner moved
    onto another makes two of them 0, one pulled across the element makes some negative."""
    pts = CUBE.copy()
    pts[change[0]] = change[1]
    text = "\n".join(HEAD + grids(pts) + ["CHEXA,5,1,1,2,3,4,5,6,", ",7,8", "ENDDATA"])
    with pytest.raises(BdfError, match=f"line 12: CHEXA 5: the element is {problem}"):
        parse_bulk(text, "f.bdf")


def test_a_mirrored_hexahedron_is_read_with_the_volume_of_the_cube():
    """Every corner Jacobian negative (the numbering of a mirrored element) is accepted, and
    its lumped mass is still rho V (the unit cube's 7850 kg)."""
    pts = CUBE * [1.0, 1.0, -1.0]
    text = "\n".join(HEAD + grids(pts) + ["CHEXA,5,1,1,2,3,4,5,6,", ",7,8", "ENDDATA"])
    M = nastran_matrices(parse_bulk(text, "f.bdf")).M
    assert abs(M.diagonal()[0::6].sum() - 7850.0) < 1e-9 * 7850.0
