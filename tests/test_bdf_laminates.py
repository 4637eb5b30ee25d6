"""PCOMP against the PSHELL it is equivalent to and against classical lamination's closed
forms; PBEAM's shear factors and end stations; SPCADD; MAT1 with E, G and NU all given."""

from __future__ import annotations

import re

import numpy as np
import pytest

from substruct.case.bdf import parse_bulk
from substruct.case.bdf_cards import Mat1
from substruct.case.bdf_fields import BdfError, split_bdf
from substruct.case.bdf_pcomp import laminate, read_pcomp
from substruct.models.nastran import nastran_matrices

GRIDS = ["GRID,1,,0.,0.,0.", "GRID,2,,1.,0.,0.", "GRID,3,,1.2,.9,.1", "GRID,4,,-.1,1.1,0.",
         "GRID,5,,2.,.2,0."]
SHELLS = ["CQUAD4,1,7,1,2,3,4", "CTRIA3,2,7,2,5,3"]
MAT = "MAT1,1,2.1+11,,.3,7850."


def matrices(lines: list[str], coupled: bool = False):
    head = ["BEGIN BULK"] + (["PARAM,COUPMASS,1"] if coupled else [])
    mats = nastran_matrices(parse_bulk("\n".join(head + lines + ["ENDDATA"]), "t.bdf"))
    return mats.K.toarray(), mats.M.toarray()


def assert_same(a, b, tol=1e-13):
    assert np.abs(a - b).max() <= tol * np.abs(b).max(), np.abs(a - b).max() / np.abs(b).max()


@pytest.mark.parametrize("coupled", [False, True])
@pytest.mark.parametrize("pcomp", [
    ["PCOMP,7", ",1,.004"],                                   # one ply
    ["PCOMP,7,,", ",1,.0004,,,,.0012", ",,.0016,30.,YES,1,.0008"],  # 4 plies, blanks repeat
    ["PCOMP,7,,,,,,,SYM", ",1,.0015,45.,,1,.0005,-45."],    # the lower half of 4
])
def test_pcomp_of_isotropic_plies_is_the_pshell_of_their_thickness(pcomp, coupled):
    """Plies of one MAT1 summing to 4 mm: K and M equal the PSHELL's (T = 4 mm, MID1 = MID2
    = MID3, 12I/T^3 = 1, TS/T = 5/6: a Reissner-Mindlin plate) to round-off, lumped and
    coupled, on a warped quadrilateral and a triangle."""
    ref = matrices([MAT, "PSHELL,7,1,.004,1,,1"] + GRIDS + SHELLS, coupled)
    got = matrices([MAT] + pcomp + GRIDS + SHELLS, coupled)
    assert_same(got[0], ref[0])
    assert_same(got[1], ref[1])


