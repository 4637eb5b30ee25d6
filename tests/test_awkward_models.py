"""Awkward but legal models (issue 6, item 3): each checked against a closed form or against
the other formulations.

* redundant constraints (the same compatibility twice);
* constraints that fix a substructure, or everything, completely;
* free-free assemblies (rigid-body modes are physical zeros with their exact vectors);
* massless coordinates that no constraint reaches (infinite roots set aside; the finite modes
  are those of static condensation);
* badly scaled units (a stiffness of ``1e12`` next to one of ``1``);
* repeated eigenvalues (identical absorbers);
* heavy non-proportional damping (complex modes, over-damped real roots);
* slow roots next to zero roots (a weakly damped rigid-body motion), which QZ alone resolves
  poorly in every formulation.

How roots are reported is fixed in :class:`substruct.analysis.results.Modes`: a complex root stands for its
conjugate pair; every real root is an entry of its own (``Im = 0``, ``omega = |lambda|``,
damping ratio 1); an undamped rigid-body mode is one entry ``lambda = 0``.
"""

import numpy as np
import pytest

from substruct.assembly.stack import Connection, LinearConstraint, PointRef, assemble
from substruct.linalg.constraints import ConstraintError
from substruct.linalg.nullspace import null_space_basis
from substruct.analysis.formulations.coupling import FORMULATIONS, constrained_acceleration, receptance, receptance_agreement
from substruct.models.discrete import fixed_free, free_free
from substruct.models.rod import (paper_taper, rod_assumed_modes, rod_fe,
                                  uniform_rod_frequencies)
from substruct.analysis.checks import modes_agreement
from substruct.analysis.modes.dense import FORMULATIONS, coupled_modes
from substruct.models.reduction import modal_truncation

from tolerances import solve_bound

SPURIOUS_ZERO = "violates A u = 0"
INFINITE = "infinite root"


def all_modes(M, C, K, A):
    return {mth: coupled_modes(M, C, K, A, method=mth) for mth in FORMULATIONS}


def asm_modes(asm):
    return all_modes(asm.M, asm.C, asm.K, asm.A)


def assert_agree(sets, rtol=1e-9):
    """Same number of modes, eigenvalues to ``rtol``, residuals ~ 0, for all formulations."""
    ref = sets["null-space"]
    for mth, md in sets.items():
        assert len(md) == len(ref), (mth, md.eigenvalues, ref.eigenvalues)
        assert modes_agreement(md, ref) < rtol, (mth, modes_agreement(md, ref))
        assert np.all(md.residual < 1e-9), (mth, md.residual)


def n_reason(md, text):
    return sum(text in r for r in md.spurious_reason)


def stable_quadratic(a, b, c):
    """Both roots of ``a x^2 - b x + c`` (``b > 0``, real roots) without cancellation."""
    big = (b + np.sqrt(b * b - 4 * a * c)) / (2 * a)
    return np.array([c / (a * big), big])


def polynomial_det(P):
    """Coefficients of ``det P(lambda)`` for a 2x2 or 3x3 matrix of polynomials (lists)."""
    mul, sub, add = np.polymul, np.polysub, np.polyadd
    if len(P) == 2:
        return sub(mul(P[0][0], P[1][1]), mul(P[0][1], P[1][0]))
    out = np.zeros(1)
    for j, sign in zip(range(3), (1, -1, 1)):
        minor = [[P[r][c] for c in range(3) if c != j] for r in (1, 2)]
        out = add(out, sign * mul(P[0][j], polynomial_det(minor)))
    return out


def refine_root(p, x, steps=6):
    """Newton on the polynomial ``p`` (exact coefficients) from ``x``."""
    dp = np.polyder(p)
    for _ in range(steps):
        x = x - np.polyval(p, x) / np.polyval(dp, x)
    return x


# --------------------------------------------------------------------------------------------
# redundant constraints


