"""The consistency of redundant nonhomogeneous constraints is decided whatever the scale of each
row: ``D A q = D b + D R F`` with ``D`` equilibrating the rows (DESIGN.md rule: rank and
consistency never depend on the scale of the input)."""

from __future__ import annotations

from pathlib import Path

import pytest

from substruct.case import CaseError, load_case
from substruct.run import build_model

CASE = Path(__file__).resolve().parents[1] / "cases" / "three_dof_frf_nonhomogeneous.yaml"


def _case(c1: float, rhs1: float, c2: float, rhs2: float):
    """eq41 plus ``c1 q2 = rhs1`` and ``c2 q2 = rhs2`` (the same row of A, twice)."""
    return load_case(CASE, [
        f"constraints[1]={{name: first, terms: {{P@q2: {c1!r}}}, rhs: {rhs1!r}}}",
        f"constraints[2]={{name: second, terms: {{P@q2: {c2!r}}}, rhs: {rhs2!r}}}"])


@pytest.mark.parametrize("c1, c2", [(1.0, 1.0), (1e9, 1e-9), (1e-9, 1e9), (1e-25, 1e25)])
def test_the_same_constraint_at_two_scales_is_accepted(c1, c2):
    # q2 = 1, written as c1 q2 = c1 and c2 q2 = c2: consistent at any pair of scales
    asm = build_model(_case(c1, c1, c2, c2)).assembly
    assert asm.A.shape == (3, 3)


@pytest.mark.parametrize("c1, c2", [(1.0, 1.0), (1e9, 1e-9), (1e-9, 1e9), (1e-25, 1e25)])
def test_contradicting_rows_are_refused_at_any_scale(c1, c2):
    # q2 = 1 and q2 = 2: no solution.  Measured against the largest right-hand side unscaled,
    # the misfit of 1e-9 q2 = 2e-9 beside 1e9 q2 = 1e9 was 1e-18 and the contradiction passed
    with pytest.raises(CaseError, match=r"constraints\.second\.rhs: inconsistent constraints: "
                                        r"the left-hand side of 'second' is .* x \(first\)"):
        build_model(_case(c1, c1, c2, 2 * c2))
