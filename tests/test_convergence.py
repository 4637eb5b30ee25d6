"""Convergence study (issue 5): enriched Ritz basis, solver, rates, limits, outputs."""

import dataclasses
import inspect

import numpy as np
import pytest
import scipy.sparse as sp

import substruct.studies.convergence as convergence
import substruct.builder.rod_system as rod_system
import substruct.builder.rod_system_case as convergence_case
import substruct.cli.convergence_summary as convergence_summary
import substruct.io.convergence_report as convergence_report
import substruct.viz.convergence_picture as convergence_picture
import substruct.models.enrichment as enrichment
from substruct.studies.convergence import convergence_study, dofs_to_reach, lowest_modes
from substruct.studies.levels import StudyLevels, parse_levels
from substruct.builder.rod_system import Attachment, RodSystemSpec, paper_rod_spec
from substruct.cli.convergence_summary import print_table, run_convergence
from substruct.io.convergence_report import load_h5, save_h5
from substruct.models.enrichment import rod_assumed_modes_enriched, static_shapes
from substruct.models.rod import paper_taper, rod_assumed_modes, rod_fe, uniform_rod_frequencies
from substruct.analysis.modes.dense import coupled_modes
from substruct.linalg.nullspace import master_slave

L = 200.0
EA0 = 6.0e6


@pytest.fixture(scope="module")
def paper_study():
    """The default study of the paper's rod, with and without (52) and bare (a few seconds)."""
    return convergence_study(paper_rod_spec())


# ------------------------------------------------------------------------ static shapes


@pytest.mark.parametrize("support, exact", [
    ("fixed-free", lambda x, a: np.minimum(x, a)),
    ("free-fixed", lambda x, a: L - np.maximum(x, a)),
    ("fixed-fixed", lambda x, a: np.where(x < a, x * (L - a), a * (L - x)) / L),
])
def test_static_shapes_uniform_rod_closed_forms(support, exact):
    x = np.linspace(0, L, 41)
    for a in (30.0, 100.0, 170.0):
        psi, dpsi = static_shapes(L, EA0, 1.0, [a], support)(x)
        np.testing.assert_allclose(psi[0] * EA0, exact(x, a), atol=1e-10 * L)


def test_static_shape_free_free_inertia_relief():
    """Uniform free-free rod: N(x) = x/L - H(x - a), so the end forces vanish."""
    x = np.array([0.0, 20.0, 80.0, 150.0, L])
    _, dpsi = static_shapes(L, EA0, 2.0, [100.0], "free-free")(x)
    np.testing.assert_allclose(dpsi[0] * EA0, x / L - (x >= 100.0), atol=1e-13)


@pytest.mark.parametrize("support", ["fixed-free", "free-fixed", "fixed-fixed", "free-free"])
def test_static_shape_slopes_and_kink_on_the_taper(support):
    EA, m = paper_taper(EA0, 1.0, L)
    pts = [50.0, 130.0]
    shapes = static_shapes(L, EA, m, pts, support)
    x, h = np.array([20.0, 90.0, 170.0]), 1e-3
    fd = (shapes(x + h)[0] - shapes(x - h)[0]) / (2 * h)
    np.testing.assert_allclose(fd, shapes(x)[1], rtol=1e-7, atol=1e-15)
    for j, a in enumerate(pts):  # the slope jump of a unit point force
        jump = shapes(np.array([a + 1e-9]))[1][j] - shapes(np.array([a - 1e-9]))[1][j]
        np.testing.assert_allclose(jump, -1.0 / EA(np.array([a])), rtol=1e-6)
    ends = shapes(np.array([0.0, L]))[0]
    if support.startswith("fixed"):
        assert np.all(ends[:, 0] == 0)
    if support.endswith("fixed"):
        assert np.all(abs(ends[:, 1]) < 1e-20)


# ----------------------------------------------------------------------- enriched basis