def test_the_same_compatibility_twice():
    """Two oscillators joined at their masses, the joint stated two (three) times: one DOF,
    ``lambda^2 (m1 + m2) + lambda (c1 + c2) + k1 + k2 = 0``."""
    m1, k1, c1, m2, k2, c2 = 2.0, 800.0, 3.0, 1.0, 400.0, 1.0
    subs = [fixed_free("a", m1, k1, c1), fixed_free("b", m2, k2, c2)]
    link = Connection(PointRef("a", "mass"), PointRef("b", "mass"))
    back = Connection(PointRef("b", "mass"), PointRef("a", "mass"))
    roots = np.roots([m1 + m2, c1 + c2, k1 + k2])
    exact = roots[roots.imag > 0]
    for links in ([link], [link, link], [link, link, back]):
        asm = assemble(subs, links)
        sets = asm_modes(asm)
        assert_agree(sets)
        for md in sets.values():
            np.testing.assert_allclose(md.eigenvalues, exact, rtol=1e-12)
        # one independent constraint: the paper's pencil sets aside one pair of zeros, however
        # many times the constraint is written
        assert n_reason(sets["generalized-inverse"], SPURIOUS_ZERO) == 2
        w = [5.0, 20.0, 40.0]
        H = receptance(asm.K, asm.M, asm.C, asm.A, w)
        closed = 1.0 / (k1 + k2 - np.square(w) * (m1 + m2) + 1j * np.multiply(w, c1 + c2))
        np.testing.assert_allclose(H, np.broadcast_to(closed[:, None, None], H.shape),
                                   rtol=1e-12)
        assert max(receptance_agreement(asm.K, asm.M, asm.C, asm.A, w).values()) < 1e-12


def test_redundant_nonhomogeneous_constraint_consistent_and_not():
    """``u_a = F_b`` written twice: consistent when both rows say the same, refused otherwise."""
    subs = [fixed_free("a", 2.0, 800.0, 3.0), fixed_free("b", 1.0, 400.0, 1.0)]
    pa, pb = PointRef("a", "mass"), PointRef("b", "mass")
    same = [LinearConstraint(((pa, 1.0),), force_terms=((pb, 1.0),), name="first"),
            LinearConstraint(((pa, 2.0),), force_terms=((pb, 2.0),), name="second")]
    asm = assemble(subs, (), same)
    for method in FORMULATIONS:
        H = receptance(asm.K, asm.M, asm.C, asm.A, 10.0, R=asm.R, method=method)
        np.testing.assert_allclose(H[0], [0.0, 1.0], atol=1e-14)  # u_a = F_b exactly
        # b alone, loaded by F_b, with u_a prescribed: 1 / (k - w^2 m + i w c)
        np.testing.assert_allclose(H[1, 1], 1 / (400.0 - 100.0 + 10j), rtol=1e-12)
    other = [same[0], LinearConstraint(((pa, 2.0),), force_terms=((pb, 3.0),), name="second")]
    asm = assemble(subs, (), other)
    with pytest.raises(ConstraintError, match="second"):
        receptance(asm.K, asm.M, asm.C, asm.A, 10.0, R=asm.R, labels=asm.constraint_labels)


def test_paper_rod_with_eq52_written_twice():
    """Table 1 (constrained column, paper-literal mapping) is unchanged by a repeated eq (52);
    the paper's pencil still sets aside 2 rank(A) = 10 zero roots, not 12."""
    L = 200.0
    points = [L / 4, L / 2, 3 * L / 4, L]
    EA, m = paper_taper(6.0e6, 1.0, L)
    rod = modal_truncation(rod_assumed_modes("rod", L, EA, m, 8, mapping="paper-literal"), 4)
    subs = [rod, fixed_free("a", 1.0, 3000.0), fixed_free("b", 1.0, 9000.0),
            free_free("c", 1.0, 7000.0), free_free("d", 1.0, 3000.0)]
    links = [Connection(PointRef("rod", x), PointRef(s, "boundary"))
             for x, s in zip(points, "abcd")]
    eq52 = LinearConstraint(tuple((PointRef("rod", x), c)
                                  for x, c in zip(points, [2.0, -5.0, -4.0, 3.0])), name="eq52")
    once, twice = assemble(subs, links, [eq52]), assemble(subs, links, [eq52, eq52])
    sets = asm_modes(twice)
    assert_agree(sets)
    np.testing.assert_array_equal(np.round(sets["generalized-inverse"].omega[:5], 1),
                                  [21.7, 54.8, 74.2, 83.7, 97.1])
    ref = coupled_modes(once.M, once.C, once.K, once.A)
    assert modes_agreement(sets["generalized-inverse"], ref) < 1e-9
    assert n_reason(sets["generalized-inverse"], SPURIOUS_ZERO) == 10


# --------------------------------------------------------------------------------------------
# constraints that fix a substructure, or everything


