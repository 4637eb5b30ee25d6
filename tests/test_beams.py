"""3D beam elements and frames against closed forms, with measured convergence orders.

* Euler-Bernoulli cantilever (``beta_n L = 1.8751, 4.6941, 7.8548``) in both bending planes
  with ``Iy != Iz``, its axial ``(2i-1) pi/2 sqrt(E/rho)/L`` and torsional
  ``(2i-1) pi/2 sqrt(G J/(rho Ip))/L`` modes, clamped by rows of ``A`` so that the three
  formulations of the coupled problem check each other;
* free-free beam: six rigid-body modes, then ``beta L = 4.7300, 7.8532`` in each plane;
* the frequency error of consistent-mass elements falls like ``h^4``, of lumped-mass elements
  like ``h^2``, to the same limit;
* Timoshenko: a thick pinned-pinned beam against the Timoshenko frequency equation, and the
  ratio to Euler-Bernoulli tending to 1 like ``(r/L)^2`` as the slenderness grows;
* end releases (pin flags): a clamped-clamped member with hinged ends is a pinned-pinned beam.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla

from substruct.analysis.api import modes
from substruct.assembly import LinearConstraint, PointRef, assemble
from substruct.models.beam import Material, Section, bending_matrices, rotation
from substruct.models.frame import Beam, frame

SEC = Section(A=0.02, Iy=2e-5, Iz=5e-5, J=3e-5)
MAT = Material(E=2.1e11, G=8.1e10, rho=7850.0)
L = 2.0
CANTILEVER = np.array([1.875104068711961, 4.694091132974175, 7.854757438237613])
FREE_FREE = np.array([4.730040744862704, 7.853204624095838])
GROUPS = {"axial": ("ux",), "torsion": ("rx",), "xy": ("uy", "rz"), "xz": ("uz", "ry")}


def bending(beta: np.ndarray, I: float, length: float = L) -> np.ndarray:
    """Euler-Bernoulli circular frequencies ``beta^2 sqrt(E I / (rho A)) / L^2``."""
    return beta**2 * np.sqrt(MAT.E * I / (MAT.rho * SEC.A)) / length**2


def straight(n: int, direction=(1.0, 0.0, 0.0), orientation=(0.0, 1.0, 0.0), **kw):
    """A straight member of length L from node 1 to node 2, in ``n`` elements."""
    d = np.asarray(direction, float) / np.linalg.norm(direction)
    beam = Beam((1, 2), kw.pop("section", SEC), MAT, orientation, divisions=n,
                theory=kw.pop("theory", "euler-bernoulli"), pin_a=kw.pop("pin_a", ""),
                pin_b=kw.pop("pin_b", ""))
    return frame("beam", {1: (0.0, 0.0, 0.0), 2: tuple(L * d)}, [beam], **kw)


def classify(sub, shapes: np.ndarray, R: np.ndarray = np.eye(3)) -> list[str]:
    """The action (axial, torsion, x-y or x-z bending in the local axes, rows of ``R``) that
    holds most of each mode shape."""
    nodes = {lab.split(":")[0]: k for k, lab in enumerate(dict.fromkeys(
        lab.split(":")[0] for lab in sub.dof_labels))}
    where = [(nodes[lab.split(":")[0]], ("ux", "uy", "uz", "rx", "ry", "rz").index(
        lab.split(":")[1])) for lab in sub.dof_labels]
    out = []
    for u in np.real(shapes).T:
        full = np.zeros((6, len(nodes)))
        for value, (node, c) in zip(u, where):
            full[c, node] = value
        t, r = R @ full[:3], R @ full[3:]
        share = {"axial": t[0] @ t[0], "torsion": r[0] @ r[0], "xy": t[1] @ t[1] + r[2] @ r[2],
                 "xz": t[2] @ t[2] + r[1] @ r[1]}
        out.append(max(share, key=share.__getitem__))
    return out


def lowest(sub, k: int) -> np.ndarray:
    """The ``k`` lowest circular frequencies of the condensed ``K, M`` (dense, independent of
    the coupled solvers)."""
    lam = sla.eigh(sub.K.toarray(), sub.M.toarray(), eigvals_only=True, subset_by_index=[0, k - 1])
    return np.sqrt(np.abs(lam))


def test_element_matrices_are_the_textbook_closed_forms():
    """Timoshenko stiffness (Przemieniecki) and Euler-Bernoulli consistent mass (L/420 table)
    from the quadrature of the interdependent shape functions."""
    Le, EI, kGA = 0.7, 3.0, 11.0
    phi = 12 * EI / (kGA * Le**2)
    K, _ = bending_matrices(Le, EI, kGA, 1.0, 0.0)
    ref = EI / ((1 + phi) * Le**3) * np.array([
        [12, 6 * Le, -12, 6 * Le], [6 * Le, (4 + phi) * Le**2, -6 * Le, (2 - phi) * Le**2],
        [-12, -6 * Le, 12, -6 * Le], [6 * Le, (2 - phi) * Le**2, -6 * Le, (4 + phi) * Le**2]])
    assert np.abs(K - ref).max() <= 1e-13 * np.abs(ref).max()
    _, M = bending_matrices(Le, EI, None, 2.0, 0.0)
    ref = 2.0 * Le / 420 * np.array([
        [156, 22 * Le, 54, -13 * Le], [22 * Le, 4 * Le**2, 13 * Le, -3 * Le**2],
        [54, 13 * Le, 156, -22 * Le], [-13 * Le, -3 * Le**2, -22 * Le, 4 * Le**2]])
    assert np.abs(M - ref).max() <= 1e-13 * np.abs(ref).max()
    R = rotation([1, 2, 3], [2, 4, 5], [0, 0, 1])
    assert np.abs(R @ R.T - np.eye(3)).max() < 1e-14
    assert R[1] @ np.cross(R[0], [0, 0, 1]) == pytest.approx(0.0, abs=1e-14)  # y in (x, v)


def test_cantilever_both_planes_axial_and_torsion_clamped_by_rows_of_A():
    n = 16
    sub = straight(n)
    clamp = [LinearConstraint(((PointRef("beam", f"1:{c}"), 1.0),), name=f"clamp {c}")
             for c in ("ux", "uy", "uz", "rx", "ry", "rz")]
    asm = assemble([sub], [], clamp)
    res = modes(asm.M, None, asm.K, asm.A, 30, checks=("null-space", "kkt"))
    assert max(res.agreement.values()) < 1e-9
    kinds = np.array(classify(sub, res.shapes))
    c_axial = np.sqrt(MAT.E / MAT.rho) / L
    c_twist = np.sqrt(MAT.G * SEC.J / (MAT.rho * SEC.polar)) / L
    odd = (2 * np.arange(1, 3) - 1) * np.pi / 2
    expect = {"xz": bending(CANTILEVER, SEC.Iy), "xy": bending(CANTILEVER, SEC.Iz),
              "axial": odd * c_axial, "torsion": odd * c_twist}
    for kind, ref in expect.items():
        got = res.omega[kinds == kind][:len(ref)]
        assert got.size == ref.size, kind
        # h^4 bending error (beta_3 h = 0.98: 2e-4), h^2 for the linear axial/torsion elements
        tol = 3e-4 if kind in ("xy", "xz") else 0.5 * (ref[-1] * L / n / c_axial) ** 2
        assert np.all(abs(got / ref - 1) < tol), (kind, got / ref - 1)
    assert bending(CANTILEVER, SEC.Iy)[0] < bending(CANTILEVER, SEC.Iz)[0]


def test_free_free_beam_has_six_rigid_modes_then_the_closed_forms():
    sub = straight(24, direction=(1.0, 2.0, -0.5), orientation=(0.3, 0.0, 1.0))
    res = modes(sub.M, None, sub.K, None, 12, checks=("null-space",))
    first = bending(FREE_FREE, SEC.Iy)[0]
    assert np.all(res.omega[:6] < 1e-6 * first)
    assert res.omega[6] > 0.5 * first
    R = rotation([0, 0, 0], [1.0, 2.0, -0.5], [0.3, 0.0, 1.0])
    kinds = np.array(classify(sub, res.shapes[:, 6:], R))
    for kind, I in (("xz", SEC.Iy), ("xy", SEC.Iz)):
        got = res.omega[6:][kinds == kind][:2]
        assert np.all(abs(got / bending(FREE_FREE, I) - 1) < 2e-4), (kind, got)


def rates(errors: list[np.ndarray]) -> np.ndarray:
    e = np.asarray(errors)
    return np.log2(e[:-1] / e[1:])


def test_convergence_orders_consistent_h4_lumped_h2_to_the_same_limit():
    """Cantilever bending in the x-y plane, first three modes, h halved 4 -> 32 elements.

    The consistent-mass error of the first mode reaches the round-off of the dense eigen solve
    (``eps`` times the condition of ``K``, ~1e-9 at 32 elements) after 16 elements: its rate is
    measured from 8 to 16 elements, that of modes 2 and 3 from 16 to 32."""
    ref = bending(CANTILEVER, SEC.Iz)
    errs: dict[str, list[np.ndarray]] = {"consistent": [], "lumped": []}
    for n in (4, 8, 16, 32):
        for mass in errs:
            sub = straight(n, supports={1: None}, mass=mass)
            w = lowest(sub, 12)
            kinds = np.array(classify(sub, sla.eigh(sub.K.toarray(), sub.M.toarray(),
                                                     subset_by_index=[0, 11])[1]))
            errs[mass].append(abs(w[kinds == "xy"][:3] / ref - 1))
    p_c = rates(errs["consistent"])
    p_l = rates(errs["lumped"])
    assert abs(p_c[1, 0] - 4) < 0.05 and np.all(abs(p_c[2, 1:] - 4) < 0.05), p_c
    assert np.all(abs(p_l[-1] - 2) < 0.05), p_l
    assert np.all(errs["consistent"][-1] < 3e-6)
    assert np.all(errs["lumped"][-1] < 6e-3)


def timoshenko_ss(n_mode: int, L_: float, I: float, A: float, kappa: float) -> float:
    """Lower root of the pinned-pinned Timoshenko frequency equation (shape ``sin k x``):
    ``(kGA k^2 - rho A w^2)(E I k^2 + kGA - rho I w^2) = (kGA k)^2``."""
    k = n_mode * np.pi / L_
    kGA = kappa * MAT.G * A
    a = MAT.rho**2 * A * I
    b = -(MAT.rho * A * (MAT.E * I * k**2 + kGA) + MAT.rho * I * kGA * k**2)
    c = kGA * k**2 * MAT.E * I * k**2
    return float(np.sqrt((-b - np.sqrt(b * b - 4 * a * c)) / (2 * a)))


def pinned(n: int, depth: float, theory: str, length: float = L):
    """Pinned-pinned square-section beam of side ``depth`` (v = w = 0 at both ends, the axial
    and twist motion held at node 1)."""
    sec = Section(A=depth**2, Iy=depth**4 / 12, Iz=depth**4 / 12, J=0.141 * depth**4)
    beam = Beam((1, 2), sec, MAT, (0.0, 1.0, 0.0), theory=theory, divisions=n)
    sub = frame("ss", {1: (0.0, 0.0, 0.0), 2: (length, 0.0, 0.0)}, [beam],
                supports={1: "1234", 2: "23"})
    return sub, sec


def xy_modes(sub, k: int) -> np.ndarray:
    lam, vec = sla.eigh(sub.K.toarray(), sub.M.toarray(), subset_by_index=[0, 3 * k + 3])
    kinds = np.array(classify(sub, vec))
    return np.sqrt(lam[kinds == "xy"][:k])


def test_thick_timoshenko_beam_against_its_frequency_equation():
    """The error falls like h^2 (the element's shear strain is constant along it), from
    2.4e-2 (mode 3, 8 elements) to 1.5e-3 at 32."""
    depth = L / 5  # slenderness L/r = 17
    ref = np.array([timoshenko_ss(i, L, depth**4 / 12, depth**2, 5 / 6) for i in (1, 2, 3)])
    eb = bending(np.pi * np.arange(1, 4), depth**4 / 12) * np.sqrt(SEC.A / depth**2)
    assert np.all(ref < 0.97 * eb)  # thick: shear and rotary inertia matter
    errs = []
    for n in (8, 16, 32):
        sub, _ = pinned(n, depth, "timoshenko")
        errs.append(abs(xy_modes(sub, 3) / ref - 1))
    p = rates(errs)
    assert np.all(abs(p - 2) < 0.05), p
    assert np.all(errs[-1] < 2e-3), errs[-1]


def test_timoshenko_tends_to_euler_bernoulli_as_slenderness_grows():
    """The first-mode ratio Timoshenko / Euler-Bernoulli is ``1 - c (r/L)^2 + ...``: the gap
    falls by 4 each time the depth is halved."""
    gaps = []
    for depth in (0.2, 0.1, 0.05):
        wt = xy_modes(pinned(32, depth, "timoshenko")[0], 1)[0]
        we = xy_modes(pinned(32, depth, "euler-bernoulli")[0], 1)[0]
        ref = timoshenko_ss(1, L, depth**4 / 12, depth**2, 5 / 6)
        assert abs(wt / ref - 1) < 1e-5
        gaps.append(1 - wt / we)
    assert np.all(np.array(gaps) > 0)
    assert np.all(abs(np.log2(np.array(gaps[:-1]) / gaps[1:]) - 2) < 0.05), gaps


def test_hinged_ends_make_a_clamped_member_pinned_pinned():
    n = 16
    sub = straight(n, supports={1: None, 2: None}, pin_a="56", pin_b="56")
    w = xy_modes(sub, 2)
    ref = bending(np.pi * np.arange(1, 3), SEC.Iz)
    assert np.all(abs(w / ref - 1) < 1e-4), w / ref - 1
    with pytest.raises(ValueError, match="mechanism"):
        frame("bad", {1: (0, 0, 0), 2: (1, 0, 0)},
              [Beam((1, 2), SEC, MAT, (0, 1, 0), pin_a="4", pin_b="4")])


@pytest.mark.parametrize("kwargs, match", [
    ({"orientation": (2.0, 0.0, 0.0)}, "parallel"),
    ({"nodes": (1, 3)}, "two different nodes"),
    ({"divisions": 0}, "divisions"),
    ({"theory": "bernoulli"}, "theory"),
])
def test_bad_members_are_refused(kwargs, match):
    args = {"nodes": (1, 2), "section": SEC, "material": MAT, "orientation": (0, 1, 0), **kwargs}
    with pytest.raises(ValueError, match=match):
        frame("bad", {1: (0, 0, 0), 2: (1, 0, 0)}, [Beam(**args)])


# ------------------------------------------------------------------- the case door


def cantilever_case(**member) -> dict:
    """A cantilever as a ``type: frame`` case, carrying a point mass at its tip."""
    return {
        "name": "frame_cantilever",
        "substructures": [
            {"name": "c", "type": "frame", "nodes": {1: [0, 0, 0], 2: [L, 0, 0]},
             "materials": {"steel": {"E": MAT.E, "G": MAT.G, "rho": MAT.rho}},
             "sections": {"s": {"A": SEC.A, "Iy": SEC.Iy, "Iz": SEC.Iz, "J": SEC.J}},
             "members": [{"nodes": [1, 2], "section": "s", "material": "steel",
                          "orientation": [0, 1, 0], "divisions": 16, **member}],
             "supports": {1: "123456"}},
            {"name": "tip", "type": "mass", "mass": 5.0}],
        "connections": [["c@2:uz", "tip"]],
        "analysis": {"modes": {"count": 4, "check": ["null-space", "kkt"]}},
    }


def test_a_frame_case_is_the_cantilever_with_a_tip_mass():
    """The lowest x-z bending frequency with a tip mass ``m_t`` against the root of the
    Euler-Bernoulli frequency equation
    ``1 + cos b cosh b + (m_t / (rho A L)) b (cos b sinh b - sin b cosh b) = 0``."""
    import yaml
    from scipy.optimize import brentq

    from substruct.case.loader import parse_case
    from substruct.run.runner import run_case

    case = parse_case(yaml.safe_dump(cantilever_case(), sort_keys=False), "cases/x.yaml",
                      Path("."), ())
    res = run_case(case).modes
    ratio = 5.0 / (MAT.rho * SEC.A * L)
    beta = brentq(lambda b: 1 + np.cos(b) * np.cosh(b) + ratio * b * (
        np.cos(b) * np.sinh(b) - np.sin(b) * np.cosh(b)), 0.5, 1.875)
    # x-y plane (Iz, no tip mass on it) and x-z plane (Iy, with the tip mass)
    expect = sorted([bending(np.array([beta]), SEC.Iy)[0], bending(CANTILEVER[:1], SEC.Iz)[0]])
    assert np.all(abs(res.omega[:2] / expect - 1) < 1e-5), res.omega[:2] / expect - 1


@pytest.mark.parametrize("change, field, problem", [
    ({"section": "t"}, "substructures.c.members[0].section: no section", "got 't'"),
    ({"orientation": [1, 0, 0]}, "substructures.c.members[0]: orientation", "parallel"),
    ({"pin_a": "7"}, "substructures.c.members[0].pin_a: pin flags", "got '7'"),
    ({"pin_a": "4", "pin_b": "4", "divisions": 1}, "members[0]: releasing", "mechanism"),
])
def test_bad_frame_cases_name_the_field(change, field, problem):
    import yaml

    from substruct.case.loader import CaseError, parse_case
    from substruct.run.runner import build_model

    with pytest.raises(CaseError) as info:
        build_model(parse_case(yaml.safe_dump(cantilever_case(**change), sort_keys=False),
                               "cases/x.yaml", Path("."), ()))
    message = str(info.value)
    assert "\n" not in message and field in message and problem in message, message