def test_enriched_basis_blocks_and_points():
    EA, m = paper_taper(EA0, 1.0, L)
    pts = [L / 4, L / 2, 3 * L / 4, L]
    rod = rod_assumed_modes_enriched("rod", L, EA, m, 8, pts)
    plain = rod_assumed_modes("rod", L, EA, m, 8)
    Me, Ke = rod.M.toarray(), rod.K.toarray()
    np.testing.assert_allclose(Me[:8, :8], plain.M.toarray(), rtol=0, atol=1e-13)
    np.testing.assert_allclose(Ke[:8, :8], plain.K.toarray(), rtol=0, atol=1e-13 * EA0 / L)
    np.testing.assert_allclose(Me[8:, 8:], np.eye(4), atol=1e-12)  # M-orthonormal shapes
    assert abs(Me[:8, 8:]).max() < 1e-10                             # M-orthogonal to sines
    assert rod.dof_labels == tuple(f"q{i}" for i in range(1, 9)) + ("s1", "s2", "s3", "s4")
    np.testing.assert_allclose(rod.row(77.0).toarray()[0, :8], plain.row(77.0).toarray()[0],
                               atol=1e-15)
    assert rod.meta["dropped_points"] == []
    assert set(rod.geometry.glyphs) == {f"x={x:g}" for x in pts}


def test_enriched_basis_reproduces_static_deflection_exactly():
    """Manufactured solution: a unit load at a; psi_a is in the Ritz space, so Galerkin
    returns it to round-off (the plain sines cannot: first-order error at the kink)."""
    EA, m = paper_taper(EA0, 1.0, L)
    a = 0.3 * L
    rod = rod_assumed_modes_enriched("rod", L, EA, m, 6, [a, 0.8 * L])
    q = np.linalg.solve(rod.K.toarray(), rod.row(a).toarray()[0])
    x = np.linspace(0, L, 33)
    u = np.array([rod.row(xi).toarray()[0] @ q for xi in x])
    exact = static_shapes(L, EA, m, [a])(x)[0][0]
    np.testing.assert_allclose(u, exact, atol=1e-11 * exact.max())
    plain = rod_assumed_modes("rod", L, EA, m, 6)
    qp = np.linalg.solve(plain.K.toarray(), plain.row(a).toarray()[0])
    assert abs(plain.row(a).toarray()[0] @ qp - exact[np.argmin(abs(x - a))]) > 1e-3 * exact.max()


def test_enriched_basis_drops_dependent_shapes():
    EA, m = paper_taper(EA0, 1.0, L)
    rod = rod_assumed_modes_enriched("rod", L, EA, m, 4, [50.0, 0.0, 50.0, 120.0])
    assert rod.n_dof == 6
    assert rod.meta["static_points"] == [50.0, 120.0]
    assert rod.meta["dropped_points"] == [0.0, 50.0]
    with pytest.raises(ValueError, match="at least one load point"):
        rod_assumed_modes_enriched("rod", L, EA, m, 4, [])


# ------------------------------------------------------------------------------ solving


def test_sparse_null_space_with_redundant_rows():
    rng = np.random.default_rng(1)
    A = np.zeros((4, 30))
    A[0, [2, 5]] = [1.0, -1.0]
    A[1, [5, 9, 17]] = rng.normal(size=3)
    A[2] = A[0] + 2 * A[1]  # redundant
    A[3, [29]] = 1.0
    Z = master_slave(sp.csr_array(A)).T
    assert Z.shape == (30, 27)
    assert abs(A @ Z.toarray()).max() < 1e-14
    assert np.linalg.matrix_rank(Z.toarray()) == 27


@pytest.mark.parametrize("with52", [True, False])
def test_lowest_modes_agrees_with_coupled_modes(with52):
    spec = paper_rod_spec()
    if not with52:
        spec = dataclasses.replace(spec, constraints=())
    EA, m = spec.EA, spec.m
    for rod in (rod_assumed_modes("rod", L, EA, m, 10),
                rod_assumed_modes_enriched("rod", L, EA, m, 6, spec.points),
                rod_fe("rod", L, EA, m, 12, 2, nodes_at=spec.points)):
        asm = spec.assemble(rod)
        lam = lowest_modes(asm, 6)
        for method in ("generalized-inverse", "null-space"):
            ref = coupled_modes(asm.M, asm.C, asm.K, asm.A, method).omega[:6]
            np.testing.assert_allclose(abs(lam), ref, rtol=1e-9)
        # the sparse (shift-invert Lanczos) path gives the same roots
        np.testing.assert_allclose(lowest_modes(asm, 6, dense_limit=0), lam, rtol=1e-9)


