"""Substructure synthesis of the tapered rod, paper section 6 and Table 1 (eqs 23-34, 50-53)."""

import numpy as np
import pytest

from substruct.assembly.stack import Connection, LinearConstraint, PointRef, assemble
from substruct.models.discrete import fixed_free, free_free
from substruct.models.rod import paper_taper, rod_assumed_modes, rod_fe
from substruct.analysis.checks import modes_agreement
from substruct.analysis.modes.dense import FORMULATIONS, coupled_modes
from substruct.models.reduction import modal_truncation

L = 200.0
POINTS = [L / 4, L / 2, 3 * L / 4, L]
EQ52 = [2.0, -5.0, -4.0, 3.0]
TABLE1_WITHOUT = [21.7, 54.8, 59.0, 83.7, 97.1, 135.0]
TABLE1_WITH = [21.7, 54.8, 74.2, 83.7, 97.1]  # the printed leading "0" is a spurious root


def tapered_rod_model(mapping="physical", n=8, g=4, with52=True, fe=None):
    """Rod of eq 50 with a, b (fixed-free) and c, d (free-free) attached at L/4 .. L."""
    EA, m = paper_taper(6.0e6, 1.0, L)
    if fe:
        rod = rod_fe("rod", L, EA, m, fe[0], order=fe[1], nodes_at=POINTS)
    else:
        rod = rod_assumed_modes("rod", L, EA, m, n, mapping=mapping)
    if g:
        rod = modal_truncation(rod, g)
    subs = [rod, fixed_free("a", 1.0, 3000.0), fixed_free("b", 1.0, 9000.0),
            free_free("c", 1.0, 7000.0), free_free("d", 1.0, 3000.0)]
    links = [Connection(PointRef("rod", x), PointRef(s, "boundary"))
             for x, s in zip(POINTS, "abcd")]
    extra = [LinearConstraint(tuple((PointRef("rod", x), c) for x, c in zip(POINTS, EQ52)),
                              name="eq52")] if with52 else []
    return assemble(subs, links, extra)


def modes_of(asm, method="generalized-inverse"):
    return coupled_modes(asm.M, asm.C, asm.K, asm.A, method=method)


@pytest.mark.parametrize("method", FORMULATIONS)
def test_table1_without_constraint52_paper_literal(method):
    md = modes_of(tapered_rod_model("paper-literal", with52=False), method)
    np.testing.assert_array_equal(np.round(md.omega[:6], 1), TABLE1_WITHOUT)


@pytest.mark.parametrize("method", FORMULATIONS)
def test_table1_with_constraint52_paper_literal(method):
    asm = tapered_rod_model("paper-literal", with52=True)
    md = modes_of(asm, method)
    np.testing.assert_array_equal(np.round(md.omega[:5], 1), TABLE1_WITH)
    assert md.omega[0] > 20.0  # no zero among the physical modes


def test_table1_zero_is_a_spurious_root():
    """The "0" of Table 1 is one of the 2 rank(A) zero roots of eq (34) that violate A u = 0."""
    asm = tapered_rod_model("paper-literal", with52=True)
    md = modes_of(asm)
    rank = np.linalg.matrix_rank(asm.A.toarray())
    assert rank == 5
    zeros = [l for l in md.spurious if abs(l) < 1e-3]
    assert len(zeros) == 2 * rank
    assert all("violates A u = 0" in r for r in md.spurious_reason)
    # the null-space formulation has no such roots at all
    assert modes_of(asm, "null-space").spurious.size == 0


def test_physical_modes_satisfy_constraints():
    for mapping in ("paper-literal", "physical"):
        for with52 in (False, True):
            asm = tapered_rod_model(mapping, with52=with52)
            md = modes_of(asm)
            u = md.shapes
            res = np.linalg.norm(asm.A @ u, axis=0) / np.linalg.norm(u, axis=0)
            assert res.max() < 1e-9


def test_physical_mapping_generalized_inverse_equals_null_space():
    for n, g in ((8, 4), (16, 16), (24, 12)):
        asm = tapered_rod_model("physical", n=n, g=g)
        gi, ns = modes_of(asm), modes_of(asm, "null-space")
        assert len(gi) == len(ns)
        assert modes_agreement(gi, ns) < 1e-9


def test_physical_mapping_differs_from_table1():
    md = modes_of(tapered_rod_model("physical", with52=False))
    assert abs(md.omega[0] - 21.7) > 0.5  # the literal mapping is not the physical answer


def test_adding_constraint52_interlaces():
    """Cauchy interlacing: w_i(without) <= w_i(with) <= w_(i+1)(without)."""
    for mapping in ("paper-literal", "physical"):
        w0 = modes_of(tapered_rod_model(mapping, n=12, g=12, with52=False)).omega
        w1 = modes_of(tapered_rod_model(mapping, n=12, g=12, with52=True)).omega
        assert w1.size == w0.size - 1
        tol = 1e-9 * w0.max()
        assert np.all(w0[:-1] <= w1 + tol) and np.all(w1 <= w0[1:] + tol)


FE_LIMIT = None


def fe_reference():
    """P2 finite elements, 256 elements, nodes at the attachment points, unreduced."""
    global FE_LIMIT
    if FE_LIMIT is None:
        FE_LIMIT = modes_of(tapered_rod_model(fe=(256, 2), g=None), "null-space").omega[:5]
    return FE_LIMIT


def test_fe_and_assumed_modes_approach_the_same_limit():
    """Assumed modes (n = g) converge at first order toward the FE limit (point constraints)."""
    ref = fe_reference()
    # FE itself is converged: 64 vs 256 elements
    coarse = modes_of(tapered_rod_model(fe=(64, 2), g=None), "null-space").omega[:5]
    assert np.max(np.abs(coarse - ref) / ref) < 1e-5
    ns = np.array([8, 16, 32, 64])
    err = np.array([np.max(np.abs(modes_of(tapered_rod_model(n=n, g=n), "null-space").omega[:5]
                                  - ref) / ref) for n in ns])
    assert np.all(np.diff(err) < 0)
    slope = np.polyfit(np.log(ns), np.log(err), 1)[0]
    assert -1.4 < slope < -0.8, slope          # first order in n (DESIGN.md section 2)
    assert err[-1] < 5e-3


def test_fe_generalized_inverse_equals_null_space():
    asm = tapered_rod_model(fe=(16, 2), g=None)
    gi, ns = modes_of(asm), modes_of(asm, "null-space")
    assert modes_agreement(gi, ns) < 1e-9
    np.testing.assert_allclose(gi.omega[:5], fe_reference(), rtol=3e-4)