def test_constraints_fix_a_substructure_completely():
    """A free-free FE rod pinned at every node by user constraints, with an absorber at its
    end: the rod does not move and the absorber sees a fixed base, ``w = sqrt(k/m)``."""
    L, ne = 10.0, 4
    rod = rod_fe("rod", L, 1.0e4, 2.0, ne, order=1, support="free-free")
    nodes = np.linspace(0.0, L, ne + 1)
    pins = [LinearConstraint(((PointRef("rod", float(x)), 1.0),), name=f"pin {x:g}")
            for x in nodes]
    m, k, c = 0.5, 200.0, 0.3
    asm = assemble([rod, free_free("abs", m, k, c)],
                   [Connection(PointRef("rod", L), PointRef("abs", "boundary"))], pins)
    sets = asm_modes(asm)
    assert_agree(sets, rtol=1e-12)
    exact = np.roots([m, c, k])
    for md in sets.values():
        assert len(md) == 1
        np.testing.assert_allclose(md.eigenvalues, exact[exact.imag > 0], rtol=1e-12)
        rod_part = md.shapes[asm.block("rod")]
        assert np.abs(rod_part).max() < 1e-12 * np.abs(md.shapes).max()
    # the paper's pencil: 2 x (ne + 2) constraints of rank ne + 2
    assert n_reason(sets["generalized-inverse"], SPURIOUS_ZERO) == 2 * (ne + 2)
    w = [3.0, 30.0]
    H = receptance(asm.K, asm.M, asm.C, asm.A, w)
    i = asm.block("abs").start  # the absorber mass
    np.testing.assert_allclose(H[:, i, i], 1 / (k - np.square(w) * m + 1j * np.multiply(w, c)),
                               rtol=1e-12)
    assert np.abs(H[:, asm.block("rod")]).max() < 1e-12 * np.abs(H).max()
    assert max(receptance_agreement(asm.K, asm.M, asm.C, asm.A, w).values()) < 1e-12


def test_constraints_fix_everything():
    """No motion is left: no modes (the null space is empty), ``H = 0`` for ``A q = 0`` and
    ``H = A^{-1} R`` for ``A q = R F``."""
    M, K = np.diag([1.0, 2.0]), np.array([[2.0, -1.0], [-1.0, 1.0]])
    A = np.array([[1.0, 1.0], [1.0, -1.0]])
    R = np.array([[1.0, 0.0], [0.0, 3.0]])
    for md in all_modes(M, 0.1 * K, K, A).values():
        assert len(md) == 0 and md.shapes.shape == (2, 0)
    assert len(coupled_modes(M, None, K, A, method="null-space").spurious) == 0
    # rounding of zero is measured against the scale of the unconstrained receptance
    # (Z^-1), the forced answer against its own; both to c n eps cond
    Z = K - 1.5 ** 2 * M
    exact = np.linalg.solve(A, R)
    for method in FORMULATIONS:
        np.testing.assert_allclose(receptance(K, M, None, A, 1.5, method=method), 0.0,
                                   atol=solve_bound(Z, np.linalg.inv(Z)))
        np.testing.assert_allclose(receptance(K, M, None, A, 1.5, R=R, method=method),
                                   exact, atol=solve_bound(A, exact))


# --------------------------------------------------------------------------------------------
# free-free assemblies


def test_two_free_free_rods_joined_are_one_rod():
    """Two free-free P2 rods joined end to end are the free-free rod of twice the length on the
    same mesh (to rounding), and that converges to ``(i - 1) pi c / 2L``; the rigid-body mode
    is a physical zero with the exact constant shape ``1 / sqrt(total mass)``."""
    EA, m, L, ne = 6.0e6, 1.0, 100.0, 20
    r1 = rod_fe("r1", L, EA, m, ne, order=2, support="free-free")
    r2 = rod_fe("r2", L, EA, m, ne, order=2, support="free-free")
    asm = assemble([r1, r2], [Connection(PointRef("r1", L), PointRef("r2", 0.0))])
    one = rod_fe("one", 2 * L, EA, m, 2 * ne, order=2, support="free-free")
    sets = asm_modes(asm)
    ref = coupled_modes(one.M, None, one.K, None, method="null-space")
    for mth, md in sets.items():
        assert len(md) == len(ref) == one.M.shape[0]
        assert modes_agreement(md, ref) < 1e-9, mth
        assert md.omega[0] == 0.0 and md.residual[0] < 1e-14
        np.testing.assert_allclose(md.shapes[:, 0], 1 / np.sqrt(2 * L * m), rtol=1e-12)
        # P2 elements: error O(h^4), 2e-5 at the fifth mode with 40 elements
        np.testing.assert_allclose(md.omega[1:6],
                                   uniform_rod_frequencies(EA, m, 2 * L, 6, "free-free")[1:],
                                   rtol=3e-5)
    gi = sets["generalized-inverse"]
    assert n_reason(gi, SPURIOUS_ZERO) == 2 and len(gi.spurious) == 2
    # receptance from one free end to the other, against the single rod
    F_in, F_out = asm.rows([PointRef("r1", 0.0)]), asm.rows([PointRef("r2", L)])
    w = [10.0, 100.0, 200.0]
    H = receptance(asm.K, asm.M, None, asm.A, w, inputs=F_in.T.toarray(), outputs=F_out)
    H1 = receptance(one.K, one.M, None, np.zeros((0, one.M.shape[0])), w,
                    inputs=one.row(0.0).T.toarray(), outputs=one.row(2 * L), method="kkt")
    np.testing.assert_allclose(H, H1, rtol=1e-9)


