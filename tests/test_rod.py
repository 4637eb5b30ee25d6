"""Rods: assumed modes and finite elements against closed forms and against each other."""

import numpy as np
import pytest
import scipy.linalg as sla

from substruct.models.rod import (
    AssumedModesOptions,
    SUPPORTS,
    paper_taper,
    rod_assumed_modes,
    rod_fe,
    uniform_rod_frequencies,
)
from substruct.models.reduction import modal_truncation, undamped_modes
from substruct.substructure import PointError
from references import tapered_rod_frequency

L_PAPER, EA_PAPER, M_PAPER = 200.0, 2e5 * 30, 1.0


def frequencies(sub, k):
    lam = sla.eigh(sub.K.toarray(), sub.M.toarray(), eigvals_only=True)[:k]
    return np.sqrt(np.maximum(lam, 0.0))


def test_uniform_frequencies_closed_form():
    c = np.sqrt(4.0 / 1.0)
    w = uniform_rod_frequencies(4.0, 1.0, 2.0, 3, "fixed-free")
    assert np.allclose(w, [np.pi * c / 4, 3 * np.pi * c / 4, 5 * np.pi * c / 4], rtol=1e-15)
    assert np.allclose(uniform_rod_frequencies(4.0, 1.0, 2.0, 2, "fixed-fixed"),
                       [np.pi, 2 * np.pi], rtol=1e-15)
    assert np.allclose(uniform_rod_frequencies(4.0, 1.0, 2.0, 2, "free-free"), [0.0, np.pi])


@pytest.mark.parametrize("support", SUPPORTS)
@pytest.mark.parametrize("EA, m, L", [(1.0, 1.0, 1.0), (EA_PAPER, M_PAPER, L_PAPER)])
def test_assumed_modes_exact_for_uniform_rod(support, EA, m, L):
    """The Ritz basis is the set of exact modes: the first 4 frequencies to 1e-10."""
    rod = rod_assumed_modes("rod", L, EA, m, 6, support=support)
    exact = uniform_rod_frequencies(EA, m, L, 4, support)
    got = frequencies(rod, 4)
    scale = exact[-1]
    assert np.max(abs(got - exact)) / scale < 1e-10
    # (47) with the orthogonal sine/cosine basis: M diagonal, m L / 2 (m L for the constant).
    Md = rod.M.toarray()
    assert np.allclose(Md - np.diag(np.diag(Md)), 0.0, atol=1e-13 * m * L)
    expected = np.full(6, m * L / 2)
    if support == "free-free":
        expected[0] = m * L
    assert np.allclose(np.diag(Md), expected, rtol=1e-13)


def test_assumed_modes_quadrature_converged():
    """Doubling the quadrature mesh changes M and K of the tapered rod by < 1e-13 relative."""
    EA, m = paper_taper(EA_PAPER, M_PAPER, L_PAPER)
    a = rod_assumed_modes("rod", L_PAPER, EA, m, 30)
    b = rod_assumed_modes("rod", L_PAPER, EA, m, 30, options=AssumedModesOptions(
        n_quad_elements=2 * a.meta["n_quad_elements"]))
    for x, y in ((a.M, b.M), (a.K, b.K)):
        assert abs(x - y).max() / abs(y).max() < 1e-13


def _observed_rates(order, support, n_elements):
    exact = uniform_rod_frequencies(1.0, 1.0, 1.0, 5, support)
    first = 1 if support == "free-free" else 0  # skip the rigid-body mode
    errs = []
    for ne in n_elements:
        rod = rod_fe("rod", 1.0, 1.0, 1.0, ne, order=order, support=support)
        w = frequencies(rod, 5)
        errs.append(abs(w[first:first + 4] ** 2 - exact[first:first + 4] ** 2)
                    / exact[first:first + 4] ** 2)
    errs = np.array(errs)
    h = 1.0 / np.asarray(n_elements, dtype=float)
    rates = [np.polyfit(np.log(h), np.log(errs[:, i]), 1)[0] for i in range(4)]
    return np.array(rates), errs


