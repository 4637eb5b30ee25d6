r"""Flat-facet shell elements with six coordinates per node: triangles and quadrilaterals.

An element is flat: a membrane (plane stress, in-plane ``u, v`` and the drilling rotation
:math:`\theta_z`) and a plate in bending (``w``, :math:`\theta_x`, :math:`\theta_y`,
:mod:`substruct.models.plate_bending`), uncoupled in the element's own axes, turned to global
axes node by node.

**Axes from the nodes.** The normal is :math:`e_z = (x_2 - x_1) \times (x_3 - x_1)` for a
triangle and the cross product of the diagonals :math:`(x_3 - x_1) \times (x_4 - x_2)` for a
quadrilateral (normalised); :math:`e_x` is side ``1-2`` projected on the plane and
:math:`e_y = e_z \times e_x`.  A quadrilateral's corners are projected on the plane through
their centroid; a warp (largest distance from that plane over the shorter diagonal) above
:data:`MAX_WARP` is refused.  The element's matrices are :math:`T^T K T` with
``T = diag(R, ..., R)``, the rows of ``R`` being :math:`e_x, e_y, e_z`.

**Warped quadrilaterals.** The flat element lies on the mean plane, its corners
:math:`p_k = x_k - h_k e_z` at the heights :math:`h_k = (x_k - c) \cdot e_z` of the nodes
above it.  Each corner is joined to its node by a rigid offset,
:math:`u(p_k) = u_k + \theta_k \times (p_k - x_k)` (:func:`warp_offsets`), so that the stiffness
is :math:`W^T K W`: a rigid motion of the nodes themselves is a rigid motion of the flat
element and stores no energy (without it, a rotation of a warped quadrilateral about an axis
in its plane would, and a free structure would lose rigid-body modes).  The mass is left at
the corners (a rigid offset of at most :data:`MAX_WARP` of the diagonal).

**Membrane.** Triangles: the constant-strain triangle (CST).  Quadrilaterals: the bilinear
element with Wilson's incompatible modes :math:`1 - \xi^2, 1 - \eta^2` in the form of Taylor,
Beresford and Wilson (QM6: their derivatives are taken with the Jacobian at the centre and
scaled by :math:`\det J_0 / \det J`, so the constant-strain patch test is passed on any
mesh), condensed statically; 2 x 2 Gauss points.  :math:`K_m = t \int B^T C B\,dA` with ``C``
the plane-stress matrix.

**Drilling rotation.** A penalty ties :math:`\theta_z` to the membrane's own rotation
:math:`\omega = \tfrac12 (v_{,x} - u_{,y})` (Hughes and Brezzi 1989),

.. math::  K_d = \gamma\, t \int_A (N\theta_z - \omega)^T (N\theta_z - \omega)\, dA, \qquad
           \gamma = \alpha\, G, \quad \alpha = 10^{-2}

(:data:`DRILL_PENALTY`; linear/bilinear ``N`` and the compatible membrane field, 3 mid-side
points or 2 x 2 Gauss points).  A rigid rotation about the normal costs nothing
(:math:`\theta_z = \omega`), a linear displacement field with :math:`\theta_z = \omega` neither
(the patch test is unchanged), and every other drilling motion has stiffness, so a shell
whose drilling rotations are free is not singular (no fictitious supports needed) and a beam
can be joined to a shell node about any axis.

**Bending.** Kirchhoff's plate (DKQ / DKT, :mod:`substruct.models.plate_bending`: no
transverse shear deformation) by default; Reissner-Mindlin's (MITC4 / MITC3,
:mod:`substruct.models.mindlin_plate`: transverse shear stiffness :math:`\kappa G t`) when
:class:`ShellTerms` gives ``shear``.

**Mass.** ``consistent``: :math:`\rho t \int N^T N` on ``u, v`` (linear/bilinear), the
bending element's mass (:mod:`substruct.models.plate_bending`) and the rotary inertia
:math:`\rho t^3/12 \int N^T N` on :math:`\theta_z`.  ``lumped``: :math:`\rho t A / n` on each
translation of each of the ``n`` corners and :math:`\rho t^3 A / (12 n)` on each rotation.
A non-structural mass per area adds to :math:`\rho t` on the translations.

The element matrices are written by hand: scikit-fem (12.0) has scalar Kirchhoff plate
elements (Morley, Argyris, the 15-parameter triangle) for a 2D mesh, with normal derivatives
on edges as degrees of freedom, but no shell element with three rotations per node.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from substruct.models.mindlin_plate import mindlin_matrices_local
from substruct.models.plate_bending import (
    bending_matrices_local, corner_shapes, plane_stress, tabulated,
)

__all__ = ["MAX_WARP", "DRILL_PENALTY", "SHELL_MASSES", "ShellTerms", "shell_axes",
           "membrane_matrices", "shell_matrices", "warp_offsets"]

#: Largest warp of a quadrilateral (distance of a corner from the mean plane over the shorter
#: diagonal) accepted for a flat facet.
MAX_WARP = 0.05
#: Drilling penalty ``gamma / G``.
DRILL_PENALTY = 1e-2
#: Mass matrices of the shell elements.
SHELL_MASSES = ("consistent", "lumped")


def shell_axes(X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(R, xy)``: the rows of ``R`` are the element's axes (module docstring) and ``xy``
    ``(n, 2)`` its corners in its plane, from the corner positions ``X`` ``(n, 3)``.

    Raises:
        ValueError: coincident or collinear corners, a warp above :data:`MAX_WARP`, or a
            quadrilateral with a zero or negative Jacobian at a corner (collapsed, folded).
    """
    n = len(X)
    if n == 3:
        ez = np.cross(X[1] - X[0], X[2] - X[0])
    else:
        ez = np.cross(X[2] - X[0], X[3] - X[1])
    size = max(float(np.linalg.norm(X[k] - X[0])) for k in range(1, n))
    if not np.linalg.norm(ez) > 1e-12 * size**2:
        raise ValueError("the corners are coincident or collinear")
    ez = ez / np.linalg.norm(ez)
    c = X.mean(axis=0)
    if n == 4:
        diag = min(float(np.linalg.norm(X[2] - X[0])), float(np.linalg.norm(X[3] - X[1])))
        warp = float(np.abs((X - c) @ ez).max()) / diag
        if warp > MAX_WARP:
            raise ValueError(f"the quadrilateral is warped by {warp:.3g} of its diagonal "
                             f"(at most {MAX_WARP} for a flat facet)")
    ex = (X[1] - X[0]) - ((X[1] - X[0]) @ ez) * ez
    if not np.linalg.norm(ex) > 1e-12 * size:
        raise ValueError("the corners are coincident or collinear")
    ex = ex / np.linalg.norm(ex)
    R = np.vstack([ex, np.cross(ez, ex), ez])
    xy = (X - c) @ R[:2].T
    if n == 4:  # the corner Jacobians (edge cross products): a collapsed or folded corner
        e1 = np.roll(xy, -1, axis=0) - xy
        e2 = np.roll(xy, 1, axis=0) - xy
        corner = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
        if not np.all(corner > 1e-12 * size**2):
            raise ValueError("the element is degenerate or not convex (det J <= 0 at a "
                             "corner)")
    return R, xy


