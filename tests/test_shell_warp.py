"""Warped quadrilateral shells: a rigid motion of the nodes themselves stores no energy.

A flat facet lies on the mean plane of its corners; the nodes of a warped quadrilateral sit
off that plane by ``h_k``.  The element is joined to its nodes by rigid offsets
(``substruct.models.shell.warp_offsets``), so the rigid motions of the nodes' true positions
are in the kernel of ``K``.  Without the offsets a rotation about an in-plane axis strained
the element by about ``h / L`` (measured: ``|K D| / |K| = 1.8e-3`` at a warp of 0.01 of the
diagonal), and a free structure with warped quadrilaterals had fewer than six rigid-body
modes and far too stiff elastic ones.  Measured on the free saddle ``z = x y / 2`` of 1 m
(``saddle_case``), the seventh frequency (rad/s) on 4, 8, 16, 32 divisions:

======== ====================== ======================================
n        with the offsets       without (rigid modes at 17.4, 450, 454)
======== ====================== ======================================
4        286.17                 791.04
8        283.35                 599.89
16       283.09                 396.31
32       283.04                 316.14
======== ====================== ======================================
"""

from __future__ import annotations

import numpy as np
import pytest

import substruct
from substruct.models.shell import MAX_WARP, ShellTerms, shell_matrices
from substruct.models.shell_batch import shell_matrices_batch

E, G, RHO, NU = 2.1e11, 8.1e10, 7850.0, 0.3


def rigid_motions(X: np.ndarray) -> np.ndarray:
    """``(6n, 6)``: the six rigid motions (three translations, three rotations about the
    origin) of nodes at ``X`` ``(n, 3)``, six coordinates a node."""
    D = np.zeros((6 * len(X), 6))
    for k, x in enumerate(X):
        D[6 * k:6 * k + 3, :3] = np.eye(3)
        D[6 * k:6 * k + 3, 3:] = -np.array([[0, -x[2], x[1]], [x[2], 0, -x[0]],
                                            [-x[1], x[0], 0]])
        D[6 * k + 3:6 * k + 6, 3:] = np.eye(3)
    return D


def warped_quads(count: int, seed: int = 3) -> np.ndarray:
    """``count`` distorted quadrilaterals tilted in space, warped by 0.2 to 0.9 of the
    largest warp accepted, far from the origin (so the rotations move the nodes by much
    more than their size)."""
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < count:
        xy = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float) + rng.uniform(-0.15, 0.15, (4, 2))
        diag = min(np.linalg.norm(xy[2] - xy[0]), np.linalg.norm(xy[3] - xy[1]))
        h = rng.uniform(0.2, 0.9) * MAX_WARP * diag * np.array([1, -1, 1, -1])
        X = np.column_stack([xy, h])
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        out.append(X @ q.T + rng.uniform(-50, 50, 3))
    return np.array(out)


@pytest.mark.parametrize("shear", [None, 5 / 6 * G * 0.01])
@pytest.mark.parametrize("mass", ["consistent", "lumped"])
def test_rigid_motion_of_warped_nodes_stores_no_energy(shear, mass):
    X = warped_quads(6)
    terms = ShellTerms(shear=shear)
    Kb, _ = shell_matrices_batch(X, E, NU, 0.01, RHO, mass, terms=terms)
    for x, K in zip(X, Kb):
        K1, _ = shell_matrices(x, E, NU, 0.01, RHO, mass, terms=terms)
        D = rigid_motions(x)
        scale = np.abs(K).max() * np.abs(D).max()
        # round-off of K D: eps times the largest product, times the few terms it sums
        assert np.abs(K @ D).max() < 1e-12 * scale
        assert np.abs(K1 @ D).max() < 1e-12 * scale
        assert np.abs(K1 - K).max() < 1e-12 * np.abs(K).max()
        # the element still has its elastic modes: exactly six zero eigenvalues
        ev = np.linalg.eigvalsh(K)
        assert np.all(np.abs(ev[:6]) < 1e-11 * ev[-1]) and ev[6] > 1e-8 * ev[-1]


def saddle_case(n: int, c: float) -> dict:
    """A free ``n x n`` hyperbolic paraboloid ``z = c x y`` of 1 m, every quadrilateral warped
    (by ``c h / 4 sqrt(2)`` of its diagonal, ``h = 1/n``), given as one shell per cell."""
    nid = lambda i, j: 1 + i * (n + 1) + j  # noqa: E731
    nodes = {nid(i, j): [i / n, j / n, c * (i / n) * (j / n)]
             for i in range(n + 1) for j in range(n + 1)}
    shells = [{"nodes": [nid(i, j), nid(i + 1, j), nid(i + 1, j + 1), nid(i, j + 1)],
               "thickness": 0.01, "material": "s"} for i in range(n) for j in range(n)]
    return {"name": "saddle", "substructures": [{
        "name": "s", "type": "frame", "nodes": nodes,
        "materials": {"s": {"E": E, "G": G, "rho": RHO}}, "shells": shells}],
        "analysis": {"modes": {"count": 8, "check": ["null-space"]}}}


def test_free_warped_shell_has_six_rigid_body_modes_and_converges():
    c = 0.5
    first = {}
    for n in (4, 8):
        assert c / n / (4 * np.sqrt(2)) < MAX_WARP
        result = substruct.run_case(substruct.load_case(saddle_case(n, c)))
        omega = np.asarray(result.modes.omega).real
        # six rigid-body modes at zero (without the offsets: three, and 17.4, 450, 454 rad/s)
        assert np.all(omega[:6] < 1e-6 * omega[6])
        first[n] = omega[6]
    # the first elastic frequency converges from above (283.04 rad/s on 32 divisions): 4 and
    # 8 divisions agree to 1 % (measured 0.99 %; without the offsets 791 and 600 rad/s)
    assert abs(first[4] - first[8]) < 0.015 * first[8]
    assert first[4] > first[8]


BDF = """\
BEGIN BULK
MAT1,1,2.1+11,,.3,7850.
PSHELL,1,1,.01,1
GRID,1,,0.,0.,0.
GRID,2,,1.,0.,.04
GRID,3,,1.,1.,0.
GRID,4,,0.,1.,.04
GRID,5,,2.,0.,0.
GRID,6,,2.,1.,.04
CQUAD4,1,1,1,2,3,4
CQUAD4,2,1,2,5,6,3
ENDDATA
"""


def test_nastran_warped_cquad4_rigid_motion_stores_no_energy(tmp_path):
    (tmp_path / "warp.bdf").write_text(BDF)
    (tmp_path / "w.yaml").write_text("name: w\nsubstructures:\n"
                                     "  - {name: p, type: nastran, file: warp.bdf}\n"
                                     "analysis: {modes: {count: 1}}\n")
    model = substruct.build_model(substruct.load_case(tmp_path / "w.yaml"))
    K = model.assembly.system.K.toarray()
    pos = {1: (0, 0, 0), 2: (1, 0, .04), 3: (1, 1, 0), 4: (0, 1, .04), 5: (2, 0, 0),
           6: (2, 1, .04)}
    D = np.zeros((K.shape[0], 6))
    for i, label in enumerate(model.assembly.dof_labels):
        grid, comp = label.split(".", 1)[1].split(":")
        D[i] = rigid_motions(np.array([pos[int(grid)]], float))[int(comp) - 1]
    assert np.abs(K @ D).max() < 1e-12 * np.abs(K).max()
