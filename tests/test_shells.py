"""Flat shells (DKT/DKQ bending, CST/QM6 membrane, drilling penalty) against closed forms and
tabulated plate frequencies, the patch tests, and shells sharing nodes with beams.

References:
* Navier: a simply supported rectangular Kirchhoff plate, ``omega_mn = pi^2 (m^2/a^2 +
  n^2/b^2) sqrt(D / (rho t))``, ``D = E t^3 / 12 (1 - nu^2)``.
* Leissa, A. W. (1973), The free vibration of rectangular plates, J. Sound Vib. 31(3),
  257-293: the square cantilever plate (one edge clamped, three free), nu = 0.3,
  ``omega a^2 sqrt(rho t / D) = 3.4917, 8.5246, 21.429, 27.331, 31.111`` (36-term Ritz).
"""

from __future__ import annotations

import numpy as np
import pytest

from substruct.analysis.api import modes
from substruct.models.beam import Material, Section
from substruct.models.frame import Beam, frame
from substruct.models.shell import shell_matrices
from substruct.models.shell_mesh import Shell

E, NU, RHO = 2.1e11, 0.3, 7800.0
MAT = Material(E=E, G=E / (2 * (1 + NU)), rho=RHO)
LEISSA_CFFF = np.array([3.4917, 8.5246, 21.429, 27.331, 31.111])


def stiffness(t: float) -> float:
    return E * t**3 / (12 * (1 - NU**2))


def plate(n: int, t: float, kind: str = "quad", mass: str = "consistent", edges: str = "ss",
          a: float = 1.0, b: float = 1.0):
    """An ``n x n`` plate in the x-y plane, element by element (quads, or two triangles per
    cell); ``edges``: ``ss`` (w and the rotation along each edge held) or ``cantilever``
    (x = 0 clamped); in-plane motion held (it is uncoupled from bending)."""
    def nid(i: int, j: int) -> int:
        return 1 + i * (n + 1) + j

    nodes = {nid(i, j): (a * i / n, b * j / n, 0.0) for i in range(n + 1) for j in range(n + 1)}
    shells = []
    for i in range(n):
        for j in range(n):
            q = (nid(i, j), nid(i + 1, j), nid(i + 1, j + 1), nid(i, j + 1))
            if kind == "quad":
                shells.append(Shell(q, t, MAT))
            else:
                shells += [Shell((q[0], q[1], q[2]), t, MAT), Shell((q[0], q[2], q[3]), t, MAT)]
    sup = {}
    for i in range(n + 1):
        for j in range(n + 1):
            held = {1, 2, 6}
            if edges == "ss":
                held |= ({3, 4} if i in (0, n) else set()) | ({3, 5} if j in (0, n) else set())
            elif i == 0:
                held |= {3, 4, 5}
            sup[nid(i, j)] = "".join(str(c) for c in sorted(held))
    return frame("plate", nodes, [], supports=sup, mass=mass, shells=shells)


def navier(count: int, t: float, a: float = 1.0, b: float = 1.0) -> np.ndarray:
    w = sorted(np.pi**2 * (m**2 / a**2 + k**2 / b**2) * np.sqrt(stiffness(t) / (RHO * t))
               for m in range(1, 6) for k in range(1, 6))
    return np.asarray(w[:count])


def lowest(sub, count: int) -> np.ndarray:
    return modes(sub.M, None, sub.K, None, count).omega


@pytest.mark.parametrize("kind", ["quad", "tri"])
@pytest.mark.parametrize("mass", ["consistent", "lumped"])
def test_navier_plate_converges_at_second_order(kind, mass):
    """The six lowest frequencies of a simply supported square plate tend to Navier's; the
    error of the fundamental falls like h^2 on halving (measured 1.84 - 1.97)."""
    ref = navier(6, 0.01)
    err = [np.abs(lowest(plate(n, 0.01, kind, mass), 6) / ref - 1) for n in (8, 16)]
    assert err[1].max() < 0.013
    rate = np.log2(err[0][0] / err[1][0])
    assert 1.6 < rate < 2.4, rate