@pytest.mark.parametrize("support", ["fixed-free", "fixed-fixed", "free-free"])
@pytest.mark.parametrize("order, n_elements", [(1, [8, 16, 32, 64]), (2, [8, 16, 32, 64])])
def test_fe_converges_at_rate_2p(order, n_elements, support):
    """Eigenvalue error ~ h^(2p): observed slopes within 0.3 of 2 (P1) and 4 (P2)."""
    rates, errs = _observed_rates(order, support, n_elements)
    assert np.all(abs(rates - 2 * order) < 0.3), rates
    assert np.all(np.diff(np.log(errs), axis=0) < 0)  # monotone
    assert errs[-1, 0] < (1e-3 if order == 1 else 1e-8)


@pytest.mark.parametrize("order", [1, 2])
def test_fe_free_free_has_a_rigid_body_mode(order):
    rod = rod_fe("rod", 1.0, 1.0, 1.0, 20, order=order, support="free-free")
    w = frequencies(rod, 2)
    assert w[0] < 1e-6 and abs(w[1] - np.pi) / np.pi < 1e-2
    M = rod.M.toarray()
    assert np.isclose(np.ones(rod.n_dof) @ M @ np.ones(rod.n_dof), 1.0, rtol=1e-13)  # m L


def test_fe_uniform_rod_paper_sizes():
    rod = rod_fe("rod", L_PAPER, EA_PAPER, M_PAPER, 64, order=2)
    exact = uniform_rod_frequencies(EA_PAPER, M_PAPER, L_PAPER, 4)
    assert np.max(abs(frequencies(rod, 4) - exact) / exact) < 1e-6


def test_tapered_rod_assumed_modes_and_fe_agree():
    """Eq 50 with L=200, EA0=6e6, m0=1: lowest 4 frequencies agree to 1e-6 relative."""
    EA, m = paper_taper(EA_PAPER, M_PAPER, L_PAPER)
    am = frequencies(rod_assumed_modes("rod", L_PAPER, EA, m, 60), 4)
    fe = frequencies(rod_fe("rod", L_PAPER, EA, m, 400, order=2), 4)
    assert np.max(abs(am - fe) / fe) < 1e-6
    # the taper changes the uniform-rod frequencies (EA/m constant, but not uniform)
    uniform = uniform_rod_frequencies(EA_PAPER, M_PAPER, L_PAPER, 4)
    assert np.all(abs(fe - uniform) / uniform > 1e-3)
    # against the shooting solution of the rod's differential equation (tests/references.py)
    exact = [tapered_rod_frequency(1), tapered_rod_frequency(2)]
    np.testing.assert_allclose(fe[:2], exact, rtol=1e-9)


def test_paper_taper_values():
    EA, m = paper_taper(6e6, 2.0, 200.0)
    assert np.allclose(EA(np.array([0.0, 100.0, 200.0])), [7.2e6, 6.3e6, 3.6e6])
    assert np.allclose(m(np.array([0.0, 200.0])), [2.4, 1.2])


def test_paper_literal_mapping_rows_are_eigenvector_entries():
    """n = 8, g = 4: the row at x = 2L/8 is entry 2 of each of the 4 eigenvectors."""
    EA, m = paper_taper(EA_PAPER, M_PAPER, L_PAPER)
    rod = rod_assumed_modes("rod", L_PAPER, EA, m, 8, mapping="paper-literal")
    assert np.array_equal(rod.row(2 * L_PAPER / 8).toarray(), np.eye(8)[[1]])
    omega, Phi = undamped_modes(rod, 4)
    reduced = modal_truncation(rod, 4)
    for j in (2, 4, 6, 8):
        row = reduced.row(j * L_PAPER / 8).toarray().ravel()
        assert np.allclose(row, Phi[j - 1, :4], rtol=0, atol=1e-15)
    assert np.allclose(reduced.row(0.25 * L_PAPER).toarray().ravel(), Phi[1, :4])
    # it is not the physical mapping: u(L/4) = sum_k Phi_k sin(...) differs
    physical = rod_assumed_modes("rod", L_PAPER, EA, m, 8)
    phys_row = physical.row(L_PAPER / 4).toarray().ravel() @ Phi
    assert np.max(abs(phys_row - Phi[1])) > 1e-2
    with pytest.raises(PointError, match="paper-literal"):
        rod.row(30.0)
    with pytest.raises(PointError, match="paper-literal"):
        rod.row(0.0)


