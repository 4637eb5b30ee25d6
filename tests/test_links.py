"""Rigid, interpolation and multi-point links as rows of ``A``, against independent references.

* two cantilever halves joined by a rigid link (or by multi-point constraints) at coincident
  nodes have the frequencies of the continuous beam;
* a rigid body (6 x 6 mass about a node) held through rigid links with offsets by twelve
  grounded springs: the 6 x 6 closed form ``K_rb = sum k a a^T``, ``a = [e_c; r x e_c]``;
* an interpolation link gives the reference node the weighted least-squares rigid fit of the
  nodes' translations (computed here with ``numpy.linalg.lstsq``), refuses components that a
  collinear set does not determine, and adds no stiffness;
* a coordinate made dependent twice is refused.

The coupled modes are computed by the main formulation and checked by the two others.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

from substruct.analysis.api import modes
from substruct.assembly import Connection, PointRef, assemble
from substruct.assembly.links import (LinkError, NodeRef, interpolation_link, link_constraints,
                                      mpc, rigid_link)
from substruct.models.beam import Material, Section
from substruct.models.discrete import spring
from substruct.models.frame import FRAME_COMPONENTS, Beam, frame

SEC = Section(A=0.02, Iy=2e-5, Iz=5e-5, J=3e-5)
MAT = Material(E=2.1e11, G=8.1e10, rho=7850.0)
L = 2.0
CHECKS = ("null-space", "kkt")


def member(name: str, a: int, b: int, xa: float, xb: float, n: int, **kw):
    return frame(name, {a: (xa, 0.0, 0.0), b: (xb, 0.0, 0.0)},
                 [Beam((a, b), SEC, MAT, (0.0, 1.0, 0.2), divisions=n)], **kw)


def continuous(count: int) -> np.ndarray:
    whole = member("whole", 1, 4, 0.0, L, 16, supports={1: None})
    return modes(whole.M, None, whole.K, None, count).omega


def coupled(subs, links, count: int, connections=()):
    asm = assemble(subs, connections, link_constraints(links))
    res = modes(asm.M, None, asm.K, asm.A, count, checks=CHECKS)
    assert max(res.agreement.values()) < 1e-9
    return res


def test_two_halves_joined_by_a_rigid_link_are_the_continuous_beam():
    a = member("a", 1, 2, 0.0, L / 2, 8, supports={1: None})
    b = member("b", 3, 4, L / 2, L, 8)
    link = rigid_link([a, b], NodeRef("a", {"node": 2}), [NodeRef("b", {"at": [L / 2, 0, 0]})])
    assert len(link.constraints) == 6
    res = coupled([a, b], [link], 12)
    ref = continuous(12)
    assert np.abs(res.omega / ref - 1).max() < 1e-9


def test_multi_point_constraints_join_the_halves_the_same_way():
    a = member("a", 1, 2, 0.0, L / 2, 8, supports={1: None})
    b = member("b", 3, 4, L / 2, L, 8)
    links = [mpc([a, b], [(NodeRef("b", {"node": 3}), c, 2.0), (NodeRef("a", {"node": 2}), c,
                                                                  -2.0)], name=f"mpc {c}")
             for c in "123456"]
    res = coupled([a, b], links, 12)
    assert np.abs(res.omega / continuous(12) - 1).max() < 1e-9


def test_rigid_body_on_springs_through_rigid_links_is_the_6x6_closed_form():
    rng = np.random.default_rng(7)
    xc = np.array([0.3, -0.2, 0.5])
    corners = xc + np.array([[0.8, 0.5, -0.3], [-0.7, 0.6, -0.2], [-0.6, -0.5, 0.4],
                             [0.5, -0.7, 0.3]])
    m = 12.0
    B = rng.normal(size=(3, 3))
    J = B @ B.T + 2.0 * np.eye(3)  # a full inertia tensor about the centre of mass
    e = np.array([0.2, -0.1, 0.15])  # the centre of mass, off the node
    T = np.block([[np.eye(3), -skew(e)], [np.zeros((3, 3)), np.eye(3)]])
    Mrb = T.T @ sla.block_diag(m * np.eye(3), J) @ T  # about the node: u_cm = u + theta x e
    nodes = {0: tuple(xc), **{k + 1: tuple(p) for k, p in enumerate(corners)}}
    body = frame("body", nodes, [], node_masses={0: Mrb})
    stiff = rng.uniform(1e4, 5e4, size=(4, 3))
    springs, connections = [], []
    Krb = np.zeros((6, 6))
    for k, p in enumerate(corners):
        for c in range(3):
            s = spring(f"s{k}{c}", stiff[k, c], grounded=True)
            springs.append(s)
            connections.append(Connection(PointRef(s.name, "i"),
                                          PointRef("body", f"{k + 1}:{'xyz'[c]}")))
            e = np.eye(3)[c]
            a = np.concatenate([e, np.cross(p - xc, e)])
            Krb += stiff[k, c] * np.outer(a, a)
    link = rigid_link([body], NodeRef("body", {"node": 0}),
                      [NodeRef("body", {"node": k}) for k in range(1, 5)])
    res = coupled([body, *springs], [link], 6, connections)
    ref = np.sqrt(sla.eigh(Krb, Mrb, eigvals_only=True))
    assert np.abs(res.omega / ref - 1).max() < 1e-9


def skew(r: np.ndarray) -> np.ndarray:
    """``[r]_x`` with ``[r]_x v = r x v``."""
    return np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])


def fit(offsets: np.ndarray, u: np.ndarray, w: np.ndarray, own: list[int]) -> np.ndarray:
    """``argmin sum_j w_j |(u_j - u_r - theta x r_j)_own|^2`` by numpy's lstsq."""
    rows, rhs = [], []
    for r, uj, wj in zip(offsets, u, w):
        S = np.hstack([np.eye(3), -skew(r)])
        rows.append(np.sqrt(wj) * S[own])
        rhs.append(np.sqrt(wj) * uj[own])
    return np.linalg.lstsq(np.vstack(rows), np.concatenate(rhs), rcond=None)[0]