def test_cantilever_plate_matches_leissa():
    """A square cantilever plate, 16 x 16, quads and triangles: within 1% of Leissa's
    table.  The two element kinds agree with each other much more closely (0.1% on the
    fundamental) than with the table: the remaining 0.6% on the fundamental is the table's."""
    scale = np.sqrt(RHO * 0.01 / stiffness(0.01))  # a = 1
    quad = lowest(plate(16, 0.01, "quad", edges="cantilever"), 5) * scale
    tri = lowest(plate(16, 0.01, "tri", edges="cantilever"), 5) * scale
    np.testing.assert_allclose(quad, LEISSA_CFFF, rtol=0.01)
    np.testing.assert_allclose(tri, LEISSA_CFFF, rtol=0.01)
    assert abs(quad[0] / tri[0] - 1) < 1e-3


@pytest.mark.parametrize("kind", ["quad", "tri"])
def test_no_shear_locking_as_the_plate_gets_thin(kind):
    """omega / omega_Kirchhoff of the modes (1, 1) and (1, 2), t/L = 1e-1 ... 1e-4 on one
    8 x 8 mesh.  A locking element stiffens without bound as t -> 0; here the ratio stays
    within the mesh error of 1 (1.1% and 1.7% at this mesh), and it changes with t only by
    the rotary inertia of the thickness, which the Kirchhoff closed form leaves out and which
    lowers a frequency by about pi^2 (m^2 + n^2) t^2 / 24 (measured 0.78% for (1, 1) at
    t/L = 0.1, against 0.82%): the bound below is twice that."""
    thick = np.array([1e-1, 1e-2, 1e-3, 1e-4])
    ratios = np.array([lowest(plate(8, t, kind), 2) / navier(2, t) for t in thick])
    assert np.abs(ratios - 1).max() < 0.04
    rotary = np.pi**2 * np.outer(thick**2, [2, 5]) / 12
    assert np.all(np.abs(ratios / ratios[-1] - 1) <= rotary)
    assert np.abs(ratios[-2] / ratios[-1] - 1).max() < 1e-5


def _patch(kind: str):
    """A distorted patch of 2 x 2 cells with one interior node, tilted in space."""
    xy = {1: (0, 0), 2: (1, 0), 3: (2, 0), 4: (0, 1), 5: (1.15, 0.9), 6: (2, 1.1), 7: (0, 2),
          8: (0.9, 2.1), 9: (2, 2)}
    axes = np.linalg.qr(np.array([[1.0, 0.3, 0.2], [-0.4, 1.0, 0.1], [0.2, -0.3, 1.0]]))[0]
    nodes = {k: tuple(axes[:, 0] * x + axes[:, 1] * y + 0.5) for k, (x, y) in xy.items()}
    cells = [(1, 2, 5, 4), (2, 3, 6, 5), (4, 5, 8, 7), (5, 6, 9, 8)]
    if kind == "quad":
        shells = [Shell(c, 0.05, MAT) for c in cells]
    else:
        shells = [Shell(s, 0.05, MAT) for c in cells
                  for s in ((c[0], c[1], c[2]), (c[0], c[2], c[3]))]
    return frame("patch", nodes, [], shells=shells), xy, axes


@pytest.mark.parametrize("kind", ["quad", "tri"])
def test_patch_test_constant_strain_and_curvature(kind):
    """Boundary nodes given the field of constant membrane strain and constant curvature
    (u, v linear, w quadratic, theta_z the membrane rotation, in the patch's tilted plane):
    the interior node solves to that field exactly (to round-off)."""
    sub, xy, axes = _patch(kind)
    ids = sub.meta["node_ids"]

    def field(x: float, y: float) -> np.ndarray:
        u = 1e-3 * (1 + 2 * x - 0.5 * y)
        v = 1e-3 * (-0.3 + 0.7 * x + 1.5 * y)
        w = 1e-3 * (0.2 + 0.4 * x - 0.1 * y + 0.5 * (0.8 * x * x - 0.6 * y * y + 0.9 * x * y))
        wx, wy = 1e-3 * (0.4 + 0.8 * x + 0.45 * y), 1e-3 * (-0.1 - 0.6 * y + 0.45 * x)
        rz = 0.5 * 1e-3 * (0.7 - (-0.5))
        local = np.array([u, v, w, wy, -wx, rz])  # theta_x = w,y, theta_y = -w,x
        return np.concatenate([axes @ local[:3], axes @ local[3:]])

    q = np.concatenate([field(*map(float, xy[k])) for k in ids])
    K = sub.K.toarray()
    inner = np.arange(6 * ids.index(5), 6 * ids.index(5) + 6)
    outer = np.setdiff1d(np.arange(K.shape[0]), inner)
    solved = np.linalg.solve(K[np.ix_(inner, inner)], -K[np.ix_(inner, outer)] @ q[outer])
    assert np.abs(solved - q[inner]).max() < 1e-9 * np.abs(q).max()


