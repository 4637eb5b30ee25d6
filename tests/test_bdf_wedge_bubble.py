"""The 6-grid CPENTA with bubble functions (MSC Nastran's default PSOLID: IN and ISOP blank),
against exact behaviour and a closed form.

* patch test on a distorted mesh (``tests/test_bdf_solids.py`` runs it with the default
  PSOLID, so on this element): here the same for a single badly shaped wedge, and exactly six
  rigid-body modes;
* pure bending of a beam of wedges laid along it (triangles across the section), clamped at
  one end and loaded at the other by the linear traction of a moment ``M``, ``nu = 0``: the
  bending field ``u_x = -k x z, u_z = k x^2 / 2`` (``k = M / EI``) is exact elasticity and
  lies in the element's space, so the tip deflection is Euler-Bernoulli's ``M L^2 / (2 E I)``
  to round-off; the plain wedge (IN 2, ISOP FULL) on the same mesh locks (measured: a quarter
  of it).
"""

from __future__ import annotations

import numpy as np

from substruct.case.bdf import parse_bulk
from substruct.models.nastran import nastran_matrices
from substruct.models.nastran_bubble import bubble_wedge_stiffness, isotropic_D

E = 2.1e11


def translations_K(text: str) -> np.ndarray:
    K = nastran_matrices(parse_bulk(text, "w.bdf")).K
    t = np.flatnonzero(np.arange(K.shape[0]) % 6 < 3)
    return K.toarray()[np.ix_(t, t)]


def test_one_distorted_wedge_passes_the_patch_test_with_six_rigid_modes():
    X = np.array([[0.0, 0.0, 0.0], [1.3, 0.2, 0.1], [0.1, 0.9, -0.2],
                  [0.2, -0.1, 0.8], [1.0, 0.3, 1.3], [0.3, 1.2, 0.7]])
    nu = 0.3
    D = isotropic_D(E, nu)
    K = bubble_wedge_stiffness(X[None], D)[0]
    rng = np.random.default_rng(2)
    G = rng.normal(size=(3, 3))
    u = (X @ G.T).ravel()
    eps = (G + G.T) / 2
    v = np.array([eps[0, 0], eps[1, 1], eps[2, 2], 2 * eps[1, 2], 2 * eps[0, 2],
                  2 * eps[0, 1]])
    # the volume of the wedge: its 3 x 2 rule integrates the Jacobian (bilinear in r, s, zeta
    # times linear) exactly; from the divergence theorem on its faces as the reference
    faces = [[0, 2, 1], [3, 4, 5], [0, 1, 4, 3], [1, 2, 5, 4], [2, 0, 3, 5]]
    c = X.mean(axis=0)
    volume = 0.0
    for f in faces:  # each face split about its centre: sum of tetrahedra to the centroid
        q = X[f].mean(axis=0)
        for a, b in zip(f, f[1:] + f[:1]):
            volume += np.dot(np.cross(X[a] - q, X[b] - q), q - c) / 6
    assert abs(0.5 * u @ K @ u / (0.5 * volume * v @ D @ v) - 1) < 1e-12
    lam = np.linalg.eigvalsh(K)
    assert np.sum(np.abs(lam) < 1e-10 * lam.max()) == 6
    assert lam[6] > 1e-4 * lam.max()


def beam_bdf(psolid: str, nx: int = 4, L: float = 4.0, b: float = 0.6, h: float = 0.4
             ) -> tuple[str, np.ndarray, list[tuple[int, int, int]]]:
    """A beam along x of CPENTA: the section's 2 x 2 rectangles each cut into two
    triangles, extruded over ``nx`` slices; returns the file, the grids and the section's
    triangles (section grid indices)."""
    ys, zs = np.linspace(-b / 2, b / 2, 3), np.linspace(-h / 2, h / 2, 3)
    sec = np.array([(y, z) for z in zs for y in ys])
    tri = []
    for j in range(2):
        for i in range(2):
            a = 3 * j + i
            tri += [(a, a + 1, a + 4), (a, a + 4, a + 3)]
    xs = np.linspace(0, L, nx + 1)
    pts = np.array([(x, y, z) for x in xs for y, z in sec])
    lines = ["BEGIN BULK", "MAT1,1,2.1+11,,0.,7850.", psolid]
    lines += [f"GRID,{k + 1},,{float(p[0])!r},{float(p[1])!r},{float(p[2])!r}"
              for k, p in enumerate(pts)]
    e = 0
    for s in range(nx):
        for t in tri:
            e += 1
            g = [9 * s + k + 1 for k in t] + [9 * (s + 1) + k + 1 for k in t]
            lines.append(f"CPENTA,{e},1," + ",".join(map(str, g)))
    return "\n".join(lines + ["ENDDATA", ""]), pts, tri