@pytest.mark.parametrize("damped", [False, True])
def test_two_free_free_chains_joined(damped):
    """Chains ``m -k- m`` joined end to end: ``m, 2m, m`` with springs ``k, k``,
    ``w^2 = 0, k/m, 2k/m``; with dampers ``c = beta k`` beside the springs the rigid-body mode
    stays a double zero (one entry) and ``lambda^2 + beta w^2 lambda + w^2 = 0``."""
    m, k, beta = 1.5, 600.0, 2e-3 if damped else 0.0
    pattern = np.array([[1.0, -1.0], [-1.0, 1.0]])
    K = np.kron(np.eye(2), k * pattern)
    M = m * np.eye(4)
    C = beta * K
    A = np.array([[0.0, 1.0, -1.0, 0.0]])
    sets = all_modes(M, C, K, A)
    assert_agree(sets)
    w2 = np.array([k / m, 2 * k / m])
    lam = (-beta * w2 + 1j * np.sqrt(4 * w2 - beta**2 * w2**2)) / 2
    for md in sets.values():
        assert len(md) == 3
        assert md.eigenvalues[0] == 0 and md.damping_ratio[0] == 0.0
        np.testing.assert_allclose(md.shapes[:, 0], 1 / np.sqrt(4 * m), rtol=1e-12)
        np.testing.assert_allclose(md.eigenvalues[1:], lam, rtol=1e-12)
    gi = sets["generalized-inverse"]
    assert n_reason(gi, SPURIOUS_ZERO) == 2 and np.all(np.abs(gi.spurious) < 1e-6)


def test_free_free_chain_with_a_damper_to_ground():
    """A dashpot from the first mass to ground acts on the rigid-body motion: its zero root is
    simple (one entry) and its decay is a further real root; all formulations agree with the
    roots of ``det(lambda^2 M + lambda C + K)`` of the joined 3-DOF chain."""
    m, k, c0 = 1.0, 1.0, 0.3
    K = np.kron(np.eye(2), k * np.array([[1.0, -1.0], [-1.0, 1.0]]))
    M, C = m * np.eye(4), np.zeros((4, 4))
    C[0, 0] = c0
    A = np.array([[0.0, 1.0, -1.0, 0.0]])
    sets = all_modes(M, C, K, A)
    assert_agree(sets, rtol=1e-10)
    P = [[[m, c0, k], [0, 0, -k], [0]], [[0, 0, -k], [2 * m, 0, 2 * k], [0, 0, -k]],
         [[0], [0, 0, -k], [m, 0, k]]]
    p = polynomial_det(P)
    assert p.size == 7 and p[-1] == 0.0  # degree 6, one zero root
    roots = np.roots(p[:-1])
    exact = np.concatenate([[0.0], roots[roots.imag >= 0]])
    exact = exact[np.lexsort((exact.real, np.abs(exact)))]
    for md in sets.values():
        assert len(md) == exact.size == 4  # 0, one real decay, two complex pairs
        np.testing.assert_allclose(md.eigenvalues, exact, rtol=1e-9, atol=1e-12)
        assert np.sum(md.eigenvalues.imag == 0) == 2


# --------------------------------------------------------------------------------------------
# massless coordinates that no constraint reaches