def _strain_matrix(dx: np.ndarray) -> np.ndarray:
    """``(3, 2k)`` membrane strains of ``(u, v)`` node by node from shape derivatives
    ``(2, k)`` in ``x, y``."""
    B = np.zeros((3, 2 * dx.shape[1]))
    B[0, 0::2] = dx[0]
    B[1, 1::2] = dx[1]
    B[2, 0::2] = dx[1]
    B[2, 1::2] = dx[0]
    return B


def membrane_matrices(xy: np.ndarray, E: float, nu: float, t: float) -> np.ndarray:
    r"""Membrane and drilling stiffness ``(3n, 3n)`` of ``(u, v, theta_z)`` corner by corner
    (module docstring: CST or QM6, plus the drilling penalty)."""
    n = len(xy)
    C = plane_stress(E, nu) * t
    gamma = DRILL_PENALTY * E / (2 * (1 + nu)) * t
    uv = np.concatenate([[3 * k, 3 * k + 1] for k in range(n)])
    rz = 3 * np.arange(n) + 2
    K = np.zeros((3 * n, 3 * n))
    J0 = corner_shapes(n, np.zeros(2) if n == 4 else np.full(2, 1 / 3))[1] @ xy
    det0 = float(np.linalg.det(J0))
    Kcc, Kci, Kii = np.zeros((2 * n, 2 * n)), np.zeros((2 * n, 4)), np.zeros((4, 4))
    for p, wq, N, dN, _, _ in tabulated(n, "stiffness"):
        J = dN @ xy
        det = float(np.linalg.det(J))
        if not det > 0:
            raise ValueError("the element is degenerate or not convex (det J <= 0)")
        dx = np.linalg.solve(J, dN)
        B = _strain_matrix(dx)
        Kcc += (wq * det) * B.T @ C @ B
        if n == 4:
            dP = np.array([[-2 * p[0], 0.0], [0.0, -2 * p[1]]])  # d(1-xi^2), d(1-eta^2)
            Bi = _strain_matrix(det0 / det * np.linalg.solve(J0, dP))
            Kci += (wq * det) * B.T @ C @ Bi
            Kii += (wq * det) * Bi.T @ C @ Bi
        g = np.zeros(3 * n)  # N theta_z - omega
        g[rz] = N
        g[uv[0::2]] += 0.5 * dx[1]
        g[uv[1::2]] -= 0.5 * dx[0]
        K += (wq * det * gamma) * np.outer(g, g)
    if n == 4:
        Kcc = Kcc - Kci @ np.linalg.solve(Kii, Kci.T)
    K[np.ix_(uv, uv)] += Kcc
    return (K + K.T) / 2