def test_paper_literal_stations_parameter():
    rod = rod_assumed_modes("rod", 1.0, 1.0, 1.0, 8, mapping="paper-literal",
                            options=AssumedModesOptions(literal_stations=4))
    assert np.array_equal(rod.row(0.5).toarray(), np.eye(8)[[1]])
    with pytest.raises(PointError):
        rod.row(1 / 8)
    with pytest.raises(ValueError, match="literal_stations"):
        rod_assumed_modes("rod", 1.0, 1.0, 1.0, 8, mapping="paper-literal",
                          options=AssumedModesOptions(literal_stations=9))


def test_assumed_modes_locator_is_sine_row():
    rod = rod_assumed_modes("rod", 2.0, 1.0, 1.0, 4)
    x = 0.7
    expected = np.sin((2 * np.arange(1, 5) - 1) * np.pi * x / 4.0)
    assert np.allclose(rod.row(x).toarray().ravel(), expected, rtol=1e-15)
    assert np.allclose(rod.row("x=0.7").toarray(), rod.row(0.7).toarray())
    assert np.allclose(rod.row(2.0 + 1e-10).toarray().ravel(), [1, -1, 1, -1])
    for bad in (-0.01, 2.01, "tip", None):
        with pytest.raises(PointError, match="rod"):
            rod.row(bad)
    # drawing: 201 points along x; the tip moves by sum q_i phi_i(L)
    g = rod.geometry
    assert g.points.shape == (201, 3) and np.allclose(g.points[:, 1:], 0)
    disp = g.displacement(np.array([1.0, 0.0, 0.0, 0.0]))
    assert np.isclose(disp[-1, 0], 1.0) and np.allclose(disp[:, 1:], 0)


def test_fe_locator_rows():
    rod = rod_fe("rod", 1.0, 1.0, 1.0, 4, order=1)
    assert rod.dof_labels == ("x=0.25", "x=0.5", "x=0.75", "x=1")
    assert np.array_equal(rod.row(0.5).toarray(), [[0, 1, 0, 0]])
    assert np.allclose(rod.row(0.625).toarray(), [[0, 0.5, 0.5, 0]], atol=1e-15)
    assert np.allclose(rod.row(0.1).toarray(), [[0.4, 0, 0, 0]], atol=1e-15)
    assert rod.row(0.0).nnz == 0  # the clamped end does not move
    with pytest.raises(PointError, match="not on the rod"):
        rod.row(1.2)
    p2 = rod_fe("rod", 1.0, 1.0, 1.0, 2, order=2, support="free-free")
    assert p2.dof_labels == ("x=0", "x=0.25", "x=0.5", "x=0.75", "x=1")
    # quadratic interpolation at x = 0.125 (element [0, .5], local coordinate 1/4)
    assert np.allclose(p2.row(0.125).toarray(), [[0.375, 0.75, -0.125, 0, 0]], atol=1e-15)
    assert np.array_equal(p2.row(0.75).toarray(), [[0, 0, 0, 1, 0]])


def test_fe_mesh_has_nodes_at_attachment_points():
    rod = rod_fe("rod", 200.0, 1.0, 1.0, 10, order=1, nodes_at=[50.0, 77.7, 150.0])
    nodes = np.array([float(s[2:]) for s in rod.dof_labels])
    for x in (50.0, 77.7, 150.0):
        assert np.min(abs(nodes - x)) < 1e-9
        assert rod.row(x).nnz == 1
    assert rod.meta["h_max"] <= 200.0 / 10 * 1.5
    assert set(rod.geometry.glyphs) == {"x=50", "x=77.7", "x=150"}
    # on the uniform grid, nodes_at changes nothing
    assert rod_fe("rod", 200.0, 1.0, 1.0, 8, nodes_at=[50.0, 100.0]).meta["n_elements"] == 8