def test_pcomp_nsm_and_mid3_and_a_sandwich_match_the_lamination_closed_forms():
    """A symmetric sandwich (faces of material 2, thickness f, on a core of material 1,
    thickness 2c): A11 = sum Q t, D11 = 2/3 (Q_f ((c+f)^3 - c^3) + Q_c c^3) (classical
    lamination), mass per area sum rho t + NSM."""
    E1, nu1, r1, E2, nu2, r2, c, f = 1e9, .25, 100., 7e10, .33, 2700., .01, .001
    card = split_bdf("BEGIN BULK\nPCOMP,7,,.5\n,2,.001,,,1,.02\n,2,.001\nENDDATA", "s").cards[0]
    mats = [Mat1(2, E2, E2 / (2 * (1 + nu2)), r2, 1), Mat1(1, E1, E1 / (2 * (1 + nu1)), r1, 1),
            Mat1(2, E2, E2 / (2 * (1 + nu2)), r2, 1)]
    T, (Em, num), (Eb, nub), rho, coupling, shear = laminate(read_pcomp(card), mats)
    q1, q2 = E1 / (1 - nu1 ** 2), E2 / (1 - nu2 ** 2)
    a11 = q1 * 2 * c + q2 * 2 * f
    a12 = nu1 * q1 * 2 * c + nu2 * q2 * 2 * f
    d11 = 2 / 3 * (q2 * ((c + f) ** 3 - c ** 3) + q1 * c ** 3)
    d12 = 2 / 3 * (nu2 * q2 * ((c + f) ** 3 - c ** 3) + nu1 * q1 * c ** 3)
    assert T == pytest.approx(2 * c + 2 * f, rel=1e-15)
    assert Em / (1 - num ** 2) * T == pytest.approx(a11, rel=1e-13)
    assert num == pytest.approx(a12 / a11, rel=1e-13)
    assert Eb / (1 - nub ** 2) * T ** 3 / 12 == pytest.approx(d11, rel=1e-13)
    assert nub == pytest.approx(d12 / d11, rel=1e-13)
    assert rho * T == pytest.approx(r1 * 2 * c + r2 * 2 * f, rel=1e-13)
    assert coupling < 1e-15
    G1, G2 = E1 / (2 * (1 + nu1)), E2 / (2 * (1 + nu2))
    assert shear == pytest.approx(5 / 6 * (G1 * 2 * c + G2 * 2 * f), rel=1e-13)
    # the same through a model: mass per area of the sandwich plus NSM, lumped on 4 corners
    text = ["MAT1,1,1.+9,,.25,100.", "MAT1,2,7.+10,,.33,2700.", "PCOMP,7,,.5",
            ",2,.001,,,1,.02", ",2,.001", "PSHELL,8,1,.01,1,,1,.9"] + GRIDS[:4] + SHELLS[:1]
    _, M = matrices(text)
    area = 0.5 * np.linalg.norm(np.cross([1.2, .9, .1], [-1.1, 1.1, 0.]))
    assert M.trace() / 3 == pytest.approx((r1 * 2 * c + r2 * 2 * f + .5) * area, rel=1e-12)


@pytest.mark.parametrize("cards, message", [
    (["PCOMP,7,-.001", ",1,.004"], "PCOMP 7: Z0: the laminate couples membrane and bending"),
    (["MAT1,2,7.+10,,.33,2700.", "PCOMP,7", ",1,.004,,,2,.001"],
     "PCOMP 7: Z0: the laminate couples"),                    # unsymmetric stack
    (["PCOMP,7,,,,,,,SMEAR", ",1,.004"], "PCOMP 7: LAM: LAM blank (all plies) or SYM"),
    (["PCOMP,7", ",1,.004,,,9,.001"], "PCOMP 7: MID2: no MAT1 of that id"),
    (["PCOMP,7", ",1,0."], "PCOMP 7: T1: must be positive"),
    (["PCOMP,7", ",1,.004,,MAYBE"], "PCOMP 7: SOUT1: must be YES or NO"),
    (["PCOMP,7"], "PCOMP 7: MID1: a PCOMP needs at least one ply"),
    (["PSHELL,7,1,.004,1,,1", ",,,2"], "PSHELL 7: MID4: MID4 is not supported"),
    (["PSHELL,7,1,.004,1,,5"], "PSHELL 7: MID3: no MAT1 of that id"),
])
def test_bad_laminates_are_refused_naming_the_field(cards, message):
    with pytest.raises(BdfError, match=re.escape(message)):
        matrices([MAT] + cards + GRIDS + SHELLS)


BEAM = ["MAT1,1,2.1+11,8.+10,,7850.", "GRID,1,,0.,0.,0.", "GRID,2,,2.,0.,0.",
        "CBEAM,1,3,1,2,0.,1.,0.", "SPC1,1,123456,1"]


def tip_flexibility(pbeam: list[str]) -> tuple[float, float]:
    """Tip deflection per unit tip force of a one-element cantilever, in plane 1 (along the
    orientation vector, y) and plane 2 (z)."""
    K, _ = matrices(BEAM + pbeam)
    Kf = K[6:, 6:]  # grid 2
    return (np.linalg.inv(Kf[np.ix_([1, 5], [1, 5])])[0, 0],
            np.linalg.inv(Kf[np.ix_([2, 4], [2, 4])])[0, 0])


