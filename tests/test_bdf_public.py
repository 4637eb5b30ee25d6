"""A public Nastran model with Nastran's own eigenvalues (tests/data/nastran/README.md names
its source, licence and the F06 table the values are copied from).

``beam_modes``: 9 CBAR and 1 CBEAM of a PBARL/PBEAML ``ROD`` section (Timoshenko shear factor
0.9, as Nastran's replacement PBAR/PBEAM prints), a tip CONM2 with inertia, lumped mass (the
CBEAM's with its torsional inertia).  Read through a case file (``type: nastran``); the ten
eigenvalues (bending pairs, torsion, axial) match MSC.Nastran 2005's to 1e-6 (its F06 prints
seven digits; measured 1.5e-7).  ``substruct run`` of the file itself is refused: its EIGRL
asks for shapes normalised to a maximum of 1 (NORM MAX), which the results would not honour.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from substruct import cli
from substruct.analysis.api import modes
from substruct.builder.model import assemble_case
from substruct.case.bdf import parse_bulk
from substruct.case.bdf_fields import BdfError
from substruct.case.loader import load_case
from substruct.models.nastran import nastran_matrices

DATA = Path(__file__).resolve().parent / "data" / "nastran"

#: beam_modes.f06, page 13, R E A L   E I G E N V A L U E S, column EIGENVALUE.
BEAM_MODES_F06 = [8.232776E+06, 8.232776E+06, 2.824056E+08, 2.824056E+08, 4.989076E+08,
                  8.021004E+08, 1.733310E+09, 1.733310E+09, 4.874295E+09, 4.874295E+09]


def test_beam_modes_reproduces_nastrans_eigenvalues():
    case = {"name": "beam_modes", "substructures": [
        {"name": "beam", "type": "nastran",
         "file": str(DATA / "beam_modes" / "beam_modes.dat")}],
        "analysis": {"modes": {"count": 10}}}
    asm = assemble_case(load_case(case)).assembly
    omega = modes(asm.M, None, asm.K, asm.A, 10).omega
    ref = np.array(BEAM_MODES_F06)
    # seven printed digits: 5e-7 of rounding, and the eigensolver's own error far below
    assert np.abs(omega ** 2 / ref - 1).max() < 1e-6


def test_running_beam_modes_itself_refuses_its_norm_max(tmp_path, capsys):
    out = tmp_path / "out"
    path = DATA / "beam_modes" / "beam_modes.dat"
    assert cli.main(["run", str(path), "--out", str(out), "--quiet", "--no-pictures"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "NORM MASS" in err and "MAX" in err, err
    assert not out.exists() or not any(out.iterdir())


BASE = ["BEGIN BULK", "MAT1,1,3.+7,1.1628+7,,7.4851-4", "GRID,1,,0.,0.,0.", "GRID,2,,1.,0.,0."]


@pytest.mark.parametrize("lines, message", [
    (["CBAR,1,1,1,2,0.,1.,0.", "PBARL,1,1,,BAR", ",1.,2."], "PBARL 1: TYPE: only the ROD"),
    (["CBEAM,1,1,1,2,0.,1.,0.", "PBEAML,1,1,,ROD", ",1.,0.,YES,1.,1."],
     "PBEAML 1: field 12: field 4 of line 2 is not read (PBEAML ROD of one constant"),
    (["CBAR,1,1,1,2,0.,1.,0.", "PBARL,1,1,MYLIB,ROD", ",1."], "PBARL 1: GROUP: only the"),
    (["CQUAD4,1,1,1,2,3,4", "GRID,3,,1.,1.,0.", "GRID,4,,0.,1.,0.", "PSHELL,1,1,.1,1",
      "PARAM,K6ROT,100."], "PARAM K6ROT: K6ROT (the drilling stiffness"),
    (["CBAR,1,1,1,2,0.,1.,0.", "PBARL,1,1,,ROD", ",1.", "EIGRL,1,,,4,,,,POINT"],
     "EIGRL 1: NORM: must be MASS or MAX"),
    (["CBAR,1,1,1,2,0.,1.,0.", "PBARL,1,1,,ROD", ",1.", "USET,U2"],
     "USET U2: ID1: a set needs a grid"),
])
def test_bad_new_cards_are_refused_naming_card_and_field(lines, message):
    with pytest.raises(BdfError, match=re.escape(message)):
        nastran_matrices(parse_bulk("\n".join(BASE + lines + ["ENDDATA"]), "bad.bdf"))


def test_pbarl_rod_is_the_pbar_nastran_prints_with_shear_factor_09():
    """A ROD PBARL gives the stiffness of a CBAR whose tip flexibility is Timoshenko's with
    ``K = 0.9``: ``L^3 / (3 E I) + L / (0.9 G A)`` (one element, clamped, end load)."""
    text = "\n".join(BASE + ["CBAR,1,1,1,2,0.,1.,0.", "PBARL,1,1,,ROD", ",.5", "ENDDATA"])
    mats = nastran_matrices(parse_bulk(text, "r.bdf"))
    K = mats.K.toarray()[6:, 6:]  # grid 2 free, grid 1 clamped
    flex = np.linalg.inv(K[np.ix_([1, 5], [1, 5])])[0, 0]
    E, G, r = 3e7, 1.1628e7, 0.5
    A, I = np.pi * r ** 2, np.pi * r ** 4 / 4
    assert abs(flex / (1 / (3 * E * I) + 1 / (0.9 * G * A)) - 1) < 1e-12