def tip_deflection(psolid: str) -> tuple[float, float]:
    """Tip deflections (mean, spread over the tip's grids) over Euler-Bernoulli's."""
    L, b, h, M = 4.0, 0.6, 0.4, 1.0e6
    text, pts, tri = beam_bdf(psolid)
    K = translations_K(text)
    I = b * h ** 3 / 12
    k = M / (E * I)
    f = np.zeros(len(pts) * 3)
    tip = np.flatnonzero(np.abs(pts[:, 0] - L) < 1e-12)
    sec = pts[tip]
    for t in tri:  # consistent forces of sigma_xx = -E k z on the linear triangle (exact)
        y, z = sec[list(t), 1], sec[list(t), 2]
        area = abs((y[1] - y[0]) * (z[2] - z[0]) - (y[2] - y[0]) * (z[1] - z[0])) / 2
        s = -E * k * z
        f[3 * tip[list(t)]] += area / 12 * (s + s.sum())
    free = np.flatnonzero(np.repeat(pts[:, 0] > 1e-12, 3))
    u = np.zeros_like(f)
    u[free] = np.linalg.solve(K[np.ix_(free, free)], f[free])
    w = u[3 * tip + 2] / (M * L ** 2 / (2 * E * I))
    return float(w.mean()), float(np.ptp(w))


def test_a_beam_of_wedges_bends_exactly_where_the_plain_wedge_locks():
    mean, spread = tip_deflection("PSOLID,1,1")
    assert abs(mean - 1) < 1e-9 and spread < 1e-9, (mean, spread)
    plain, _ = tip_deflection("PSOLID,1,1,,2,,FULL")
    assert 0.2 < plain < 0.3, plain


def bending_energy_ratio(axis: int, full: bool) -> float:
    """Energy of the pure bending field ``u_x = -x z, u_z = x^2 / 2`` (``nu = 0``) in a 1 x 0.6
    x 0.4 box cut into two wedges whose axis is along ``axis``, over its exact ``E I / 2``
    (with the wedges' bubbles condensed, or fully integrated)."""
    size = np.array([1.0, 0.6, 0.4])
    plane = [d for d in range(3) if d != axis]
    D = isotropic_D(E, 0.0)
    total = 0.0
    for tri in (((0, 0), (1, 0), (1, 1)), ((0, 0), (1, 1), (0, 1))):
        X = np.zeros((6, 3))
        for k, (a, b) in enumerate(tri):
            for level in (0, 1):
                X[k + 3 * level, plane] = a, b
                X[k + 3 * level, axis] = level
        X = (X - 0.5) * size
        x, z = X[:, 0], X[:, 2]
        u = np.stack([-x * z, 0 * x, x ** 2 / 2], axis=1).ravel()
        if full:
            text = "\n".join(["BEGIN BULK", "MAT1,1,2.1+11,,0.,7850.", "PSOLID,1,1,,2,,FULL"] +
                             [f"GRID,{k + 1},,{float(p[0])!r},{float(p[1])!r},{float(p[2])!r}"
                              for k, p in enumerate(X)] + ["CPENTA,1,1,1,2,3,4,5,6", "ENDDATA"])
            K = translations_K(text)
        else:
            K = bubble_wedge_stiffness(X[None], D)[0]
        total += 0.5 * u @ K @ u
    return total / (E * size[1] * size[2] ** 3 / 12 / 2 * size[0])


def test_bending_energy_of_a_wedge_along_and_across_its_axis():
    """Along the axis (triangles across the beam) the bubbles hold the bending field exactly;
    through the thickness they take out part of the parasitic shear (measured 2.04 against
    4.12 times the exact energy); bent in the triangles' plane the constant-strain triangle
    locks either way (12.4 times)."""
    assert abs(bending_energy_ratio(0, False) - 1) < 1e-12
    assert bending_energy_ratio(0, True) > 4
    assert 1.9 < bending_energy_ratio(2, False) < 0.55 * bending_energy_ratio(2, True)
    assert bending_energy_ratio(1, False) > 12 and bending_energy_ratio(1, True) > 12