def test_lowest_modes_above_the_dense_limit_take_the_sparse_strategy(monkeypatch):
    """A bare uniform fixed-free rod, P2 with 300 elements (600 coordinates): the roots come
    from the one analysis entry point with the sparse strategy, and are the closed form
    ``(2i - 1) pi c / 2L`` up to the P2 error (7.6e-9 for the sixth mode, 4e-12 for the
    first)."""
    seen = []
    real = convergence.modes

    def spy(*args, **kwargs):
        out = real(*args, **kwargs)
        seen.append(out.solver)
        return out
    monkeypatch.setattr(convergence, "modes", spy)
    spec = RodSystemSpec("uniform", L, EA0, 1.0, "fixed-free", n_modes=6)
    asm = spec.assemble(rod_fe("rod", L, EA0, 1.0, 300, 2))
    assert asm.n_dof == 600
    lam = lowest_modes(asm, 6)
    assert seen == ["sparse"]
    np.testing.assert_allclose(lam.imag, uniform_rod_frequencies(EA0, 1.0, L, 6), rtol=1e-8)
    assert abs(lam[0].imag / uniform_rod_frequencies(EA0, 1.0, L, 1)[0] - 1) < 1e-10
    assert np.all(lam.real == 0)


def test_lowest_modes_damped_attachments():
    spec = paper_rod_spec()
    att = tuple(dataclasses.replace(a, damping=20.0) for a in spec.attachments)
    spec = dataclasses.replace(spec, attachments=att)
    assert spec.damped
    asm = spec.assemble(rod_fe("rod", L, spec.EA, spec.m, 16, 2, nodes_at=spec.points))
    lam = lowest_modes(asm, 6)
    ref = coupled_modes(asm.M, asm.C, asm.K, asm.A, "generalized-inverse").eigenvalues[:6]
    np.testing.assert_allclose(lam, ref, rtol=1e-9)
    assert np.all(lam.real < 0) and np.all(lam.imag > 0)
    np.testing.assert_allclose(lowest_modes(asm, 6, dense_limit=0), lam, rtol=1e-9)


# ------------------------------------------------------------------------- the study


def test_smooth_rod_fe_at_theoretical_rates():
    """Bare tapered rod (no attachments, no constraint): P1 at h^2, P2 at h^4."""
    levels = StudyLevels(assumed=(4, 8, 16, 32), fixed_g=None, enriched=(),
                         fe_p1=(16, 32, 64, 128, 256, 512), fe_p2=(8, 16, 32, 64, 128, 256))
    res = convergence_study(paper_rod_spec(), levels, variants=("bare",))
    v = res.variants["bare"]
    assert set(v.series) == {"assumed", "fe-p1", "fe-p2"}  # no points: nothing to enrich
    np.testing.assert_allclose(v.series["fe-p1"].rate, 2.0, atol=0.3)
    np.testing.assert_allclose(v.series["fe-p2"].rate, 4.0, atol=0.3)
    np.testing.assert_allclose(v.reference_order, 4.0, atol=0.3)  # no assumed limit at all
    assert np.all(v.limit_difference < 1e-7)


def test_uniform_rod_limit_is_the_closed_form():
    spec = RodSystemSpec("uniform", L, EA0, 1.0, "fixed-free", n_modes=4)
    levels = StudyLevels(assumed=(4, 8), fixed_g=None, enriched=(), fe_p1=(16, 32),
                         fe_p2=(32, 64, 128))
    v = convergence_study(spec, levels, variants=("unconstrained",)).variants["unconstrained"]
    exact = uniform_rod_frequencies(EA0, 1.0, L, 4)
    np.testing.assert_allclose(abs(v.limit), exact, rtol=1e-10)
    # the Richardson estimate is closer to the exact answer than the finest level (or both at
    # round-off)
    err_rich, err_fine = abs(abs(v.limit) - exact) / exact, abs(abs(v.limit_finest) - exact) / exact
    assert np.all(err_rich < np.maximum(0.1 * err_fine, 1e-10))
    assert err_fine[-1] > 1e-8  # mode 4 of the finest P2 is not yet at round-off
    # the sines are the exact modes of the uniform rod
    for w in abs(v.series["assumed"].eigenvalues):
        np.testing.assert_allclose(w, exact, rtol=1e-13)