def _membrane_mass(xy: np.ndarray, mu: float, rot: float) -> np.ndarray:
    n = len(xy)
    M = np.zeros((3 * n, 3 * n))
    for _, wq, N, dN, _, _ in tabulated(n, "mass"):
        m = wq * float(np.linalg.det(dN @ xy)) * np.outer(N, N)
        for c, scale in ((0, mu), (1, mu), (2, rot)):
            M[c::3, c::3] += scale * m
    return M


def warp_offsets(X: np.ndarray, ez: np.ndarray) -> np.ndarray:
    r"""The rigid offsets ``W`` ``(m, 6n, 6n)`` from the nodes ``X`` ``(m, n, 3)`` of ``m``
    elements to their corners on the mean planes (normals ``ez`` ``(m, 3)``, through the
    centroids): ``u(p_k) = u_k + theta_k x (p_k - x_k)``, ``theta(p_k) = theta_k``, with
    ``p_k - x_k = -h_k e_z`` (module docstring).  The identity for a flat element."""
    X = np.asarray(X, dtype=float)
    m, n = X.shape[:2]
    h = np.einsum("mkc,mc->mk", X - X.mean(axis=1, keepdims=True), ez)
    d = -h[:, :, None] * ez[:, None, :]  # p_k - x_k
    W = np.tile(np.eye(6 * n), (m, 1, 1))
    for k in range(n):  # theta x d = -[d]_x theta
        dx, dy, dz = d[:, k, 0], d[:, k, 1], d[:, k, 2]
        r, c = 6 * k, 6 * k + 3
        W[:, r, c + 1], W[:, r, c + 2] = dz, -dy
        W[:, r + 1, c], W[:, r + 1, c + 2] = -dz, dx
        W[:, r + 2, c], W[:, r + 2, c + 1] = dy, -dx
    return W