@pytest.mark.parametrize("c", [0.0, 5.0])
def test_unreached_massless_coordinate(c):
    """Mass ``m`` held by springs ``k1`` (to a massless node ``s``) and ``k2`` (node to ground,
    with a dashpot ``c`` beside it), joined by a constraint to an oscillator ``mb, kb``.  No
    constraint reaches ``s``.  Undamped: one mode, the static condensation
    ``w^2 = (kb + k1 k2 / (k1 + k2)) / (m + mb)``; the roots at ``s`` are infinite and set aside.
    Damped: the cubic ``((m + mb) l^2 + k1 + kb)(c l + k1 + k2) - k1^2 = 0`` (a first-order root
    of the massless dashpot besides the complex pair)."""
    m, mb, k1, k2, kb = 2.0, 1.0, 300.0, 100.0, 50.0
    M = np.diag([m, 0.0, mb])
    K = np.array([[k1, -k1, 0.0], [-k1, k1 + k2, 0.0], [0.0, 0.0, kb]])
    C = np.zeros((3, 3))
    C[1, 1] = c
    A = np.array([[1.0, 0.0, -1.0]])
    sets = all_modes(M, C, K, A)
    assert_agree(sets, rtol=1e-12)
    cubic = np.polysub(np.polymul([m + mb, 0.0, k1 + kb], [c, k1 + k2]), [k1**2])
    roots = np.roots(np.trim_zeros(cubic, "f"))
    exact = roots[roots.imag >= 0]
    exact = exact[np.lexsort((exact.real, np.abs(exact)))]
    for mth, md in sets.items():
        np.testing.assert_allclose(md.eigenvalues, exact, rtol=1e-12)
        assert n_reason(md, INFINITE) >= 1, mth
        assert all(np.isinf(l) or abs(l) > 1e6 for l, r in zip(md.spurious, md.spurious_reason)
                   if INFINITE in r)
    if c == 0.0:
        np.testing.assert_allclose(sets["generalized-inverse"].omega,
                                   np.sqrt((kb + k1 * k2 / (k1 + k2)) / (m + mb)), rtol=1e-14)
        # each unreached massless coordinate: 2 infinite roots (null space: 2 of its 2(n - 1))
        assert n_reason(sets["null-space"], INFINITE) == 2
    w = [1.0, 7.0]
    H = receptance(K, M, C, A, w)
    kc = k1 * (k2 + 1j * np.multiply(w, c)) / (k1 + k2 + 1j * np.multiply(w, c))
    np.testing.assert_allclose(H[:, 0, 0], 1 / (kb + kc - np.square(w) * (m + mb)), rtol=1e-12)
    assert max(receptance_agreement(K, M, C, A, w).values()) < 1e-12
    # eq (10) cannot give the acceleration of a massless coordinate that nothing constrains
    with pytest.raises(ValueError, match="massless coordinates not determined"):
        constrained_acceleration(M, A, np.zeros(1), np.ones(3))


def test_massless_coordinate_attached_to_nothing_is_refused():
    """Not legal: a massless coordinate with no stiffness and no constraint makes the pencil
    singular (every lambda is a root); all formulations say so instead of returning noise."""
    M, K = np.diag([1.0, 0.0]), np.diag([100.0, 0.0])
    for method in FORMULATIONS:
        with pytest.raises(ValueError, match="singular model"):
            coupled_modes(M, None, K, None, method=method)


# --------------------------------------------------------------------------------------------
# badly scaled units


def test_stiffness_1e12_next_to_1():
    """A mass on a ``1e12`` spring with an absorber ``k = 1`` on it (free-free, massless
    boundary joined to the mass): ``m1 m2 w^4 - (m1 k + m2 (k0 + k)) w^2 + k0 k = 0``.  The
    frequencies (about 1 and 1e6) from all formulations; no spurious rigid-body mode (the
    unequilibrated rank test saw one: ``K / max K`` has singular values below ``1e-9``).  QZ
    alone had the low one to ``1e-6`` (GI) and ``8e-6`` (KKT): see ``substruct.analysis.modes.pencil.rayleigh_root``
    and ``_gi_polish``."""
    m1, k0, m2, k = 1.0, 1e12, 1.0, 1.0
    asm = assemble([fixed_free("base", m1, k0), free_free("abs", m2, k)],
                   [Connection(PointRef("base", "mass"), PointRef("abs", "boundary"))])
    exact = np.sqrt(stable_quadratic(m1 * m2, m1 * k + m2 * (k0 + k), k0 * k))
    sets = asm_modes(asm)
    for mth, md in sets.items():
        assert len(md) == 2, (mth, md.omega)
        np.testing.assert_allclose(md.omega, exact, rtol=1e-9)
        assert np.all(md.omega > 0.5)
    # without any constraint, on the stacked 2-DOF system itself
    M = np.diag([m1, m2])
    K = np.array([[k0 + k, -k], [-k, k]])
    for md in all_modes(M, None, K, None).values():
        np.testing.assert_allclose(md.omega, exact, rtol=1e-9)
    w = [0.5, 2.0, 1e5]
    H = receptance(asm.K, asm.M, asm.C, asm.A, w)
    Z = [K - x**2 * M for x in w]
    i_base, i_abs = asm.block("base").start, asm.block("abs").start
    for j, z in enumerate(Z):
        det = z[0, 0] * z[1, 1] - z[0, 1] ** 2
        np.testing.assert_allclose(H[j, i_abs, i_abs], z[0, 0] / det, rtol=1e-9)
        np.testing.assert_allclose(H[j, i_base, i_base], z[1, 1] / det, rtol=1e-9)
    assert max(receptance_agreement(asm.K, asm.M, asm.C, asm.A, w).values()) < 1e-9