@pytest.mark.parametrize("own, comps", [("123", "123456"), ("13", "13456")])
def test_interpolation_link_is_the_weighted_least_squares_fit(own, comps):
    """With the nodes' x and z only, the reference's y never enters the fit: it is left out
    (and refused if asked, as the last lines check)."""
    rng = np.random.default_rng(3)
    pts = rng.uniform(-1.0, 1.0, size=(6, 3)) * [3.0, 2.0, 1.0]
    xr = np.array([0.4, 0.9, -0.3])  # away from the weighted centroid
    w = np.array([1.0, 2.0, 0.5, 3.0, 1.5, 0.7])
    cloud = frame("cloud", {k + 1: tuple(p) for k, p in enumerate(pts)}, [])
    ref = frame("ref", {100: tuple(xr)}, [])
    link = interpolation_link([cloud, ref], NodeRef("ref", {"node": 100}),
                              [NodeRef("cloud", {"node": k + 1}) for k in range(6)], w,
                              components=comps, node_components=own)
    asm = assemble([cloud, ref], [], link_constraints([link]))
    A = asm.A.toarray()
    u = rng.normal(size=(6, 3))
    q = np.zeros(asm.n_dof)
    for k in range(6):
        for c in range(3):
            q[asm.dof_labels.index(f"cloud.{k + 1}:{'u' + 'xyz'[c]}")] = u[k, c]
    cols = [asm.dof_labels.index(f"ref.100:{FRAME_COMPONENTS[int(c) - 1]}") for c in comps]
    got = np.linalg.solve(A[:, cols], -A @ q)
    expect = fit(pts - xr, u, w, [int(c) - 1 for c in own])[[int(c) - 1 for c in comps]]
    assert np.abs(got - expect).max() < 1e-12 * np.abs(expect).max()
    if own == "13":
        with pytest.raises(LinkError, match="component uy of the reference"):
            interpolation_link([cloud, ref], NodeRef("ref", {"node": 100}),
                               [NodeRef("cloud", {"node": k + 1}) for k in range(6)], w,
                               node_components=own)


