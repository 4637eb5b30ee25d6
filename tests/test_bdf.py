"""Nastran bulk data in, against independent references.

* the same frame written as bulk data (small, large and free field) and as a ``type: frame``
  case gives the same stiffness and mass matrices to round-off (COUPMASS; the lumped mass is
  Nastran's: half of each element on the translations of its ends);
* a cantilever of CBARs against the Euler-Bernoulli closed form ``beta_n L = 1.8751, 4.6941``
  in both planes, run as ``substruct run MODEL.bdf`` (the HDF5 result's ``omega``); WTMASS
  scales the frequencies by ``1/sqrt(WTMASS)``; CBEAM's shear factors soften a thick beam as
  the Timoshenko stiffness says;
* a CONM2 with offset and inertia against the 6 x 6 matrix computed by hand (and the kinetic
  energy of a rigid motion);
* RBE2, RBE3 and MPC cards give the rows of :mod:`substruct.assembly.links`;
* bad files: one line naming file, line, card and id, exit 2, nothing written.
"""

from __future__ import annotations

import numpy as np
import pytest

from substruct import cli
from substruct.assembly import assemble
from substruct.assembly.links import NodeRef, interpolation_link, link_constraints, mpc, \
    rigid_link
from substruct.builder.model import assemble_case
from substruct.case.bdf import parse_bulk
from substruct.case.bdf_fields import BdfError, nastran_real
from substruct.case.loader import load_case
from substruct.io.result_reader import load
from substruct.models.nastran import conm2_matrix, nastran_matrices, nastran_substructure

E, NU, RHO = 2.1e11, 0.3, 7850.0
A, I1, I2, J = 4e-4, 2e-8, 5e-8, 3e-8


def small(*fields) -> str:
    """A small-field line."""
    return "".join(f"{str(f):<8}"[:8] for f in fields).rstrip()


def cantilever(n: int, extra: str = "", mass: str = "", length: float = 1.0) -> str:
    lines = ["SOL 103", "CEND", "METHOD = 1", "SPC = 1", "BEGIN BULK",
             small("EIGRL", 1, "", "", 4), small("MAT1", 1, "2.1+11", "", ".3", "7850.")]
    for k in range(n + 1):
        lines.append(small("GRID", k + 1, "", f"{k * length / n:.6f}", "0.", "0."))
    for k in range(n):
        lines.append(small("CBAR", k + 1, 1, k + 1, k + 2, "0.", "1.", "0."))
    lines += [small("PBAR", 1, 1, "4.-4", "2.-8", "5.-8", "3.-8"), small("SPC1", 1, 123456, 1)]
    lines += [m for m in (mass, extra) if m]
    return "\n".join(lines + ["ENDDATA", ""])


def run_bdf(tmp_path, text: str, name: str = "model.bdf"):
    path = tmp_path / name
    path.write_text(text)
    out = tmp_path / "out"
    code = cli.main(["run", str(path), "--out", str(out), "--quiet", "--no-pictures"])
    return code, out


def test_numbers_and_fields_follow_nastran():
    assert nastran_real("7.85-9") == 7.85e-9 and nastran_real("2.1+11") == 2.1e11
    assert nastran_real("1.D3") == 1e3 and nastran_real(".5E-2") == 5e-3
    assert nastran_real("1") is None  # a real needs its decimal point
    free = "GRID,7,,1.5,-2.,3.25\nCBAR,1,1,7,8,0.,0.,1.\n,,,,.1\nGRID,8,,2.,0.,0.\n"
    big = ("GRID*   " + "7".ljust(16) + " " * 16 + "1.5".ljust(16) + "-2.".ljust(16) +
           "\n*       " + "3.25".ljust(16) + "\n" + small("CBAR", 1, 1, 7, 8, "0.", "0.", "1.")
           + "\n" + small("", "", "", "", ".1") + "\n" + small("GRID", 8, "", "2.", "0.", "0."))
    for text in (free, big):
        bulk = parse_bulk(text + "\nPBAR,1,1,1.,1.,1.,1.\nMAT1,1,1.,,.3\n", "t.bdf")
        assert np.array_equal(bulk.grids[7], [1.5, -2.0, 3.25])
        assert bulk.bars[0][0].wa == (0.0, 0.1, 0.0) and bulk.bars[0][0].v == (0.0, 0.0, 1.0)