def test_fe_point_spring_keeps_rate():
    """A spring to ground at x = L/3 (a node): P1 eigenvalue rate stays 2."""
    errs, h = [], []
    ref = None
    for ne in (12, 24, 48, 96, 768):
        rod = rod_fe("rod", 1.0, 1.0, 1.0, ne, order=1, nodes_at=[1 / 3])
        K = rod.K.toarray()
        K += 50.0 * rod.row(1 / 3).toarray().T @ rod.row(1 / 3).toarray()
        lam = sla.eigh(K, rod.M.toarray(), eigvals_only=True)[:3]
        if ne == 768:
            ref = lam
        else:
            errs.append(lam)
            h.append(1 / ne)
    errs = abs(np.array(errs) - ref) / ref
    rates = [np.polyfit(np.log(h), np.log(errs[:, i]), 1)[0] for i in range(3)]
    assert np.all(abs(np.array(rates) - 2) < 0.3), rates


@pytest.mark.parametrize("kwargs, match", [
    ({"length": -1.0}, "length"),
    ({"support": "pinned"}, "support"),
    ({"EA": lambda x: 0.5 - x}, "EA"),
    ({"n_elements": 0}, "n_elements"),
    ({"m": 0.0}, "m"),
])
def test_fe_rejects_bad_input(kwargs, match):
    args = {"name": "rod", "length": 1.0, "EA": 1.0, "m": 1.0, "n_elements": 4} | kwargs
    with pytest.raises(ValueError, match=match):
        rod_fe(**args)
    with pytest.raises(ValueError, match="rod"):
        rod_fe(**args)


def test_paper_literal_mapping_reproduces_table_1():
    """Rod (n=8, g=4) + a, b fixed-free + c, d free-free, compatibility by a null-space basis.

    Only the paper-literal mapping gives Table 1 (to its printed digits); the physical mapping
    gives other frequencies (DESIGN.md section 2).
    """
    from substruct.models.discrete import fixed_free, free_free

    EA, m = paper_taper(EA_PAPER, M_PAPER, L_PAPER)
    points = (L_PAPER / 4, L_PAPER / 2, 3 * L_PAPER / 4, L_PAPER)

    def coupled(mapping, extra_constraint):
        rod = modal_truncation(rod_assumed_modes("rod", L_PAPER, EA, m, 8, mapping=mapping), 4)
        subs = [rod, fixed_free("a", 1, 3000), fixed_free("b", 1, 9000),
                free_free("c", 1, 7000), free_free("d", 1, 3000)]
        M = sla.block_diag(*[s.M.toarray() for s in subs])
        K = sla.block_diag(*[s.K.toarray() for s in subs])
        off = np.cumsum([0] + [s.n_dof for s in subs])
        rows = []
        for i, x in enumerate(points, start=1):
            r = np.zeros(off[-1])
            r[:4] = rod.row(x).toarray()
            r[off[i]:off[i + 1]] -= subs[i].row("boundary").toarray().ravel()
            rows.append(r)
        if extra_constraint:  # eq 52
            r = np.zeros(off[-1])
            r[:4] = sum(c * rod.row(x).toarray().ravel() for c, x in zip((2, -5, -4, 3), points))
            rows.append(r)
        N = sla.null_space(np.array(rows))
        return np.sqrt(sla.eigh(N.T @ K @ N, N.T @ M @ N, eigvals_only=True))

    assert np.array_equal(np.round(coupled("paper-literal", False), 1),
                          [21.7, 54.8, 59.0, 83.7, 97.1, 135.0])
    # with (52): Table 1 lists 0 (a spurious root, not a mode) then these
    assert np.array_equal(np.round(coupled("paper-literal", True), 1),
                          [21.7, 54.8, 74.2, 83.7, 97.1])
    physical = coupled("physical", False)
    assert abs(physical[0] - 21.7) > 0.5