def test_units_change_nothing_but_the_units():
    """The same coupled system in kg, N/m and in t, kN/mm (mass x 1e-3, stiffness x 1e6,
    damping x 1e1.5 ...): the frequencies scale by ``sqrt(1e6 / 1e-3)``, the damping ratios do
    not change, for every formulation."""
    M = np.diag([2.0, 0.0, 1.0, 3.0])
    K = np.array([[500.0, -500.0, 0.0, 0.0], [-500.0, 700.0, -200.0, 0.0],
                  [0.0, -200.0, 300.0, -100.0], [0.0, 0.0, -100.0, 100.0]])
    C = 0.02 * K + 0.1 * M
    A = np.array([[0.0, 1.0, 0.0, -1.0]])
    base = all_modes(M, C, K, A)
    assert_agree(base)
    fm, fk = 1e-3, 1e6
    fw = np.sqrt(fk / fm)
    scaled = all_modes(fm * M, np.sqrt(fm * fk) * C, fk * K, 7.0 * A)
    for mth in FORMULATIONS:
        np.testing.assert_allclose(scaled[mth].eigenvalues, fw * base[mth].eigenvalues,
                                   rtol=1e-11)
        np.testing.assert_allclose(scaled[mth].damping_ratio, base[mth].damping_ratio,
                                   rtol=1e-10, atol=1e-13)


def test_penalty_like_stiff_coupling():
    """Two masses joined by a ``1e12`` spring, one on a unit spring to ground, a third DOF tied
    by a constraint: the low mode is the two masses moving together,
    ``w^2 = k / (m1 + m2 + m3)`` to ``O(k / k_c)``; the high one is the stiff spring's.

    Unlike the stiff spring to ground above, a stiff spring in series is ill conditioned in
    the assembled ``K`` itself: the soft mode's strain energy is ``k / k_c = 1e-12`` of
    ``|u|^T |K| |u|``, so ``K u`` (rounded at ``eps |K| |u|``) fixes its frequency to about
    ``eps k_c / k = 2e-4`` in any formulation (measured: 2e-5 .. 7e-5); not a rigid link
    though (``RIGID_ENERGY_TOL``; the rank test alone took it for one)."""
    m1, m2, m3, kc, k = 1.0, 2.0, 0.5, 1e12, 1.0
    M = np.diag([m1, m2, m3])
    K = np.array([[kc, -kc, 0.0], [-kc, kc + k, 0.0], [0.0, 0.0, 0.0]])
    A = np.array([[0.0, 1.0, -1.0]])  # m3 rides on m2
    sets = all_modes(M, None, K, A)
    # the exact quadratic of the constrained 2-DOF system (m1; m2 + m3)
    ma, mb = m1, m2 + m3
    exact = np.sqrt(stable_quadratic(ma * mb, ma * (kc + k) + mb * kc, kc * k))
    for mth, md in sets.items():
        assert len(md) == 2 and md.omega[0] > 0.5, (mth, md.omega)
        np.testing.assert_allclose(md.omega[0], exact[0], rtol=5e-4)
        np.testing.assert_allclose(md.omega[1], exact[1], rtol=1e-12)
        np.testing.assert_allclose(md.shapes[:, 0], md.shapes[0, 0], rtol=1e-9)  # together
    np.testing.assert_allclose(exact[0], np.sqrt(k / (m1 + m2 + m3)), rtol=1e-11)


# --------------------------------------------------------------------------------------------
# repeated eigenvalues