def test_bdf_and_frame_case_give_the_same_matrices(tmp_path):
    """A 3D frame with a pinned end, two orientations and a tip mass: BDF (COUPMASS) against
    the frame case (consistent Euler-Bernoulli mass), element by element."""
    xyz = {1: (0, 0, 0), 2: (0, 0, 1.5), 3: (1.2, 0.3, 1.5), 4: (1.2, 0.3, 0)}
    bdf = ["BEGIN BULK", "PARAM,COUPMASS,1", "MAT1,1,2.1+11,8.1+10,,7850.",
           "PBAR,1,1,4.-4,2.-8,5.-8,3.-8", "SPC1,1,123456,1,4", "CONM2,9,3,,12.5"]
    bdf += [f"GRID,{k},,{x:.1f},{y:.1f},{z:.1f}" for k, (x, y, z) in xyz.items()]
    bdf += ["CBAR,1,1,1,2,1.,0.,0.", "CBAR,2,1,2,3,0.,0.,1.", ",,5", "CBAR,3,1,3,4,0.2,1.,0."]
    (tmp_path / "f.bdf").write_text("\n".join(bdf + ["EIGRL,1,,,3", "ENDDATA"]))
    members = [{"nodes": [1, 2], "orientation": [1, 0, 0]},
               {"nodes": [2, 3], "orientation": [0, 0, 1], "pin_b": "5"},
               {"nodes": [3, 4], "orientation": [0.2, 1, 0]}]
    frame = {"name": "f", "substructures": [{
        "name": "f", "type": "frame", "nodes": {k: list(v) for k, v in xyz.items()},
        "materials": {"s": {"E": 2.1e11, "G": 8.1e10, "rho": 7850.0}},
        "sections": {"p": {"A": A, "Iy": I2, "Iz": I1, "J": J}},
        "members": [{**m, "section": "p", "material": "s"} for m in members],
        "supports": {1: "123456", 4: "123456"}, "node_masses": {3: 12.5}}],
        "analysis": {"modes": {"count": 3}}}
    a = assemble_case(load_case(tmp_path / "f.bdf")).assembly
    b = assemble_case(load_case(frame)).assembly
    assert [s.split(":")[0] for s in a.dof_labels] == [s.split(":")[0] for s in b.dof_labels]
    for X, Y in ((a.K, b.K), (a.M, b.M)):
        assert abs(X - Y).max() <= 1e-13 * abs(Y).max()


def test_cantilever_against_the_closed_form(tmp_path):
    code, out = run_bdf(tmp_path, cantilever(20, mass="PARAM,COUPMASS,1"))
    assert code == 0
    omega = np.sort(load(out / "model.h5").modes.omega)
    base = np.sqrt(E * np.array([I1, I2]) / (RHO * A))
    ref = np.sort(np.concatenate([1.87510407**2 * base, 4.69409113**2 * base]))
    assert np.abs(omega / ref - 1).max() < 1e-5  # h^4: (1/20)^4 ~ 6e-6
    # lumped mass (Nastran's default) converges like h^2 to the same limit
    lumped = [np.sort(assemble_modes(cantilever(n)))[0] / ref[0] - 1 for n in (10, 20)]
    assert 3.5 < lumped[0] / lumped[1] < 4.5 and abs(lumped[1]) < 2e-3


def assemble_modes(text: str, count: int = 4) -> np.ndarray:
    from substruct.analysis.api import modes

    bulk = parse_bulk(text, "m.bdf")
    sub = nastran_substructure("m", nastran_matrices(bulk))
    return modes(sub.M, None, sub.K, None, count).omega


def test_wtmass_scales_every_mass():
    tip = small("CONM2", 99, 9, "", "3.5")
    plain = assemble_modes(cantilever(8, extra=tip))
    scaled = assemble_modes(cantilever(8, extra=tip + "\nPARAM,WTMASS,0.25"))
    assert np.abs(scaled / (plain * 2.0) - 1).max() < 1e-12


def test_cbeam_shear_factor_one_softens_as_timoshenko():
    """A pinned-pinned thick CBEAM: one element's static stiffness carries the shear term
    ``phi = 12 E I / (G A L^2)`` (PBEAM K1 = K2 = 1): the tip deflection under a unit end
    load of a cantilever element is ``L^3/(3EI) + L/(GA)``."""
    L, G = 0.3, E / (2 * (1 + NU))
    text = "\n".join(["GRID,1,,0.,0.,0.", f"GRID,2,,{L},0.,0.", "CBEAM,1,1,1,2,0.,1.,0.",
                      "PBEAM,1,1,4.-4,2.-8,5.-8,,3.-8", "MAT1,1,2.1+11,,.3,7850.",
                      "SPC1,1,123456,1"])
    sub = nastran_substructure("b", nastran_matrices(parse_bulk(text, "b.bdf")))
    flex = np.linalg.inv(sub.K.toarray())
    k = sub.dof_labels.index("2:2")
    assert flex[k, k] == pytest.approx(L**3 / (3 * E * I1) + L / (G * A), rel=1e-12)