@pytest.mark.parametrize("kind", ["quad", "tri"])
def test_drilling_rotation_is_not_singular(kind):
    """A patch with only its rigid-body motion removed (three translations of one node, two of
    another, one of a third) has a positive definite stiffness: the drilling rotations, free
    at every node, are held by the penalty alone; one element has exactly six zero
    eigenvalues (the rigid-body motions), the seventh clear of round-off."""
    sub, _, _ = _patch(kind)
    ids = sub.meta["node_ids"]
    held = [6 * ids.index(1) + c for c in (0, 1, 2)] + [6 * ids.index(3) + c for c in (1, 2)] + \
        [6 * ids.index(7) + 2]
    K = sub.K.toarray()
    keep = np.setdiff1d(np.arange(K.shape[0]), held)
    lam = np.linalg.eigvalsh(K[np.ix_(keep, keep)])
    assert lam[0] > 1e-9 * lam[-1]
    X = np.array([[0.0, 0.0, 0.0], [1.0, 0.2, 0.3], [0.9, 1.1, 0.0], [-0.1, 1.0, -0.2]])
    X[3] = X[0] + X[2] - X[1]  # flat
    Ke, _ = shell_matrices(X if kind == "quad" else X[:3], E, NU, 0.01, RHO)
    ev = np.linalg.eigvalsh(Ke)
    assert np.abs(ev[:6]).max() < 1e-12 * ev[-1] and ev[6] > 1e-9 * ev[-1]


def test_element_mass_is_the_plate_mass_in_every_direction():
    """The consistent and lumped masses of a tilted quadrilateral carry rho t A on each
    translation (a rigid translation's kinetic energy)."""
    X = np.array([[0.0, 0.0, 0.0], [1.0, 0.2, 0.3], [0.9, 1.1, 0.0], [0.0, 0.0, 0.0]])
    X[3] = X[0] + X[2] - X[1]
    area = np.linalg.norm(np.cross(X[2] - X[0], X[3] - X[1])) / 2
    for mass in ("consistent", "lumped"):
        _, Me = shell_matrices(X, E, NU, 0.02, RHO, mass, nsm=3.0)
        for c in range(3):
            u = np.zeros(24)
            u[c::6] = 1.0
            assert u @ Me @ u == pytest.approx((RHO * 0.02 + 3.0) * area, rel=1e-12)


def test_shells_and_beams_share_nodes():
    """A plate divided 4 x 2 with beams along two edges divided to match: the nodes made along
    the edges are the beams' nodes (15 nodes, not 15 + 3 + 1); with the beams as stiffeners the
    first frequency rises."""
    nodes = {1: (0, 0, 0), 2: (2, 0, 0), 3: (2, 1, 0), 4: (0, 1, 0)}
    sec = Section(A=4e-4, Iy=2e-7, Iz=2e-7, J=3e-7)
    beams = [Beam((1, 2), sec, MAT, (0, 0, 1), divisions=4), Beam((2, 3), sec, MAT, (0, 0, 1),
                                                                  divisions=2)]
    shell = Shell((1, 2, 3, 4), 0.005, MAT, divisions=(4, 2))
    both = frame("f", nodes, beams, supports={1: None, 4: None}, shells=[shell])
    assert both.meta["n_nodes"] == 15
    alone = frame("f", nodes, [], supports={1: None, 4: None}, shells=[shell])
    assert lowest(both, 1)[0] > lowest(alone, 1)[0]


def test_bad_shells_are_refused():
    nodes = {1: (0, 0, 0), 2: (1, 0, 0), 3: (1, 1, 0.3), 4: (0, 1, 0), 5: (2, 0, 0)}
    with pytest.raises(ValueError, match="warped"):
        frame("f", nodes, [], shells=[Shell((1, 2, 3, 4), 0.01, MAT)])
    with pytest.raises(ValueError, match="collinear"):
        frame("f", nodes, [], shells=[Shell((1, 2, 5), 0.01, MAT)])
    with pytest.raises(ValueError, match="must be 3 or 4 different nodes"):
        frame("f", nodes, [], shells=[Shell((1, 2, 9), 0.01, MAT)])
    with pytest.raises(ValueError, match="divisions"):
        frame("f", nodes, [], shells=[Shell((1, 2, 4), 0.01, MAT, divisions=(2, 3))])