def _area(xy: np.ndarray) -> float:
    x, y = xy[:, 0], xy[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


@dataclass(frozen=True)
class ShellTerms:
    r"""Which terms a shell element has, as Nastran's PSHELL gives them: ``bending_material``
    ``(E, nu)`` of the bending (MID2; the membrane's if ``None``), ``bend`` the ratio
    ``12 I / t^3`` multiplying the bending stiffness, ``membrane`` / ``bending`` whether the
    element has each (MID1 / MID2 given), ``rotary`` whether the mass has the rotary inertia of
    the thickness, ``shear`` the transverse shear stiffness per width :math:`\kappa G t` of a
    Reissner-Mindlin plate (MITC4 / MITC3, :mod:`substruct.models.mindlin_plate`; ``None``:
    a Kirchhoff plate, DKQ / DKT).  The default is a plain Kirchhoff shell of one material."""

    bending_material: tuple[float, float] | None = None
    bend: float = 1.0
    membrane: bool = True
    bending: bool = True
    rotary: bool = True
    shear: float | None = None


def shell_matrices(X: np.ndarray, E: float, nu: float, t: float, rho: float,
                   mass: str = "consistent", nsm: float = 0.0, *,
                   terms: ShellTerms = ShellTerms()) -> tuple[np.ndarray, np.ndarray]:
    r"""Stiffness and mass ``(6n, 6n)``, global axes, of a flat shell element with corners
    ``X`` ``(n, 3)``, ``n`` = 3 or 4, six coordinates ``(ux, uy, uz, rx, ry, rz)`` per corner
    (module docstring).  ``nsm`` is a non-structural mass per area, added to :math:`\rho t`
    on the translations.

    ``terms``: the terms of the element (:class:`ShellTerms`, for Nastran's PSHELL).

    Raises:
        ValueError: bad properties, a degenerate, non-convex or warped element.
    """
    X = np.asarray(X, dtype=float)
    n = len(X)
    if n not in (3, 4) or X.shape != (n, 3):
        raise ValueError(f"a shell element has 3 or 4 corners, got {X.shape}")
    if mass not in SHELL_MASSES:
        raise ValueError(f"mass must be one of {list(SHELL_MASSES)}, got {mass!r}")
    if not (E > 0 and t > 0 and rho >= 0 and nsm >= 0 and -1 < nu < 0.5):
        raise ValueError(f"a shell needs E > 0, t > 0, rho >= 0, nsm >= 0 and -1 < nu < 0.5, "
                         f"got E={E!r}, t={t!r}, rho={rho!r}, nsm={nsm!r}, nu={nu!r}")
    bending_material, bend = terms.bending_material, terms.bend
    membrane, bending, rotary = terms.membrane, terms.bending, terms.rotary
    R, xy = shell_axes(X)
    if _area(xy) <= 0:
        raise ValueError("the corners are not in order around the element")
    mu, rot = rho * t + nsm, (rho * t**3 / 12 if rotary else 0.0)
    Eb, nub = bending_material if bending_material is not None else (E, nu)
    if terms.shear is None:
        Kb, Mb = bending_matrices_local(xy, Eb, nub, t, mu, rot)
        Kb = Kb * bend
    else:
        Kb, Mb = mindlin_matrices_local(xy, plane_stress(Eb, nub) * (bend * t**3 / 12),
                                        terms.shear, t, mu, rot)
    Kb = Kb if bending else 0.0 * Kb
    Km = membrane_matrices(xy, E, nu, t) if membrane else np.zeros((3 * n, 3 * n))
    memb = np.concatenate([[6 * k, 6 * k + 1, 6 * k + 5] for k in range(n)])
    bent = np.concatenate([[6 * k + 2, 6 * k + 3, 6 * k + 4] for k in range(n)])
    K, M = np.zeros((6 * n, 6 * n)), np.zeros((6 * n, 6 * n))
    K[np.ix_(memb, memb)] = Km
    K[np.ix_(bent, bent)] = Kb
    if mass == "consistent":
        M[np.ix_(memb, memb)] = _membrane_mass(xy, mu, rot)
        M[np.ix_(bent, bent)] = Mb
    else:
        A = _area(xy)
        M[np.arange(6 * n), np.arange(6 * n)] = np.tile([mu * A / n] * 3 + [rot * A / n] * 3, n)
    T = np.kron(np.eye(2 * n), R)
    W = warp_offsets(X[None], R[None, 2])[0]
    return W.T @ (T.T @ K @ T) @ W, T.T @ M @ T