def test_conm2_offset_and_inertia_by_hand():
    m, (rx, ry, rz) = 3.0, (0.1, -0.2, 0.4)
    I11, I21, I22, I31, I32, I33 = 2.0, 0.1, 3.0, 0.2, -0.3, 4.0
    text = "\n".join(["GRID,5,,1.,2.,3.", f"CONM2,7,5,,{m},{rx},{ry},{rz}",
                      f",{I11},{I21},{I22},{I31},{I32},{I33}", "PARAM,AUTOSPC,NO"])
    M = nastran_matrices(parse_bulk(text, "m.bdf")).M.toarray()
    hand = np.zeros((6, 6))
    hand[:3, :3] = m * np.eye(3)
    # u_cg = u + theta x r: ux couples with +rz thy and -ry thz, and cyclic
    hand[0, 4], hand[0, 5], hand[1, 3], hand[1, 5], hand[2, 3], hand[2, 4] = \
        m * rz, -m * ry, -m * rz, m * rx, m * ry, -m * rx
    hand[3:, :3] = hand[:3, 3:].T
    hand[3, 3] = I11 + m * (ry**2 + rz**2)
    hand[4, 4] = I22 + m * (rx**2 + rz**2)
    hand[5, 5] = I33 + m * (rx**2 + ry**2)
    hand[3, 4] = hand[4, 3] = -I21 - m * rx * ry
    hand[3, 5] = hand[5, 3] = -I31 - m * rx * rz
    hand[4, 5] = hand[5, 4] = -I32 - m * ry * rz
    assert np.abs(M - hand).max() < 1e-14 * np.abs(hand).max()
    # the same mass given with CID = -1 (the centre of gravity in basic)
    text2 = text.replace(f"CONM2,7,5,,{m},{rx},{ry},{rz}",
                         f"CONM2,7,5,-1,{m},{1 + rx},{2 + ry},{3 + rz}")
    M2 = nastran_matrices(parse_bulk(text2, "m.bdf")).M.toarray()
    assert np.abs(M2 - hand).max() < 1e-12 * np.abs(hand).max()
    # kinetic energy of a rigid motion: m |v_cg|^2 + w^T Jcg w
    v, w = np.array([0.3, -1.0, 0.5]), np.array([0.7, 0.2, -0.4])
    Jcg = np.array([[I11, -I21, -I31], [-I21, I22, -I32], [-I31, -I32, I33]])
    vcg = v + np.cross(w, [rx, ry, rz])
    q = np.concatenate([v, w])
    assert q @ M @ q == pytest.approx(m * vcg @ vcg + w @ Jcg @ w, rel=1e-13)
    assert np.allclose(conm2_matrix(m, np.array([rx, ry, rz]), Jcg), hand, rtol=0,
                       atol=1e-14 * np.abs(hand).max())


def test_rigid_elements_and_mpc_are_the_library_rows(tmp_path):
    grids = {1: (0.0, 0.0, 0.0), 2: (1.0, 0.0, 0.0), 3: (1.0, 1.0, 0.0), 4: (0.0, 1.0, 0.2),
             5: (0.5, 0.4, 0.7), 6: (2.0, 0.0, 0.0), 7: (0.5, 0.4, 0.9)}
    lines = ["BEGIN BULK", "MAT1,1,2.1+11,,.3,7850.", "PBAR,1,1,1.-3,1.-7,2.-7,1.-7",
             "PARAM,AUTOSPC,NO", "EIGRL,1,,,2"]
    lines += [f"GRID,{k},,{x},{y},{z}" for k, (x, y, z) in grids.items()]
    lines += ["CBAR,1,1,1,2,0.,0.,1.", "CBAR,2,1,2,3,0.,0.,1.", "CBAR,3,1,3,4,0.,0.,1.",
              "CBAR,4,1,4,1,0.,0.,1.", "CBAR,5,1,2,6,0.,0.,1.", "CBAR,6,1,5,6,0.,0.,1.",
              "RBE2,10,6,1235,5", "RBE3,11,,7,123456,2.,123,1,2", ",3,4",
              "MPC,1,3,6,1.,4,6,-.5"]
    path = tmp_path / "links.bdf"
    path.write_text("\n".join(lines + ["ENDDATA"]))
    asm = assemble_case(load_case(path)).assembly
    bulk = parse_bulk(path.read_text(), "links.bdf")
    sub = nastran_substructure("links", nastran_matrices(bulk))
    n = lambda g: NodeRef("links", {"node": g})  # noqa: E731
    links = [rigid_link([sub], n(6), [n(5)], "1235"),
             interpolation_link([sub], n(7), [n(1), n(2), n(3), n(4)], [2.0] * 4, "123456",
                                "123"),
             mpc([sub], [(n(3), "6", 1.0), (n(4), "6", -0.5)])]
    ref = assemble([sub], [], link_constraints(links)).A
    assert ref.shape == asm.A.shape and abs(ref - asm.A).max() < 1e-15 * abs(ref).max()