@pytest.mark.parametrize("variant", ["constrained", "unconstrained"])
def test_paper_rod_rates_and_limits(paper_study, variant):
    v = paper_study.variants[variant]
    s = v.series
    # the limit: finest P2 and its Richardson estimate agree; P2 observed order 4 without it
    assert np.all(v.limit_difference < 1e-9)
    np.testing.assert_allclose(v.reference_order, 4.0, atol=0.1)
    # nodes at the attachment points keep the element rates
    np.testing.assert_allclose(s["fe-p1"].rate, 2.0, atol=0.1)
    np.testing.assert_allclose(s["fe-p2"].rate, 4.0, atol=0.2)
    # plain assumed modes: first order (slope jumps), to the same limit as FE
    np.testing.assert_allclose(s["assumed"].rate, 1.0, atol=0.15)
    assert np.all(s["assumed"].extrapolated_difference < 1e-5)
    # enriched: all modes to 1e-6 with a few dozen functions; plain far from it at 256
    n_enriched = dofs_to_reach(s["enriched"], 1e-6)
    assert n_enriched is not None and n_enriched <= 40
    assert dofs_to_reach(s["assumed"], 1e-6) is None
    assert s["assumed"].worst_error[-1] > 1e-5 and s["assumed"].dofs[-1] == 256
    assert np.all(s["enriched"].rate > 4.5)
    assert np.all(s["enriched"].extrapolated_difference < 1e-8)
    # the paper's g = 4 reduction converges to the truncated model, not to the rod
    assert np.all(abs(s["assumed-g4"].rate[np.isfinite(s["assumed-g4"].rate)]) < 0.05)


def test_paper_rod_constrained_mode_count_and_speed(paper_study):
    with52 = paper_study.variants["constrained"]
    assert with52.label == "with eq52"
    assert paper_study.variants["unconstrained"].label == "without eq52"
    # g = 4 rod modes + 6 attachment coordinates - 4 connections - (52): 5 roots only
    g4 = with52.series["assumed-g4"]
    assert np.all(np.isinf(g4.rel_error[:, 5])) and np.all(np.isinf(g4.worst_error))
    assert paper_study.seconds < 60.0


def test_each_rod_model_is_built_once_per_study(monkeypatch):
    """The sines serve both assumed-modes series and the constrained and unconstrained variants
    (same points); the bare rod has no points, so its sines are built again."""
    calls = []
    build = rod_system.rod_assumed_modes

    def counting(*args, **kwargs):
        calls.append(args[4])
        return build(*args, **kwargs)
    monkeypatch.setattr(rod_system, "rod_assumed_modes", counting)
    levels = StudyLevels(assumed=(4, 8), fixed_g=4, enriched=(2,), fe_p1=(8,), fe_p2=(4, 8))
    res = convergence_study(dataclasses.replace(paper_rod_spec(), n_modes=3), levels)
    assert sorted(calls) == [4, 4, 8, 8]
    for v in res.variants.values():  # a reused model is charged its build time
        assert np.all(v.series["assumed-g4"].seconds > 0)


def test_rigid_body_mode_of_a_free_free_system():
    """Free-free rod with one absorber: the rigid mode is reported, its error is NaN."""
    spec = RodSystemSpec("free", L, EA0, 1.0, "free-free",
                         (Attachment("d", L, "free-free", 1.0, 3000.0),), n_modes=4)
    levels = StudyLevels(assumed=(8, 16, 32), fixed_g=None, enriched=(2, 4, 8),
                         fe_p1=(16, 32, 64), fe_p2=(16, 32, 64))
    v = convergence_study(spec, levels).variants["unconstrained"]
    assert abs(v.limit[0]) < 1e-6 * abs(v.limit[1])
    for s in v.series.values():
        assert np.all(np.isnan(s.rel_error[:, 0]))
        assert np.all(np.isfinite(s.worst_error))
    assert np.isnan(v.limit_difference[0]) and np.all(v.limit_difference[1:] < 1e-7)
    assert v.series["enriched"].worst_error[-1] < 1e-6 < v.series["assumed"].worst_error[-1]