@pytest.mark.parametrize("beta", [0.0, 1e-3])
def test_three_identical_absorbers_on_one_mass(beta):
    """Three identical absorbers ``m, k`` on a mass ``M0, K0``: ``w^2 = k/m`` twice (the
    absorbers move against each other, the mass stands still); the in-phase pair from
    ``(K0 + 3k - w^2 M0)(k - w^2 m) = 3 k^2``.  Stiffness-proportional damping ``beta K``."""
    M0, K0, m, k = 10.0, 4000.0, 1.0, 300.0
    subs = [fixed_free("p", M0, K0, beta * K0)] + \
        [free_free(f"a{i}", m, k, beta * k) for i in range(3)]
    asm = assemble(subs, [Connection(PointRef("p", "mass"), PointRef(f"a{i}", "boundary"))
                          for i in range(3)])
    sets = asm_modes(asm)
    assert_agree(sets)
    w2 = np.concatenate([[k / m, k / m], stable_quadratic(M0 * m, M0 * k + m * (K0 + 3 * k),
                                                          K0 * k)])
    w2.sort()
    lam = (-beta * w2 + 1j * np.sqrt(4 * w2 - beta**2 * w2**2)) / 2
    masses = [asm.block(f"a{i}").start for i in range(3)]
    for mth, md in sets.items():
        np.testing.assert_allclose(md.eigenvalues, lam, rtol=1e-10)
        double = np.flatnonzero(np.isclose(md.omega, np.sqrt(k / m), rtol=1e-8))
        assert double.size == 2, mth
        U = md.shapes[:, double]
        # two independent shapes: primary mass at rest, absorbers summing to zero
        assert np.linalg.matrix_rank(U[masses], tol=1e-6 * np.abs(U).max()) == 2
        assert np.abs(U[asm.block("p").start]).max() < 1e-9 * np.abs(U).max()
        assert np.abs(U[masses].sum(axis=0)).max() < 1e-9 * np.abs(U).max()


@pytest.mark.parametrize("kc", [0.0, 50.0])
def test_two_identical_absorbers_on_a_symmetric_structure(kc):
    """Masses ``M0`` on springs ``K0`` joined by ``kc``, an absorber ``m, k`` on each.  The
    symmetric modes obey ``(K0 - w^2 M0 + k)(k - w^2 m) = k^2``, the antisymmetric ones the same
    with ``K0 + 2 kc``; with ``kc = 0`` every frequency is double."""
    M0, K0, m, k = 5.0, 2000.0, 0.5, 150.0
    M = np.diag([M0, M0, m, 0.0, m, 0.0])
    K = np.zeros((6, 6))
    K[:2, :2] = [[K0 + kc, -kc], [-kc, K0 + kc]]
    pat = k * np.array([[1.0, -1.0], [-1.0, 1.0]])
    K[2:4, 2:4] = pat
    K[4:6, 4:6] = pat
    A = np.array([[1.0, 0.0, 0.0, -1.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0, 0.0, -1.0]])
    sets = all_modes(M, None, K, A)
    assert_agree(sets)
    w2 = []
    for Kp in (K0, K0 + 2 * kc):
        w2.extend(stable_quadratic(M0 * m, M0 * k + m * (Kp + k), Kp * k))
    exact = np.sqrt(np.sort(w2))
    for md in sets.values():
        np.testing.assert_allclose(md.omega, exact, rtol=1e-10)
        for j in range(4):  # every mode symmetric or antisymmetric
            u = md.shapes[:, j]
            s, a = abs(u[0] - u[1]), abs(u[0] + u[1])
            assert min(s, a) < 1e-8 * np.abs(u).max() or kc == 0.0


# --------------------------------------------------------------------------------------------
# heavy non-proportional damping


@pytest.mark.parametrize("zeta", [3.0, 1.0])
def test_overdamped_and_critically_damped(zeta):
    """Two oscillators joined: one DOF ``M l^2 + C l + K = 0`` with ``C = 2 zeta sqrt(K M)``.
    Over-damped: two real entries ``-w (zeta -+ sqrt(zeta^2 - 1))``, each with damping ratio 1
    and ``omega = |lambda|``.  Critically damped: the double root ``-w`` is two real entries for
    every formulation (not one complex pair in one and two real roots in another)."""
    m1, m2, k1, k2 = 1.0, 3.0, 100.0, 300.0
    Mt, Kt = m1 + m2, k1 + k2
    w = np.sqrt(Kt / Mt)
    c_total = 2 * zeta * np.sqrt(Kt * Mt)
    asm = assemble([fixed_free("a", m1, k1, c_total), fixed_free("b", m2, k2)],
                   [Connection(PointRef("a", "mass"), PointRef("b", "mass"))])
    sets = asm_modes(asm)
    if zeta > 1:
        exact = -w * np.array([zeta - np.sqrt(zeta**2 - 1), zeta + np.sqrt(zeta**2 - 1)])
        rtol = 1e-12
    else:
        exact, rtol = -w * np.ones(2), 1e-7  # a double root is known to sqrt(eps)
    for mth, md in sets.items():
        assert len(md) == 2, (mth, md.eigenvalues)
        assert np.all(md.eigenvalues.imag == 0)
        np.testing.assert_allclose(md.eigenvalues.real, exact, rtol=rtol)
        np.testing.assert_allclose(md.omega, np.abs(exact), rtol=rtol)
        np.testing.assert_array_equal(md.damping_ratio, 1.0)