def test_interpolation_link_refuses_what_collinear_nodes_do_not_determine():
    line = frame("line", {k: (float(k), 0.0, 0.0) for k in range(1, 4)}, [])
    on = frame("on", {9: (1.5, 0.0, 0.0)}, [])
    off = frame("off", {9: (1.5, 1.0, 0.0)}, [])
    nodes = [NodeRef("line", {"node": k}) for k in range(1, 4)]
    with pytest.raises(LinkError, match="component rx of the reference"):
        interpolation_link([line, on], NodeRef("on", {"node": 9}), nodes)
    link = interpolation_link([line, on], NodeRef("on", {"node": 9}), nodes, components="12356")
    assert len(link.constraints) == 5
    with pytest.raises(LinkError, match="component uz of the reference"):
        interpolation_link([line, off], NodeRef("off", {"node": 9}), nodes, components="123")


def test_interpolation_link_adds_no_stiffness():
    """A massless reference node on the axis beyond the tip, linked to the last three nodes of
    a cantilever: the coupled modes are the cantilever's."""
    beam = member("beam", 1, 2, 0.0, L, 16, supports={1: None})
    ref = frame("ref", {50: (L + 0.3, 0.0, 0.0)}, [], supports={50: "4"})
    tip = [NodeRef("beam", {"at": [L * (1 - k / 16), 0.0, 0.0]}) for k in range(3)]
    link = interpolation_link([beam, ref], NodeRef("ref", {"node": 50}), tip, [1.0, 2.0, 1.0],
                              components="12356")
    res = coupled([beam, ref], [link], 10)
    alone = modes(beam.M, None, beam.K, None, 10).omega
    assert np.abs(res.omega / alone - 1).max() < 1e-9


def test_a_coordinate_dependent_twice_is_refused():
    a = member("a", 1, 2, 0.0, 1.0, 1)
    b = member("b", 3, 4, 1.0, 2.0, 1)
    one = rigid_link([a, b], NodeRef("a", {"node": 2}), [NodeRef("b", {"node": 3})], "123")
    two = mpc([a, b], [(NodeRef("b", {"at": [1.0, 0.0, 0.0]}), "uy", 1.0),
                       (NodeRef("a", {"node": 1}), "uy", -1.0)], name="second")
    with pytest.raises(LinkError, match="already dependent in rigid link"):
        link_constraints([one, two])
    with pytest.raises(LinkError, match="no node component 'rq'"):
        rigid_link([a, b], NodeRef("a", {"node": 2}), [NodeRef("b", {"node": 3})], ["rq"])
    with pytest.raises(LinkError, match="no node 7"):
        rigid_link([a, b], NodeRef("a", {"node": 2}), [NodeRef("b", {"node": 7})])


def test_supported_dependent_coordinates_are_not_dependent_twice():
    """Two links whose dependent coordinates are supported (empty rows) used to share one
    empty-pattern key and were refused as 'already dependent'; they are kept, and their rows
    hold the independent nodes: two clamped stubs rigidly tied to one free node clamp it."""
    a = member("a", 1, 2, 0.0, 1.0, 1, supports={1: None, 2: None})
    b = member("b", 3, 4, 1.0, 2.0, 2, supports={4: None})
    c = member("c", 5, 6, 1.0, 2.0, 2, supports={6: None})
    one = rigid_link([a, b, c], NodeRef("b", {"node": 3}), [NodeRef("a", {"node": 2})],
                     name="one")
    two = rigid_link([a, b, c], NodeRef("c", {"node": 5}), [NodeRef("a", {"node": 2})],
                     name="two")
    assert all(key is None for _, key in one.dependent + two.dependent)
    rows = link_constraints([one, two])
    assert len(rows) == 12
    # node 3 of b and node 5 of c are held by the rows: each member is clamped-clamped
    asm = assemble([a, b, c], (), rows)
    res = modes(asm.M, None, asm.K, asm.A, 4, checks=CHECKS)
    alone = member("alone", 3, 4, 1.0, 2.0, 2, supports={3: None, 4: None})
    ref = modes(alone.M, None, alone.K, None, 2).omega
    np.testing.assert_allclose(res.omega[:4], np.repeat(ref, 2), rtol=1e-9)
    # a free dependent coordinate twice is still refused
    free = member("f", 7, 8, 1.0, 2.0, 1)
    three = rigid_link([b, free], NodeRef("b", {"node": 3}), [NodeRef("f", {"node": 7})],
                       name="three")
    four = rigid_link([c, free], NodeRef("c", {"node": 5}), [NodeRef("f", {"node": 7})],
                      name="four")
    with pytest.raises(LinkError, match="already dependent in three"):
        link_constraints([three, four])
