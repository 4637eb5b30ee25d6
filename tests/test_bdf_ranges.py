"""Bulk data numbers held to the range of the case's numbers (0 or ``1e-30 .. 1e30`` in
magnitude): every real field of a card, the entries of DMIG and OP4 matrices, and the products
each element makes of them (its stiffness and mass entries).  The corpus
(``tests/bad_cases/hostile_nastran_*``, ``hostile_op4_entry_tiny``, ``hostile_dmig_entry_huge``)
holds the cases run end to end; these are the ones read in-process."""

from __future__ import annotations

import numpy as np
import pytest

from substruct.case.bdf import parse_bulk
from substruct.case.bdf_fields import BdfError
from substruct.case.numbers import entry_problem
from substruct.models.nastran import nastran_matrices

ROD = ("GRID,1,,0.,0.,0.\nGRID,2,,{x},0.,0.\nCROD,1,1,1,2\nPROD,1,1,{a}\n"
       "MAT1,1,{e},,.3,{rho}\n")


def rod(x: str = "1.", a: str = "1.", e: str = "1.", rho: str = "1.", extra: str = "") -> str:
    return ROD.format(x=x, a=a, e=e, rho=rho) + extra


@pytest.mark.parametrize("text, fragment", [
    (rod(x="1.-31"), "GRID 2: X1: out of range: too small"),
    (rod(e="1.+31"), "MAT1 1: E: out of range: too large"),
    (rod(a="1.D+40"), "PROD 1: A: out of range: too large"),
    (rod(extra="CONM2,5,2,,1.,,,,\n,1.-40"), "CONM2 5: I11: out of range: too small"),
    (rod(extra="PARAM,WTMASS,1.-31"), "PARAM WTMASS: V1: out of range: too small"),
])
def test_every_real_field_is_in_range(text, fragment):
    with pytest.raises(BdfError, match=fragment):
        parse_bulk(text, "t.bdf")


def test_zero_and_the_bounds_are_accepted():
    bulk = parse_bulk(rod(x="1.+30", a="1.-30", e="0.", rho="-0.", extra="EIGRL,1,,,2"),
                      "t.bdf")
    assert bulk.grids[2][0] == 1e30


def test_an_mpc_coefficient_is_a_coefficient_at_any_magnitude():
    """MPC rows are equilibrated before any decision, as a case file's constraint terms."""
    text = rod(extra="MPC,3,2,2,1.-40,1,2,-1.-40")
    (m,) = parse_bulk(text, "t.bdf").mpcs
    assert [a for _, _, a in m.terms] == [1e-40, -1e-40]


@pytest.mark.parametrize("text, fragment", [
    # a rod of length 1e-20: E A / L = 1e40
    (rod(x="1.-20", e="1.+20", a="1."), "CROD 1: a product of its fields and its grids' "
     "positions is out of range: the stiffness matrix"),
    # rho A L = 1e20 in range; times WTMASS 1e20, not
    (rod(x="1.+10", rho="1.+10", extra="PARAM,WTMASS,1.+20"), "CROD 1: a product"),
    (rod(extra="CONM2,5,2,,1.+10,1.+12,0.,0."), "CONM2 5: a product of its fields and its "
     "grids' positions is out of range: the mass matrix"),
])
def test_an_element_whose_matrices_leave_the_range_is_refused(text, fragment):
    with pytest.raises(BdfError, match=fragment):
        nastran_matrices(parse_bulk(text, "t.bdf"))


def test_a_solid_whose_matrices_leave_the_range_is_refused_by_its_card():
    corners = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1),
               (0, 1, 1)]
    grids = "".join(f"GRID,{k + 1},,{x * 1e20:.1e},{y * 1e20:.1e},{z * 1e20:.1e}\n"
                    .replace("e+", "+") for k, (x, y, z) in enumerate(corners))
    text = grids + "CHEXA,7,1,1,2,3,4,5,6\n,7,8\nPSOLID,1,1\nMAT1,1,1.+20,,.3,0.\n"
    with pytest.raises(BdfError, match="CHEXA 7: a product .* stiffness matrix"):
        nastran_matrices(parse_bulk(text, "t.bdf"))


def test_entry_problem_holds_the_matrix_rule():
    """Entries beyond 1e30 or not finite are refused where they are; a small entry beside
    large ones is a round-off entry (an exported damping matrix has 6e-31), kept; a matrix
    whose largest entry is below 1e-30 is refused at that entry."""
    assert entry_problem(np.array([[1.0, 0.0], [1e-30, 1e30]])) is None
    assert entry_problem(np.array([[1.0, 0.0], [0.0, 2e-300]])) is None
    assert entry_problem(np.array([[1e-31, 0.0], [0.0, 2e-300]]))[:2] == ((0, 0), 1e-31)
    index, value, problem = entry_problem(np.array([1.0, np.inf]))
    assert index == (1,) and problem == "must be a finite number"