def test_heavy_nonproportional_damping_complex_modes():
    """A 2-DOF chain with a large dashpot on the first mass only, tied by a constraint to a
    third mass: the roots of the quartic ``det(l^2 M + l C + K)`` of the reduced system; one
    complex pair and two real roots; the complex mode shape is not real (non-proportional) and
    ``N^T (l^2 M + l C + K) u = 0`` holds for every mode of every formulation."""
    m1, m2, m3, k1, k2, c1 = 1.0, 1.0, 0.5, 100.0, 100.0, 60.0
    M = np.diag([m1, m2, m3])
    K = np.array([[k1 + k2, -k2, 0.0], [-k2, k2, 0.0], [0.0, 0.0, 0.0]])
    C = np.zeros((3, 3))
    C[0, 0] = c1
    A = np.array([[0.0, 1.0, -1.0]])
    sets = all_modes(M, C, K, A)
    assert_agree(sets, rtol=1e-11)
    P = [[[m1, c1, k1 + k2], [-k2]], [[-k2], [m2 + m3, 0.0, k2]]]
    roots = np.roots(polynomial_det(P))
    roots = np.array([refine_root(polynomial_det(P), r) for r in roots])
    exact = roots[roots.imag >= -1e-12]
    exact = np.where(np.abs(exact.imag) < 1e-9, exact.real, exact)
    exact = exact[np.lexsort((exact.real, np.abs(exact)))]
    N = null_space_basis(A)
    for mth, md in sets.items():
        np.testing.assert_allclose(md.eigenvalues, exact, rtol=1e-11)
        assert np.sum(md.eigenvalues.imag == 0) == 2 and np.sum(md.eigenvalues.imag > 0) == 1
        for lam, u in zip(md.eigenvalues, md.shapes.T):
            r = N.T @ ((lam**2) * M + lam * C + K) @ u
            assert np.linalg.norm(r) < 1e-10 * np.linalg.norm(K) * np.linalg.norm(u), mth
        u = md.shapes[:, md.eigenvalues.imag > 0][:, 0]
        assert np.abs(u.imag).max() > 1e-3 * np.abs(u).max()  # a complex mode


# --------------------------------------------------------------------------------------------
# the accuracy limit shared by all formulations


@pytest.mark.parametrize("c0", [1e-1, 1e-2, 1e-4, 1e-6])
def test_slow_decay_of_a_nearly_free_rigid_body(c0):
    """A weak dashpot ``c0`` from the free-free chain ``m, 2m, m`` to ground: the rigid-body
    motion decays at about ``-c0 / 4m``, a root ``|lambda| / |lambda|_max ~ c0 / 5.7`` next to
    the zero root.  QZ gets such a root to ``eps (|lambda|_max / |lambda|)^2`` only (the pair
    ``0``, ``-c0/4m`` tends to a Jordan block; the paper's pencil has its spurious zeros there
    too): before the Rayleigh refinement the relative errors of (GI, KKT) were (3e-10, 1e-8) at
    ``c0 = 1e-3``, (2e-7, 1e-7) at ``1e-4``, and at ``1e-5`` the paper's pencil lost the root
    (its vector's ``|A u|`` was ``1e-6``).  Reference: Newton on the exact characteristic
    polynomial."""
    m, k = 1.0, 1.0
    K = np.kron(np.eye(2), k * np.array([[1.0, -1.0], [-1.0, 1.0]]))
    M, C = m * np.eye(4), np.zeros((4, 4))
    C[0, 0] = c0
    A = np.array([[0.0, 1.0, -1.0, 0.0]])
    P = [[[m, c0, k], [0, 0, -k], [0]], [[0, 0, -k], [2 * m, 0, 2 * k], [0, 0, -k]],
         [[0], [0, 0, -k], [m, 0, k]]]
    p = np.trim_zeros(polynomial_det(P), "b")  # lambda x (quintic)
    slow = refine_root(p, -c0 / (4 * m))
    for mth, md in all_modes(M, C, K, A).items():
        assert len(md) == 4, mth
        assert md.eigenvalues[0] == 0
        np.testing.assert_allclose(md.eigenvalues[1], slow, rtol=1e-10, err_msg=mth)