# ----------------------------------------------------------------------------- outputs


def test_h5_round_trip_and_table(paper_study, tmp_path):
    path = save_h5(paper_study, tmp_path / "out" / "x_convergence.h5")
    assert sorted(p.name for p in path.parent.iterdir()) == ["x_convergence.h5"]  # no temp
    back = load_h5(path)
    assert back.name == paper_study.name and list(back.variants) == list(paper_study.variants)
    for key, v in paper_study.variants.items():
        w = back.variants[key]
        assert w.label == v.label and w.limit_source == v.limit_source
        np.testing.assert_array_equal(w.limit, v.limit)
        for skey, s in v.series.items():
            t = w.series[skey]
            for name in ("level", "dofs", "eigenvalues", "rel_error", "rate", "fit_mask"):
                np.testing.assert_array_equal(getattr(t, name), getattr(s, name))
    text = print_table(back, file=False)
    assert "with eq52" in text and "fitted order (theory 4)" in text
    assert "DOFs for worst error <= 1e-06" in text


def test_run_convergence_writes_outputs_and_reports_progress(tmp_path, capsys):
    calls = []
    spec = dataclasses.replace(paper_rod_spec(), name="quick_rod", n_modes=3)
    levels = "assumed=4,8; g=none; enriched=2,4; p1=8,16; p2=4,8"
    result, h5, png = run_convergence(spec, tmp_path, levels, variants=("constrained",),
                                      progress=lambda d, t, s: calls.append((d, t, s)))
    assert h5 == tmp_path / "quick_rod_convergence.h5" and h5.exists()
    assert png == tmp_path / "quick_rod_convergence.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == [h5.name, png.name]  # no temporaries
    assert [c[0] for c in calls] == list(range(1, 9)) and all(c[1] == 8 for c in calls)
    assert "Convergence study: quick_rod" in capsys.readouterr().out
    assert set(result.variants["constrained"].series) == {"assumed", "enriched", "fe-p1",
                                                          "fe-p2"}


def test_parse_levels():
    assert parse_levels(None) == StudyLevels()
    assert parse_levels("quick") == StudyLevels.preset("quick")
    lv = parse_levels("assumed=4:32; p2=8,4; g=none; enriched=")
    assert lv.assumed == (4, 8, 16, 32) and lv.fe_p2 == (4, 8) and lv.fixed_g is None
    assert lv.enriched == () and lv.fe_p1 == StudyLevels().fe_p1
    with pytest.raises(ValueError, match="bad item"):
        parse_levels("cubic=3")
    with pytest.raises(ValueError, match="positive"):
        parse_levels("p1=0")
    with pytest.raises(ValueError, match="empty range"):
        parse_levels("p1=64:8")
    with pytest.raises(ValueError, match="more than the 1024 functions"):
        parse_levels("enriched=2000")
    # a preset as the base, and the fixed-g series' g from outside unless the text sets it
    lv = parse_levels("quick; p2=4,8", fixed_g=20)
    assert lv == dataclasses.replace(StudyLevels.preset("quick"), fe_p2=(4, 8), fixed_g=20)
    assert parse_levels(None, fixed_g=None).fixed_g is None
    assert parse_levels("g=6", fixed_g=20).fixed_g == 6
    assert parse_levels("g=none", fixed_g=20).fixed_g is None


def test_study_variants():
    spec = paper_rod_spec()
    keys = [k for k, _, _ in convergence.study_variants(spec, ["bare", "constrained", "bare"])]
    assert keys == ["bare", "constrained"]
    bare = RodSystemSpec("bare", L, EA0, 1.0)
    assert convergence.study_variants(bare, ["constrained"]) == []  # nothing to run
    assert [k for k, _, _ in convergence.study_variants(bare)] == ["bare"]
    with pytest.raises(ValueError, match="unknown variant 'x'"):
        convergence.study_variants(spec, ["x"])


@pytest.mark.parametrize("module", [convergence, convergence_report, convergence_summary,
                                    convergence_picture, convergence_case, rod_system,
                                    enrichment])
def test_public_names_exist_and_are_documented(module):
    for name in module.__all__:
        obj = getattr(module, name)
        assert inspect.getdoc(obj), f"{module.__name__}.{name} has no docstring"
