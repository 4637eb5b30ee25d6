"""GRID CD, the displacement coordinate system (substruct/models/nastran_cd.py,
substruct/builder/nastran_cd_links.py): a grid's six coordinates along its CD system's
directions at the grid, K_CD = T^T K T, and every component reference in CD.

(a) a spatial cantilever of CBARs with masses whose every grid (and clamp) is in a CORD2R
    rotated about z: the eigenvalues of the basic model to 1e-12, mode shapes T^T phi;
(b) an inclined roller: a plane frame whose support grid has CD rotated so that its
    component 2 is normal to a 30 degree slope, SPC on 2: the eigenvalues of the basic model
    with the MPC u_n = 0, to 1e-10;
(c) a ring of CBARs in a cylindrical CD (CORD2C), SPC on radial and tangential components:
    the eigenvalues of the basic model with the equivalent MPCs, to 1e-10;
(d) RBE2, RBAR and RBE3 whose dependent (and independent) grids have a CD: the eigenvalues
    of the same elements in basic, to 1e-10;
and the combinations refused, naming card and line.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as la

from substruct.analysis.api import modes
from substruct.builder.model import assemble_case
from substruct.case.bdf import parse_bulk
from substruct.case.bdf_fields import BdfError
from substruct.case.loader import load_case
from substruct.models.nastran import nastran_matrices, nastran_substructure
from substruct.models.nastran_cd import grid_transform

PROPS = ["MAT1,1,2.1+11,,.3,7850.", "PBAR,1,1,1.-3,1.-7,2.-7,1.5-7"]
HEAD = ["SOL 103", "CEND", "METHOD = 1", "SPC = 1", "BEGIN BULK", "EIGRL,1,,,8"] + PROPS


def _r(v: float) -> str:
    return f"{v:.16e}"


def _eigenvalues(tmp_path: Path, lines: list[str], name: str, n: int = 8) -> np.ndarray:
    path = tmp_path / f"{name}.bdf"
    head = HEAD if not any(a.startswith("MPC,") for a in lines) else \
        HEAD[:4] + ["MPC = 2"] + HEAD[4:]
    path.write_text("\n".join(head + lines + ["ENDDATA", ""]))
    asm = assemble_case(load_case(path)).assembly
    return modes(asm.M, None, asm.K, asm.A, n).omega ** 2


def _close(a: np.ndarray, b: np.ndarray, tol: float) -> None:
    assert a.shape == b.shape and np.abs(a - b).max() <= tol * np.abs(b).max(), (a, b)


def _cantilever(cd: str) -> str:
    grids = [(0., 0., 0.), (1., 0., 0.), (1., 1., 0.), (1., 1., .5), (1.3, 1.2, .6)]
    lines = [f"GRID,{k + 1},,{x:.1f},{y:.1f},{z:.1f},{cd}" for k, (x, y, z) in enumerate(grids)]
    # orientation vectors along z or by G0: the same in basic and in CD 7 (OFFT GGG: the
    # vector is in GA's CD)
    lines += ["CBAR,1,1,1,2,0.,0.,1.", "CBAR,2,1,2,3,0.,0.,1.", "CBAR,3,1,3,4,1",
              "CBAR,4,1,4,5,0.,0.,1.", "CONM2,11,5,,2.,.1,0.,0.,,+", "+,.01,,.02,,,.03",
              "CONM2,12,3,,1.5", "SPC1,1,123456,1"] + PROPS
    return "\n".join(["CORD2R,7,,0.,0.,0.,0.,0.,1.,", f",{_r(math.cos(.5))},"
                      f"{_r(math.sin(.5))},0."] + lines) + "\n"


def test_a_cantilever_in_a_rotated_cd_has_the_basic_modes():
    subs = []
    for cd in ("", "7"):
        mats = nastran_matrices(parse_bulk(_cantilever(cd), "c.bdf"))
        subs.append((mats, nastran_substructure("c", mats)))
    (mb, sb), (mc, sc) = subs
    assert sb.dof_labels == sc.dof_labels
    # M is singular (lumped, no rotary inertia), K is not (clamped): the pencil (M, K), whose
    # eigenvalues 1 / omega^2 are largest for the lowest modes
    lb, vb = la.eigh(sb.M.toarray(), sb.K.toarray())
    lc, vc = la.eigh(sc.M.toarray(), sc.K.toarray())
    lb, vb, lc, vc = lb[::-1], vb[:, ::-1], lc[::-1], vc[:, ::-1]
    assert np.all(np.diff(lb[:9]) < -1e-6 * lb[0])  # distinct: the shapes are defined
    # the eight lowest omega^2, to 1e-12 of the largest (each to ~1e-11 of itself: the
    # rounding of the dense solver, cond(K) ~ 1e5)
    _close(1 / lc[:8], 1 / lb[:8], 1e-12)
    T = grid_transform(mc.ids, mc.bulk.frames).toarray()
    free = [6 * mc.ids.index(int(lab.split(":")[0])) + int(lab.split(":")[1]) - 1
            for lab in sc.dof_labels]
    Tf = T[np.ix_(free, free)]  # the clamp's grid is all removed: T stays block diagonal
    want = Tf.T @ vb[:, :8]
    got = vc[:, :8] * np.sign(np.sum(vc[:, :8] * want, axis=0))
    assert np.abs(got - want).max() < 1e-8 * np.abs(want).max()


def _plane_frame(support: list[str], cd: str) -> list[str]:
    lines = ["GRID,1,,0.,0.,0.", "GRID,2,,0.,1.,0.", "GRID,3,,1.,1.,0.",
             f"GRID,4,,1.,0.,0.,{cd}", "CBAR,1,1,1,2,0.,0.,1.", "CBAR,2,1,2,3,0.,0.,1.",
             "CBAR,3,1,3,4,0.,0.,1.", "CONM2,11,2,,2.", "CONM2,12,3,,1.",
             "SPC1,1,12,1", "SPC1,1,345,1,2,3,4"]
    return lines + support


def test_an_inclined_roller_is_the_mpc_normal_to_the_slope(tmp_path):
    a = math.radians(30.0)
    cord = ["CORD2R,5,,0.,0.,0.,0.,0.,1.,", f",{_r(math.cos(a))},{_r(math.sin(a))},0."]
    rolled = _eigenvalues(tmp_path, _plane_frame(cord + ["SPC1,1,2,4"], "5"), "cd", 6)
    mpc = _eigenvalues(tmp_path, _plane_frame([f"MPC,2,4,2,{_r(math.cos(a))},4,1,"
                                                f"{_r(-math.sin(a))}"], ""), "mpc", 6)
    _close(rolled, mpc, 1e-10)
    flat = _eigenvalues(tmp_path, _plane_frame(["SPC1,1,2,4"], ""), "flat", 6)
    assert np.abs(flat - mpc).max() > 1e-3 * mpc.max()  # the slope matters


def _ring(cd: str, support: list[str]) -> list[str]:
    n = 12
    lines = [f"GRID,{k + 1},,{_r(math.cos(2 * math.pi * k / n))},"
             f"{_r(math.sin(2 * math.pi * k / n))},0.,{cd}" for k in range(n)]
    lines += [f"CBAR,{k + 1},1,{k + 1},{(k + 1) % n + 1},0.,0.,1." for k in range(n)]
    lines += [f"CONM2,{20 + k},{k + 1},,.5" for k in range(0, n, 3)]
    return lines + ["SPC1,1,3,1,5,9"] + support


def test_a_ring_in_a_cylindrical_cd_held_radially_is_the_basic_mpcs(tmp_path):
    cord = ["CORD2C,3,,0.,0.,0.,0.,0.,1.,", ",1.,0.,0."]
    held = _eigenvalues(tmp_path, _ring("3", cord + ["SPC1,1,1,2,6", "SPC1,1,2,4"]), "cyl")
    t = [2 * math.pi * k / 12 for k in (1, 5, 3)]
    mpcs = [f"MPC,2,2,1,{_r(math.cos(t[0]))},2,2,{_r(math.sin(t[0]))}",
            f"MPC,2,6,1,{_r(math.cos(t[1]))},6,2,{_r(math.sin(t[1]))}",
            f"MPC,2,4,2,{_r(math.cos(t[2]))},4,1,{_r(-math.sin(t[2]))}"]
    _close(held, _eigenvalues(tmp_path, _ring("", mpcs), "basic"), 1e-10)


ARM = ["GRID,1,,0.,0.,0.", "GRID,2,,1.,0.,0.", "GRID,3,,1.,1.,0.", "GRID,4,,1.,1.,.5",
       "GRID,5,,1.3,1.2,.6,{cd}", "GRID,6,,1.5,1.,.9,{cd}", "GRID,7,,1.,1.5,.2,{cd}",
       "CORD2R,8,,.1,.2,.3,.5,.6,1.3,", ",1.,-.2,.4",
       "CORD2C,9,,1.,1.,0.,1.,1.,1.,", ",2.,1.,0.",
       "CBAR,1,1,1,2,0.,0.,1.", "CBAR,2,1,2,3,0.,0.,1.", "CBAR,3,1,3,4,1.,0.,0.",
       "CBAR,4,1,6,3,1", "CBAR,5,1,7,2,1",
       "CONM2,11,5,,2.,.1,0.,0.,,+", "+,.01,,.02,,,.03", "CONM2,12,6,,1.5", "CONM2,13,7,,1.",
       "SPC1,1,123456,1"]


@pytest.mark.parametrize("rigid", [
    ["RBE2,21,4,123456,5", "RBE2,22,5,123,6"],
    ["RBAR,21,4,5,123,456", "RBAR,22,5,6,123456"],
    ["RBE2,21,4,123456,5,6", "RBE3,23,,7,123456,1.,123,5,6,", ",4"],
])
def test_rigid_elements_on_grids_with_a_cd_are_those_in_basic(tmp_path, rigid):
    basic = _eigenvalues(tmp_path, [a.replace("{cd}", "") for a in ARM] + rigid, "basic")
    for cd in ("8", "9"):
        got = _eigenvalues(tmp_path, [a.replace("{cd}", cd) for a in ARM] + rigid, "cd" + cd)
        _close(got, basic, 1e-10)


@pytest.mark.parametrize("text, fragment", [
    ("GRID,1,,0.,0.,0.,3", "line 1: GRID 1: CD: no such coordinate system, got 3"),
    ("CORD2C,3,,0.,0.,0.,0.,0.,1.,\n,1.,0.,0.\nGRID,1,,0.,0.,2.,3",
     "line 3: GRID 1: CD: the grid is on the axis of its cylindrical or spherical CD system"),
    ("CORD2C,3,,0.,0.,0.,0.,0.,1.,\n,1.,0.,0.\nGRID,1,,1.,0.,0.\nCONM2,5,1,3,1.",
     "line 4: CONM2 5: CID: the system must be rectangular"),
])
def test_cd_refusals_name_the_card(text, fragment):
    with pytest.raises(BdfError) as err:
        parse_bulk(text + "\n", "c.bdf")
    assert fragment in str(err.value) and "\n" not in str(err.value), str(err.value)
