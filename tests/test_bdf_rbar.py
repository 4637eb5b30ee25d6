"""RBAR, the rigid bar of Nastran, against the RBE2 it equals and against MSC Nastran.

* an RBAR with ``CNA = 123456`` makes the rows of an RBE2 from GA to GB: a frame with two
  RBARs has the eigenvalues of the same frame with RBE2s to 1e-10 (relative), and so does
  ``CNB = 123456`` (the independent grid at B) and dependent components chosen by CMB;
* independent components split between the ends (``CNA = 123``, ``CNB = 456``) make the
  same rigid bar (other rows, the same constrained space): the same eigenvalues to 1e-10;
* CNA and CNB that do not determine the bar's rigid motion, six components in all that are
  not six, a component both independent and dependent at one grid: refused, naming the card;
* the BAH wing of pyNastran's models (tests/data/nastran/README.md), whose tail is four
  RBARs: its six elastic eigenvalues are MSC Nastran's to 1e-6.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from substruct import cli
from substruct.analysis.api import modes
from substruct.builder.model import assemble_case
from substruct.case.loader import load_case

DATA = Path(__file__).resolve().parent / "data" / "nastran" / "bah_plane"


def _frame(rigid: list[str]) -> str:
    """A clamped frame of CBARs with masses on an arm joined by the ``rigid`` cards (grid 4 at
    the frame's tip, 5 and 6 on the arm, 6 also tied back to grid 3 by a CBAR)."""
    lines = ["SOL 103", "CEND", "METHOD = 1", "SPC = 1", "BEGIN BULK", "EIGRL,1,,,8",
             "MAT1,1,2.1+11,,.3,7850.", "PBAR,1,1,1.-3,1.-7,2.-7,1.5-7",
             "GRID,1,,0.,0.,0.", "GRID,2,,1.,0.,0.", "GRID,3,,1.,1.,0.", "GRID,4,,1.,1.,.5",
             "GRID,5,,1.3,1.2,.6", "GRID,6,,1.5,1.,.9",
             "CBAR,1,1,1,2,0.,0.,1.", "CBAR,2,1,2,3,0.,0.,1.", "CBAR,3,1,3,4,1.,0.,0.",
             "CBAR,4,1,6,3,0.,0.,1.",
             "CONM2,11,5,,2.,.1,0.,0.,,+", "+,.01,,.02,,,.03", "CONM2,12,6,,1.5",
             "SPC1,1,123456,1"]
    return "\n".join(lines + rigid + ["ENDDATA", ""])


def _eigenvalues(tmp_path: Path, text: str, name: str) -> np.ndarray:
    path = tmp_path / f"{name}.bdf"
    path.write_text(text)
    asm = assemble_case(load_case(path)).assembly
    return modes(asm.M, None, asm.K, asm.A, 8).omega ** 2


RBE2 = ["RBE2,21,4,123456,5", "RBE2,22,5,123456,6"]


@pytest.mark.parametrize("rbar", [
    ["RBAR,21,4,5,123456", "RBAR,22,5,6,123456"],                 # CMB blank: all six of GB
    ["RBAR,21,5,4,,123456", "RBAR,22,6,5,,123456,,"],             # independent at GB
    ["RBAR,21,4,5,123,456", "RBAR,22,5,6,123456,,,123456,2.3-5"],  # split ends; ALPHA
    ["RBAR,21,4,5,12,3456", "RBAR,22,5,6,123456,,0,0"],           # split the other way
])
def test_rbar_gives_the_eigenvalues_of_the_equivalent_rbe2(tmp_path, rbar):
    ref = _eigenvalues(tmp_path, _frame(RBE2), "rbe2")
    lam = _eigenvalues(tmp_path, _frame(rbar), "rbar")
    assert np.all(ref > 0)
    assert np.abs(lam / ref - 1).max() < 1e-10, lam / ref - 1


def test_rbar_dependent_components_are_cmb_only(tmp_path):
    """CMB = 123: GB's translations follow the bar, its rotations are its own (held by the
    CBAR to grid 3), as an RBE2 of CM 123; the eigenvalues differ from the fully rigid
    bar's."""
    partial = ["RBE2,21,4,123456,5", "RBE2,22,5,123,6"]
    ref = _eigenvalues(tmp_path, _frame(partial), "rbe2")
    lam = _eigenvalues(tmp_path, _frame(["RBAR,21,4,5,123456", "RBAR,22,5,6,123456,,,123"]),
                       "rbar")
    full = _eigenvalues(tmp_path, _frame(RBE2), "full")
    assert np.abs(lam / ref - 1).max() < 1e-10
    assert np.abs(lam / full - 1).max() > 1e-3


@pytest.mark.parametrize("card, fragment", [
    ("RBAR,21,4,5,123,123", "RBAR 21: CNA: CNA 123 and CNB 123 do not determine the bar's "
                            "rigid motion"),
    ("RBAR,21,4,5,123,12", "RBAR 21: CNA: CNA and CNB hold six independent components in "
                           "all, got '123+12'"),
    ("RBAR,21,4,5,123456,,1", "RBAR 21: CMA: a component is both independent and dependent "
                              "at the same grid, got '1'"),
    ("RBAR,21,4,4,123456", "RBAR 21: GB: GA and GB are the same grid, got 4"),
    ("RBAR,21,4,5,123456,,,,A", "RBAR 21: ALPHA: must be a real number"),
])
def test_bad_rbar_is_refused_naming_the_card(tmp_path, capsys, card, fragment):
    path = tmp_path / "bad.bdf"
    path.write_text(_frame([card]))
    assert cli.main(["run", str(path), "--out", str(tmp_path / "o"), "--quiet",
                     "--no-pictures"]) == 2
    err = capsys.readouterr().err
    line = _frame([card]).splitlines().index(card) + 1
    assert f"bad.bdf: line {line}: {fragment}" in err, err


def test_bah_wing_with_its_rbar_tail_gives_nastrans_eigenvalues():
    table = (DATA / "bah_plane_excerpt.f06").read_text()
    ref = np.array([float(m.group(1)) for m in
                    re.finditer(r"^\s+\d+\s+\d+\s+([-+.\dE]+)\s", table, re.M)])
    assert ref.shape == (8,) and ref[2] == 2.377467E+02
    asm = assemble_case(load_case(DATA / "bah_plane_modes.bdf")).assembly
    lam = modes(asm.M, None, asm.K, asm.A, 8).omega ** 2
    assert np.all(np.abs(lam[:2]) < 1e-9 * ref[2]) and np.all(np.abs(ref[:2]) < 1e-9 * ref[2])
    rel = lam[2:] / ref[2:] - 1
    assert np.abs(rel).max() < 1e-6, rel  # the F06's seven digits: 2e-7 measured
