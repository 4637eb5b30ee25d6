"""Input that MSC Nastran runs and that substruct reads with Nastran's meaning (an audit of
public decks found each refused before):

* element ids: structural elements, mass elements (CONM2) and rigid elements (RBE2, RBE3,
  RBAR) are separate id tables; a deck whose CONM2 and RBE2 reuse CBAR ids has the
  eigenvalues of the same deck renumbered (to 1e-12) and links named by card; a duplicate
  within one table is still refused, naming the table;
* a CBUSH with CID and GO or X1-X3 filled uses CID (the same stiffness as with GO/X blank);
* case control abbreviations (the first four letters or more) choose the same sets; an
  ambiguous one is refused naming the commands;
* a repeated ENDDATA is accepted, any other text after ENDDATA still refused;
* the printing and output PARAMs are read and change nothing (the same matrices); G is
  refused; the refusal of an unknown PARAM lists the one table of accepted PARAMs;
* the case control's ``AUTOSPC = NO`` is ``PARAM,AUTOSPC,NO`` (the same coordinates);
  options other than printing are refused, naming them, and so is a PARAM that disagrees;
* a set that the case control does not choose is refused naming its first card's line.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from substruct.analysis.api import modes
from substruct.builder.model import assemble_case
from substruct.builder.nastran import bulk_links, rigid_element_grids
from substruct.case.bdf import parse_bulk
from substruct.case.bdf_control import CASE_CONTROL, OUTPUT_PARAMS, PARAM_TABLE, PARAMS, \
    case_command, read_control
from substruct.case.bdf_fields import BdfError, split_bdf
from substruct.case.loader import load_case
from substruct.models.nastran import nastran_matrices, nastran_substructure


def _deck(ids: dict[str, int], head: str = "SOL 103\nCEND\nMETHOD = 1\nSPC = 1",
          extra: tuple[str, ...] = ()) -> str:
    """A clamped frame of three CBARs, a CONM2 on an arm held by an RBE2 and an RBAR; the
    ids of CONM2, RBE2 and RBAR given."""
    lines = [head, "BEGIN BULK", "EIGRL,1,,,6", "MAT1,1,2.1+11,,.3,7850.",
             "PBAR,1,1,1.-3,1.-7,2.-7,1.5-7", "GRID,1,,0.,0.,0.", "GRID,2,,1.,0.,0.",
             "GRID,3,,1.,1.,0.", "GRID,4,,1.,1.,.5", "GRID,5,,1.3,1.2,.6", "GRID,6,,1.4,1.,.7",
             "CBAR,1,1,1,2,0.,0.,1.", "CBAR,2,1,2,3,0.,0.,1.", "CBAR,3,1,3,4,1.,0.,0.",
             f"CONM2,{ids['CONM2']},5,,2.,,,,,+", "+,.01,,.02,,,.03",
             f"CONM2,{ids['CONM2b']},6,,1.",
             f"RBE2,{ids['RBE2']},4,123456,5", f"RBAR,{ids['RBAR']},5,6,123456",
             "SPC1,1,123456,1", *extra, "ENDDATA", ""]
    return "\n".join(lines)


def _eigenvalues(path: Path) -> np.ndarray:
    asm = assemble_case(load_case(path)).assembly
    return modes(asm.M, None, asm.K, asm.A, 6).omega ** 2


def test_ids_repeat_across_element_mass_and_rigid_tables(tmp_path):
    shared = tmp_path / "shared.bdf"
    shared.write_text(_deck({"CONM2": 1, "CONM2b": 2, "RBE2": 1, "RBAR": 3}))
    apart = tmp_path / "apart.bdf"
    apart.write_text(_deck({"CONM2": 101, "CONM2b": 102, "RBE2": 201, "RBAR": 202}))
    lam, ref = _eigenvalues(shared), _eigenvalues(apart)
    assert np.all(ref > 0) and np.abs(lam / ref - 1).max() < 1e-12
    bulk = parse_bulk(shared.read_text(), "shared.bdf")
    assert [m.id for m in bulk.masses] == [1, 2] and [b.id for b, _ in bulk.bars] == [1, 2, 3]
    sub = nastran_substructure("m", nastran_matrices(bulk))
    names = [link.name for link, _, _, _ in bulk_links("m", bulk, {"m": sub})]
    assert names == ["m: RBE2 1", "m: RBAR 3"]
    assert [(c, i) for c, i, _, _ in rigid_element_grids(bulk)] == [("RBE2", 1), ("RBAR", 3)]


@pytest.mark.parametrize("ids, fragment", [
    ({"CONM2": 7, "CONM2b": 7, "RBE2": 1, "RBAR": 2},
     "line 20: CONM2 7: duplicate mass element id (also CONM2 on line 18)"),
    ({"CONM2": 7, "CONM2b": 8, "RBE2": 5, "RBAR": 5},
     "line 22: RBAR 5: duplicate rigid element id (also RBE2 on line 21)"),
    ({"CONM2": 7, "CONM2b": 8, "RBE2": 5, "RBAR": 6},
     "line 24: CQUAD4 2: duplicate element id (also CBAR on line 16)"),
])
def test_duplicates_within_one_table_are_refused(ids, fragment):
    extra = ("CQUAD4,2,9,1,2,3,4",) if ids["RBAR"] == 6 else ()
    with pytest.raises(BdfError) as err:
        parse_bulk(_deck(ids, extra=extra), "d.bdf")
    assert fragment in str(err.value), str(err.value)


def _bush(x: str) -> str:
    return "\n".join(["GRID,1,,0.,0.,0.", "GRID,2,,1.,0.,0.", "GRID,3,,0.,0.,1.",
                      "CORD2R,5,,0.,0.,0.,.3,.4,.5,+", "+,1.,0.,0.",
                      f"CBUSH,1,2,1,2,{x},5", "PBUSH,2,K,1.,2.,3.,4.,5.,6.",
                      "PARAM,AUTOSPC,NO", ""])


@pytest.mark.parametrize("x", ["0.,1.,0.", "3,,", ",,1."])
def test_cbush_with_cid_uses_cid_and_not_go_or_x(x):
    ref = nastran_matrices(parse_bulk(_bush(",,"), "b.bdf")).K
    K = nastran_matrices(parse_bulk(_bush(x), "b.bdf")).K
    assert abs(ref).max() > 0 and abs(K - ref).max() == 0.0


@pytest.mark.parametrize("x, fragment", [
    ("A,,", "CBUSH 1: X1: must be a real number"),
    ("3,1.,", "CBUSH 1: X2: with GO in field 6, X2 and X3 are blank"),
])
def test_cbush_go_or_x_beside_cid_must_still_be_well_formed(x, fragment):
    with pytest.raises(BdfError, match=fragment):
        parse_bulk(_bush(x), "b.bdf")


def _control(case: str) -> dict:
    return read_control(split_bdf(f"SOL 103\nCEND\n{case}\nBEGIN BULK\nENDDATA\n", "c.bdf"))


def test_case_control_abbreviations_are_read_as_the_commands():
    full = _control("TITLE = T\nSUBTITLE = S\nLABEL = L\nMETHOD = 4\nSPC = 2\n"
                    "DISPLACEMENT(PLOT) = ALL\nSPCFORCES = ALL\nSUBCASE 1")
    short = _control("TITL = T\nSUBTI = S\nLABE = L\nMETH = 4\nSPC = 2\nDISP(PLOT) = ALL\n"
                     "SPCF = ALL\nSUBCA 1")
    assert short["METHOD"] == full["METHOD"] == 4 and short["SPC"] == full["SPC"] == 2
    assert case_command("SUBT") == "SUBTITLE" and case_command("ELFOR") == "ELFORCE"
    assert case_command("SUB") is None and case_command("SUBTITLEX") is None
    assert all(case_command(c[:4]) == c for c in CASE_CONTROL if c != "SUBCASE")


@pytest.mark.parametrize("line, fragment", [
    ("SUBC 1", "line 3: case control SUBC is ambiguous: it abbreviates SUBCASE and SUBCOM"),
    ("SUB = X", "line 3: case control SUB is not supported"),
    ("LOADS = 1", "line 3: case control LOADS is not supported"),
])
def test_short_or_ambiguous_abbreviations_are_refused(line, fragment):
    with pytest.raises(BdfError, match=fragment):
        _control(line)


def test_a_repeated_enddata_is_accepted_and_other_text_after_it_is_not():
    base = "GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nENDDATA\n"
    assert sorted(parse_bulk(base + "$ end\nENDDATA\n enddata\n", "e.bdf").grids) == [1, 2]
    with pytest.raises(BdfError, match="line 5: a card after ENDDATA would not be read, got "
                                       "'GRID,3,,0.,0.,0.'"):
        parse_bulk(base + "ENDDATA\nGRID,3,,0.,0.,0.\n", "e.bdf")


def test_output_params_are_read_and_change_nothing():
    plain = _deck({"CONM2": 1, "CONM2b": 2, "RBE2": 1, "RBAR": 3}, head="")
    ref = nastran_matrices(parse_bulk(plain, "p.bdf"))
    extra = tuple(f"PARAM,{name},NO" for name in OUTPUT_PARAMS)
    mats = nastran_matrices(parse_bulk(
        _deck({"CONM2": 1, "CONM2b": 2, "RBE2": 1, "RBAR": 3}, head="", extra=extra), "p.bdf"))
    assert abs(mats.K - ref.K).max() == 0.0 and abs(mats.M - ref.M).max() == 0.0
    assert {"OGEOM", "PRGPST", "NOFISR", "RPOSTS1", "SPARSEDR", "POST", "GRDPNT"} \
        <= set(OUTPUT_PARAMS)
    assert set(PARAMS) == {"WTMASS", "COUPMASS", "AUTOSPC", "K6ROT"}


@pytest.mark.parametrize("card, fragment", [
    ("PARAM,G,.05", "line 1: PARAM G: PARAM G is not supported: the structural damping G is "
                    "not used"),
    ("PARAM,LGDISP,1", "line 1: PARAM LGDISP: PARAM LGDISP is not supported (read: "
                       + ", ".join(PARAM_TABLE) + ")"),
])
def test_params_that_change_results_are_refused_listing_the_table(card, fragment):
    with pytest.raises(BdfError) as err:
        parse_bulk(card + "\nGRID,1,,0.,0.,0.\n", "p.bdf")
    assert fragment in str(err.value), str(err.value)


@pytest.mark.parametrize("case", ["AUTOSPC = NO", "AUTOSPC(PRINT,NOPUNCH) = NO",
                                  "AUTO = NO"])
def test_case_control_autospc_no_is_param_autospc_no(case):
    ids = {"CONM2": 1, "CONM2b": 2, "RBE2": 1, "RBAR": 3}
    by_param = parse_bulk(_deck(ids, extra=("PARAM,AUTOSPC,NO",)), "a.bdf")
    by_case = parse_bulk(_deck(ids, head=f"SOL 103\nCEND\nMETHOD = 1\nSPC = 1\n{case}"),
                         "a.bdf")
    default = parse_bulk(_deck(ids), "a.bdf")
    assert by_param.autospc is False and by_case.autospc is False and default.autospc is True
    n = [nastran_substructure("a", nastran_matrices(b), autospc=b.autospc).n_dof
         for b in (by_param, by_case, default)]
    assert n[0] == n[1] == 30 > n[2]  # 6 grids, grid 1 clamped


@pytest.mark.parametrize("case, extra, fragment", [
    ("AUTOSPC(EPS=1.E-8) = NO", (), "line 5: AUTOSPC: the AUTOSPC option EPS is not "
                                    "supported (read: PRINT, NOPRINT, PUNCH, NOPUNCH"),
    ("AUTOSPC = MAYBE", (), "line 5: AUTOSPC: AUTOSPC = YES or NO, got 'MAYBE'"),
    ("AUTOSPC = YES", ("PARAM,AUTOSPC,NO",), "line 25: PARAM AUTOSPC: V1: PARAM,AUTOSPC and "
                                             "the case control's AUTOSPC = YES (line 5) "
                                             "disagree"),
])
def test_autospc_options_and_disagreement_are_refused(case, extra, fragment):
    ids = {"CONM2": 1, "CONM2b": 2, "RBE2": 1, "RBAR": 3}
    text = _deck(ids, head=f"SOL 103\nCEND\nMETHOD = 1\nSPC = 1\n{case}", extra=extra)
    with pytest.raises(BdfError) as err:
        parse_bulk(text, "a.bdf")
    assert fragment in str(err.value), str(err.value)


@pytest.mark.parametrize("extra, fragment", [
    (("SPC,2,3,123456", "SPC1,2,1,4"),
     "line 24: SPC 2: SPC set 2 is not chosen by the case control (SPC = 1) and would be "
     "unused, got 2"),
    (("MPC,7,3,1,1.,4,1,-1.",),
     "line 24: MPC 7: MPC sets [7] are not chosen by the case control (no MPC = ...) and "
     "would be unused, got 7"),
])
def test_an_unchosen_set_is_refused_naming_its_first_card(extra, fragment):
    ids = {"CONM2": 1, "CONM2b": 2, "RBE2": 1, "RBAR": 3}
    with pytest.raises(BdfError) as err:
        parse_bulk(_deck(ids, extra=extra), "s.bdf")
    assert fragment in str(err.value), str(err.value)


def test_a_chosen_set_missing_names_the_case_control_line():
    with pytest.raises(BdfError, match="s.bdf: line 3: METHOD: the case control's METHOD names "
                                       "no EIGRL"):
        parse_bulk(_deck({"CONM2": 1, "CONM2b": 2, "RBE2": 1, "RBAR": 3},
                         head="SOL 103\nCEND\nMETHOD = 9\nSPC = 1"), "s.bdf")