@pytest.mark.parametrize("text, fragment", [
    ("GRID,1,,0.,0.,0.\nCQUAD8,3,1,1,2,3,4", "line 2: CQUAD8 3: card CQUAD8 is not supported"),
    ("GRID,1,,0.,0.,0.\nGRID,1,,1.,0.,0.", "line 2: GRID 1: duplicate grid id (also GRID on "
                                            "line 1)"),
    ("GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nCBAR,4,7,1,2,0.,1.,0.",
     "line 3: CBAR 4: PID: no PBAR or PBARL of that id, got 7"),
    ("GRID,1,,0,0.,0.", "line 1: GRID 1: X1: must be a real number with a decimal point"),
    ("SOL 103\nCEND\nSPC = 1\nBEGIN BULK\nGRID,1,,0.,0.,0.\nSPC1,2,1,1",
     "SPC: the case control chooses SPC set 1, which the bulk data does not have"),
    ("GRID,1,,0.,0.,0.,3", "line 1: GRID 1: CD: no such coordinate system, got 3"),
    ("GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nGRID,3,,0.,1.,0.\nGRID,4,,1.,1.,0.\n"
     "CROD,1,1,1,2\nCROD,2,1,2,3\nPROD,1,1,1.\nMAT1,1,1.,,.3\nRBE2,8,1,123,4\n"
     "RBE3,9,,4,12,1.,123,1,2,3\nEIGRL,1,,,2",
     "line 10: RBE3 9: model@4:ux is already dependent in model: "
     "RBE2 8"),
    ("GRID,1,,0.,0.,0.\nRBE3,5,,1,123456,1.,123,1\nPARAM,LGDISP,1",
     "line 3: PARAM LGDISP: PARAM LGDISP is not supported"),
])
def test_bad_bulk_data_is_one_line(tmp_path, capsys, text, fragment):
    code, out = run_bdf(tmp_path, text + "\n")
    err = capsys.readouterr().err.strip()
    assert code == 2 and "\n" not in err and "Traceback" not in err
    assert err.startswith(f"substruct: error: {tmp_path / 'model.bdf'}: "), err  # as given
    assert fragment in err, err
    assert not out.exists() or not any(out.iterdir())


def test_a_huge_file_is_refused_from_its_size(tmp_path, capsys):
    path = tmp_path / "huge.bdf"
    with open(path, "wb") as f:
        f.truncate(5 * 10**9)  # sparse: nothing is written
    assert cli.main(["run", str(path), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "a bulk data file of 5000000000 bytes, more than the" in err


def test_rbe3_collinear_for_a_rotation_names_the_card():
    text = "\n".join(["GRID,1,,0.,0.,0.", "GRID,2,,1.,0.,0.", "GRID,3,,2.,0.,0.",
                      "GRID,4,,.5,0.,0.", "CROD,1,1,1,2", "CROD,2,1,2,3", "PROD,1,1,1.",
                      "MAT1,1,1.,,.3", "RBE3,9,,4,123456,1.,123,1,2,", ",3"])
    bulk = parse_bulk(text, "r.bdf")
    from substruct.builder.nastran import bulk_links

    sub = nastran_substructure("r", nastran_matrices(bulk))
    with pytest.raises(BdfError, match=r"r.bdf: line 9: RBE3 9: REFC: .*component rx"):
        bulk_links("r", bulk, {"r": sub})