def _deck_case(**shell) -> dict:
    item = {"nodes": [1, 2, 3, 4], "thickness": 0.01, "material": "s", "divisions": [8, 8],
            **shell}
    return {"name": "deck", "substructures": [{
        "name": "p", "type": "frame",
        "nodes": {1: [0, 0, 0], 2: [1, 0, 0], 3: [1, 1, 0], 4: [0, 1, 0]},
        "materials": {"s": {"E": E, "G": E / (2 * (1 + NU)), "rho": RHO}},
        "shells": [item], "supports": {1: "123456", 2: "123456"}}],
        "analysis": {"modes": {"count": 3}}}


@pytest.mark.parametrize("bending", ["kirchhoff", "mindlin"])
def test_case_file_shells_are_the_api_shells(bending):
    """``shells:`` in a ``type: frame`` item builds the same matrices as the Python API, with
    ``bending: kirchhoff`` (DKQ) or ``mindlin`` (MITC4); the two differ."""
    from substruct.builder.model import assemble_case
    from substruct.case.loader import load_case

    asm = assemble_case(load_case(_deck_case(bending=bending))).assembly
    nodes = {1: (0, 0, 0), 2: (1, 0, 0), 3: (1, 1, 0), 4: (0, 1, 0)}
    api = frame("p", nodes, [], supports={1: "123456", 2: "123456"},
                shells=[Shell((1, 2, 3, 4), 0.01, MAT, divisions=(8, 8), bending=bending)])
    assert abs(asm.K - api.K).max() <= 1e-13 * abs(api.K).max()
    assert abs(asm.M - api.M).max() <= 1e-13 * abs(api.M).max()
    other = frame("p", nodes, [], supports={1: "123456", 2: "123456"},
                  shells=[Shell((1, 2, 3, 4), 0.01, MAT, divisions=(8, 8),
                                bending="mindlin" if bending == "kirchhoff" else "kirchhoff")])
    assert abs(other.K - api.K).max() > 1e-3 * abs(api.K).max()


@pytest.mark.parametrize("n", [3, 4])
def test_mindlin_shell_element_in_space_has_exactly_six_rigid_body_modes(n):
    """A tilted MITC4 / MITC3 shell element (thick, t/L = 0.2): six zero eigenvalues (rigid
    motions, shear strain zero for a rigid rotation), the seventh clear of round-off."""
    from substruct.models.shell import ShellTerms

    X = np.array([[0.0, 0.0, 0.0], [1.0, 0.2, 0.3], [0.9, 1.1, 0.0], [-0.1, 1.0, -0.2]])
    X[3] = X[0] + X[2] - X[1]  # flat
    terms = ShellTerms(shear=5 / 6 * MAT.G * 0.2)
    Ke, Me = shell_matrices(X[:n], E, NU, 0.2, RHO, terms=terms)
    ev = np.linalg.eigvalsh(Ke)
    assert np.abs(ev[:6]).max() < 1e-12 * ev[-1] and ev[6] > 1e-9 * ev[-1]
    assert np.linalg.eigvalsh(Me)[0] > 0


@pytest.mark.parametrize("shell, field, text", [
    ({"nodes": [1, 2, 9]}, "shells.0.nodes", "no node 9"),
    ({"nodes": [1, 2, 4], "divisions": [2, 3]}, "shells.0.divisions", "divided equally"),
    ({"material": "x"}, "shells.0.material", "no material"),
    ({"thickness": -1}, "shells.0.thickness", ""),
    ({"bending": "reissner"}, "shells.0.bending", "reissner"),
])
def test_case_file_bad_shells_name_their_field(shell, field, text):
    from substruct.case.errors import CaseError
    from substruct.case.loader import load_case

    with pytest.raises(CaseError) as err:
        load_case(_deck_case(**shell))
    assert field.replace(".", "") in str(err.value).replace(".", "").replace("[", "") \
        .replace("]", "") and text in str(err.value)


def test_case_file_warped_shell_is_refused_naming_it():
    from substruct.builder.model import assemble_case
    from substruct.case.errors import CaseError
    from substruct.case.loader import load_case

    case = _deck_case(divisions=1)
    case["substructures"][0]["nodes"][4] = [0, 1, 0.5]
    with pytest.raises(CaseError, match=r"shells\[0\]: the quadrilateral is warped by 0.0833"):
        assemble_case(load_case(case))
