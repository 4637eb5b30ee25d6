"""Scalar springs of bulk data (CELAS1 with PELAS, CELAS2): the stiffness they add, and the
ones refused (a negative stiffness, as PBUSH's; a spring joining a coordinate to itself, which
adds nothing).  The corpus (``tests/bad_cases/hostile_nastran_*elas*``) runs the refusals end
to end."""

from __future__ import annotations

import numpy as np
import pytest

from substruct.case.bdf import parse_bulk
from substruct.case.bdf_fields import BdfError
from substruct.models.nastran import nastran_matrices

GRIDS = "GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\n"


def test_celas2_between_grids_and_celas1_grounded():
    text = GRIDS + "CELAS2,5,3.,1,2,2,3\nCELAS1,6,7,2,1\nPELAS,7,4.\n"
    K = nastran_matrices(parse_bulk(text, "t.bdf")).K.toarray()
    a, b, c = 1, 6 + 2, 6 + 0  # grid 1 component 2, grid 2 component 3, grid 2 component 1
    assert np.array_equal(K[np.ix_([a, b], [a, b])], [[3.0, -3.0], [-3.0, 3.0]])
    assert K[c, c] == 4.0 and np.count_nonzero(K) == 5


@pytest.mark.parametrize("text, fragment", [
    ("CELAS2,5,-3.,1,2,2,3", "CELAS2 5: K: stiffnesses must not be negative"),
    ("CELAS1,5,7,1,2\nPELAS,7,1.,,,8,-2.", "PELAS 7: K2: stiffnesses must not be negative"),
    ("CELAS2,5,3.,1,2,1,2", "CELAS2 5: G2: the spring joins a coordinate to itself"),
    ("CELAS1,5,7,2,6,2,6\nPELAS,7,1.", "CELAS1 5: G2: the spring joins a coordinate to itself"),
])
def test_a_negative_or_self_joining_spring_is_refused(text, fragment):
    with pytest.raises(BdfError, match=fragment):
        parse_bulk(GRIDS + text + "\n", "t.bdf")


def test_a_spring_between_two_components_of_one_grid_is_kept():
    K = nastran_matrices(parse_bulk(GRIDS + "CELAS2,5,3.,1,1,1,2\n", "t.bdf")).K.toarray()
    assert np.array_equal(K[:2, :2], [[3.0, -3.0], [-3.0, 3.0]])