def test_pbeam_shear_factors_k1_k2_act_in_their_planes():
    """Timoshenko's cantilever: w = L^3 / (3 E I_i) + L / (K_i G A); K = 0 drops the shear
    term (Euler-Bernoulli), blank K is 1."""
    E, G, L, A, I1, I2 = 2.1e11, 8e10, 2.0, 4e-3, 2e-6, 5e-6
    head = "PBEAM,3,1,4.-3,2.-6,5.-6,,1.-6"
    cases = [([head, ",,,,,,,,", ",.6,.8"], .6, .8), ([head, ",,,,,,,,", ",0.,.5"], 0, .5),
             ([head], 1.0, 1.0)]
    for card, k1, k2 in cases:
        w1, w2 = tip_flexibility(card)
        for w, I, k in ((w1, I1, k1), (w2, I2, k2)):
            ref = L ** 3 / (3 * E * I) + (L / (k * G * A) if k else 0.0)
            assert abs(w / ref - 1) < 1e-12, (card, w, ref)


def test_pbeam_end_b_station_within_a_tenth_of_a_percent_is_the_mean_section():
    """An end-B station (SO YES with its stress points, or NO) differing by 0.05% reads as the
    mean section: the same matrices as one PBEAM of the mean values; a blank end-B field
    takes end A's value."""
    ref = tip_flexibility(["PBEAM,3,1,4.-3,2.0005-6,5.-6,,1.-6", ",,,,,,,,", ",.85,.85"])
    for card in (["PBEAM,3,1,4.-3,2.-6,5.-6,,1.-6", ",.1,.1,-.1,.1,,,,",
                  ",YES,1.,4.-3,2.001-6,,0.,1.-6,0.", ",.1,.1,,,,,,", ",.85,.85"],
                 ["PBEAM,3,1,4.-3,2.-6,5.-6,,1.-6", ",,,,,,,,", ",NO,1.,,2.001-6",
                  ",.85,.85,0.,0.,0.,0.,0.,0.", ",0.,0.,0.,0.,0.,0.,0.,0."]):
        got = tip_flexibility(card)
        assert np.allclose(got, ref, rtol=1e-14, atol=0), (got, ref)


@pytest.mark.parametrize("card, message", [
    (["PBEAM,3,1,4.-3,2.-6,5.-6,,1.-6", ",,,,,,,,", ",NO,1.,4.-3,2.1-6"],
     "PBEAM 3: I1(B): tapered sections are not supported"),
    (["PBEAM,3,1,4.-3,2.-6,5.-6,,1.-6", ",,,,,,,,", ",NO,.5", ",NO,1."],
     "PBEAM 3: X/XB: only the station at end B"),
    (["PBEAM,3,1,4.-3,2.-6,5.-6,,1.-6", ",,,,,,,,", ",NO,1.", ",NO,1."],
     "PBEAM 3: SO: one station (end B) is supported"),
    (["PBEAM,3,1,4.-3,2.-6,5.-6,,1.-6", ",,,,,,,,", ",1.,1.,,,2."],
     "PBEAM 3: NSI(A): shear relief, non-structural inertia"),
    (["PBEAM,3,1,4.-3,2.-6,5.-6,,1.-6", ",,,,,,,,", ",1.,1.", ",,,,,,,,.1"],
     "PBEAM 3: N2(B): shear relief"),
    (["PBEAM,3,1,4.-3,2.-6,5.-6,,1.-6", ",,,,,,,,", ",-1.,1."], "PBEAM 3: K1: must not be"),
    (["PBEAM,3,1,4.-3,2.-6,5.-6,1.-7,1.-6"], "PBEAM 3: I12: unsymmetric sections"),
])
def test_bad_pbeam_fields_are_refused_naming_them(card, message):
    with pytest.raises(BdfError, match=re.escape(message)):
        matrices(BEAM + card)


SPC_MODEL = ["SOL 103", "CEND", "SPC = 9", "BEGIN BULK", "MAT1,1,2.1+11,8.+10,,7850.",
             "GRID,1,,0.,0.,0.", "GRID,2,,1.,0.,0.", "GRID,3,,2.,0.,0.",
             "PBAR,3,1,1.-3,1.-6,1.-6,2.-6",
             "CBAR,1,3,1,2,0.,1.,0.", "CBAR,2,3,2,3,0.,1.,0."]


def test_spcadd_chooses_the_union_of_its_sets():
    bulk = parse_bulk("\n".join(SPC_MODEL + ["SPCADD,9,1,2", "SPC1,1,123,1", "SPC,2,1,456",
                                             "SPC1,2,3,3", "ENDDATA"]), "s.bdf")
    assert bulk.spc == {1: {0, 1, 2, 3, 4, 5}, 3: {2}}


@pytest.mark.parametrize("extra, message", [
    (["SPCADD,9,1", "SPC1,1,123,1", "SPC1,4,3,3"], "SPC set 4 is not in the chosen SPCADD 9"),
    (["SPCADD,9,1,5", "SPC1,1,123,1"], "SPCADD 9: S2: no SPC or SPC1 set of that id"),
    (["SPCADD,9,1", "SPC1,1,123,1", "SPC1,9,3,3"], "SPCADD 9: SID: an SPCADD id must differ"),
    (["SPCADD,9,1", "SPCADD,9,1", "SPC1,1,123,1"], "SPCADD 9: duplicate SPCADD id"),
    (["SPCADD,9,1", "SPC1,1,123,1", "FORCE,3,3,0,1.,x"], "FORCE 3: N1: must be a real"),
])
def test_bad_spcadd_and_loads_are_refused(extra, message):
    with pytest.raises(BdfError, match=re.escape(message)):
        parse_bulk("\n".join(SPC_MODEL + extra + ["ENDDATA"]), "s.bdf")


def test_mat1_with_e_g_and_nu_given_uses_e_nu_for_shells_and_g_for_torsion():
    """MAT1 2.9+7 1.1+7 .32 (E/2G - 1 = 0.318): the shells are those of E and NU (G derived),
    a CROD's torsion uses the G given, as Nastran's MAT1 table says."""
    three = matrices(["MAT1,1,2.9+7,1.1+7,.32,.283", "PSHELL,7,1,.25,1"] + GRIDS + SHELLS)
    two = matrices(["MAT1,1,2.9+7,,.32,.283", "PSHELL,7,1,.25,1"] + GRIDS + SHELLS)
    assert_same(three[0], two[0])
    rod = ["GRID,1,,0.,0.,0.", "GRID,2,,2.,0.,0.", "PROD,3,1,1.,.5", "CROD,1,3,1,2"]
    K, _ = matrices(["MAT1,1,2.9+7,1.1+7,.32,.283"] + rod)
    assert K[3, 3] == pytest.approx(1.1e7 * .5 / 2, rel=1e-15)


@pytest.mark.parametrize("head, message", [
    (["ASSIGN INPUTT4 = 'k.op4', UNIT = 11", "SOL 103", "CEND"], "ASSIGN of output files"),
    (["SOL 103", "CEND", "SEALL = 5"], "SEALL = ALL is read"),
    (["SOL 103", "CEND", "SUPER = 2"], "SUPER = ALL is read"),
])
def test_control_statements_other_than_outputs_and_one_residual_are_refused(head, message):
    text = head + ["BEGIN BULK", "GRID,1,,0.,0.,0.", "ENDDATA"]
    with pytest.raises(BdfError, match=re.escape(message)):
        parse_bulk("\n".join(text), "c.bdf")


def test_output_assign_seall_super_maxlines_are_read_without_effect():
    base = ["SOL 103", "CEND", "BEGIN BULK"] + SPC_MODEL[4:] + ["ENDDATA"]
    more = ["ASSIGN OUTPUT2 = 'm.op2', UNIT = 12", "SOL 103", "CEND", "SEALL = ALL",
            "SUPER = ALL", "MAXLINES = 999999", "BEGIN BULK"] + SPC_MODEL[4:] + \
        ["PARAM,NOCOMPS,-1", "ENDDATA"]
    a, b = (nastran_matrices(parse_bulk("\n".join(t), "c.bdf")) for t in (base, more))
    assert (a.K != b.K).nnz == 0 and (a.M != b.M).nnz == 0
