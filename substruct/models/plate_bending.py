r"""Discrete Kirchhoff plate bending: the DKT triangle and the DKQ quadrilateral.

Both elements have three coordinates at each corner, the deflection and the two rotations
``(w, theta_x, theta_y)`` in the element's plane ``x-y`` (:mod:`substruct.models.shell`).  The
normal's rotations :math:`\beta = (\beta_x, \beta_y)` (with :math:`u = z \beta_x`,
:math:`v = z\beta_y` through the thickness) are interpolated *quadratically* on six nodes
(DKT, the quadratic triangle T6; Batoz, Bathe and Ho 1980) or eight nodes (DKQ, the serendipity
quadrilateral Q8; Batoz and Ben Tahar 1982): the corners and the mid-sides.  The mid-side
values are eliminated by the discrete Kirchhoff constraints,

* at the corners :math:`\beta = -\nabla w`, i.e. :math:`\beta_x = \theta_y`,
  :math:`\beta_y = -\theta_x`;
* along each side ``i-j`` (length ``l``, unit tangent ``t``) ``w`` is cubic (Hermite in ``w``
  and :math:`w_{,s} = -t\cdot\beta` at the ends) and :math:`\beta_s = -w_{,s}` holds at the
  mid-side ``k``, while the normal component :math:`\beta_n` varies linearly:

.. math::  \beta_k = -\frac{3}{2l}\,t\,(w_j - w_i) + \Bigl(\tfrac12 I - \tfrac34\, t t^T\Bigr)
           (\beta_i + \beta_j)

The curvatures :math:`\kappa = (\beta_{x,x}, \beta_{y,y}, \beta_{x,y} + \beta_{y,x})` follow
from the quadratic field, and

.. math::  K_b = \int_A B^T D_b B \, dA, \qquad D_b = \frac{E t^3}{12 (1-\nu^2)}
           \begin{bmatrix} 1 & \nu & 0 \\ \nu & 1 & 0 \\ 0 & 0 & (1-\nu)/2 \end{bmatrix}

by the 3-point rule (DKT: the curvatures are linear, exact) or 2 x 2 Gauss points (DKQ).
**No shear locking**: the transverse shear strain is zero by construction (Kirchhoff's
constraint holds at discrete points), there is no shear energy to lock, so the element stays
right as ``t -> 0``; the price is that a thick plate's shear deformation is left out (the
elements converge to Kirchhoff plate theory).  They are the shells' default bending (and
Nastran's PSHELL with ``MID3`` blank); a thick plate, or a PSHELL with ``MID3`` and a PCOMP,
is a Reissner-Mindlin plate of :mod:`substruct.models.mindlin_plate` (MITC4 / MITC3).  DKT
and DKQ share one construction (and one code path), and they pass the constant-curvature
patch test on distorted meshes.

**Consistent mass** uses the same quadratic interpolation for ``w``, whose mid-side values are
those of the Hermite cubic along each side, :math:`w_k = (w_i + w_j)/2 + (l/8)\,
t\cdot(\beta_j - \beta_i)`, and the rotary inertia of the thickness on :math:`\beta`:

.. math::  M_b = \int_A \rho t\, N_w^T N_w + \frac{\rho t^3}{12} N_\beta^T N_\beta \, dA

(9-point collapsed Gauss rule on triangles, 3 x 3 on quadrilaterals: exact for the degree-4
integrands on parallelograms).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

__all__ = ["plane_stress", "kirchhoff_maps", "bending_matrices_local", "curvature_matrix",
           "quadratic_shapes", "corner_shapes", "quadrature", "tabulated"]

_GP2 = np.array([-1.0, 1.0]) / np.sqrt(3.0)
_Q8 = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1], [0, -1], [1, 0], [0, 1], [-1, 0]], float)


def plane_stress(E: float, nu: float) -> np.ndarray:
    r"""The plane-stress matrix :math:`\frac{E}{1-\nu^2}[[1,\nu,0],[\nu,1,0],[0,0,(1-\nu)/2]]`
    (times :math:`t` for the membrane, :math:`t^3/12` for bending)."""
    return E / (1 - nu**2) * np.array([[1.0, nu, 0.0], [nu, 1.0, 0.0], [0.0, 0.0,
                                                                          (1 - nu) / 2]])


@lru_cache(maxsize=8)
def tabulated(n: int, order: str) -> tuple[tuple[np.ndarray, float, np.ndarray, np.ndarray,
                                                  np.ndarray, np.ndarray], ...]:
    """For each point of :func:`quadrature`: the point, its weight, the corner shapes and
    their derivatives, the quadratic shapes and their derivatives (computed once; read-only)."""
    out = []
    for p, w in zip(*quadrature(n, order)):
        N, dN = corner_shapes(n, p)
        Q, dQ = quadratic_shapes(n, p)
        for a in (p, N, dN, Q, dQ):
            a.setflags(write=False)
        out.append((p, float(w), N, dN, Q, dQ))
    return tuple(out)


def quadrature(n: int, order: str) -> tuple[np.ndarray, np.ndarray]:
    """Points ``(k, 2)`` and weights in the reference element of an ``n``-corner element
    (triangle ``0 <= xi, eta, xi + eta <= 1``; square ``[-1, 1]^2``).

    ``order``: ``"stiffness"`` (3 mid-side points; 2 x 2 Gauss) or ``"mass"`` (9-point
    collapsed Gauss, exact to degree 5; 3 x 3 Gauss)."""
    if n == 3:
        if order == "stiffness":
            return np.array([[0.5, 0.0], [0.5, 0.5], [0.0, 0.5]]), np.full(3, 1.0 / 6.0)
        g, w = np.polynomial.legendre.leggauss(3)
        g, w = (g + 1) / 2, w / 2
        u, v = np.meshgrid(g, g, indexing="ij")
        wu, wv = np.meshgrid(w, w, indexing="ij")
        pts = np.column_stack([u.ravel(), ((1 - u) * v).ravel()])
        return pts, (wu * wv * (1 - u)).ravel()
    g, w = (_GP2, np.ones(2)) if order == "stiffness" else np.polynomial.legendre.leggauss(3)
    u, v = np.meshgrid(g, g, indexing="ij")
    wu, wv = np.meshgrid(w, w, indexing="ij")
    return np.column_stack([u.ravel(), v.ravel()]), (wu * wv).ravel()


def corner_shapes(n: int, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Linear (T3) or bilinear (Q4) shape functions at ``p`` and their derivatives
    ``(2, n)`` with respect to the reference coordinates."""
    x, y = p
    if n == 3:
        return np.array([1 - x - y, x, y]), np.array([[-1.0, 1.0, 0.0], [-1.0, 0.0, 1.0]])
    a, b = _Q8[:4, 0], _Q8[:4, 1]
    N = (1 + a * x) * (1 + b * y) / 4
    return N, np.vstack([a * (1 + b * y) / 4, b * (1 + a * x) / 4])


def quadratic_shapes(n: int, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Quadratic T6 (``n = 3``) or serendipity Q8 (``n = 4``) shape functions at ``p`` (corners
    first, then the mid-side of each side ``k, k+1``) and their reference derivatives."""
    x, y = p
    if n == 3:
        L = 1 - x - y
        N = np.array([L * (2 * L - 1), x * (2 * x - 1), y * (2 * y - 1), 4 * L * x, 4 * x * y,
                      4 * y * L])
        dN = np.array([[1 - 4 * L, 4 * x - 1, 0.0, 4 * (L - x), 4 * y, -4 * y],
                       [1 - 4 * L, 0.0, 4 * y - 1, -4 * x, 4 * x, 4 * (L - y)]])
        return N, dN
    N, dN = np.zeros(8), np.zeros((2, 8))
    for k, (a, b) in enumerate(_Q8):
        if k < 4:
            N[k] = (1 + a * x) * (1 + b * y) * (a * x + b * y - 1) / 4
            dN[:, k] = [a * (1 + b * y) * (2 * a * x + b * y) / 4,
                        b * (1 + a * x) * (a * x + 2 * b * y) / 4]
        elif a == 0:
            N[k] = (1 - x**2) * (1 + b * y) / 2
            dN[:, k] = [-x * (1 + b * y), b * (1 - x**2) / 2]
        else:
            N[k] = (1 + a * x) * (1 - y**2) / 2
            dN[:, k] = [a * (1 - y**2) / 2, -y * (1 + a * x)]
    return N, dN


def kirchhoff_maps(xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r"""The discrete Kirchhoff maps of an element with corners ``xy`` ``(n, 2)``: ``Tb``
    ``(2 * 2n, 3n)`` from the corner coordinates ``(w, theta_x, theta_y)`` to
    :math:`(\beta_x, \beta_y)` at the ``2n`` nodes of the quadratic element, and ``Tw``
    ``(2n, 3n)`` to ``w`` at them (module docstring)."""
    n = len(xy)
    Tb = np.zeros((4 * n, 3 * n))
    Tw = np.zeros((2 * n, 3 * n))
    rot = np.array([[0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])  # beta = (theta_y, -theta_x)
    for i in range(n):
        Tb[2 * i:2 * i + 2, 3 * i:3 * i + 3] = rot
        Tw[i, 3 * i] = 1.0
    for i in range(n):
        j = (i + 1) % n
        d = xy[j] - xy[i]
        l = float(np.hypot(*d))
        t = d / l
        k = n + i
        bi, bj = Tb[2 * i:2 * i + 2], Tb[2 * j:2 * j + 2]
        dw = np.zeros(3 * n)
        dw[3 * j], dw[3 * i] = 1.0, -1.0
        Tb[2 * k:2 * k + 2] = -1.5 / l * np.outer(t, dw) + \
            (0.5 * np.eye(2) - 0.75 * np.outer(t, t)) @ (bi + bj)
        Tw[k] = (Tw[i] + Tw[j]) / 2 + l / 8 * t @ (bj - bi)
    return Tb, Tw


def _det(J: np.ndarray) -> float:
    return float(J[0, 0] * J[1, 1] - J[0, 1] * J[1, 0])


def _inv(J: np.ndarray) -> np.ndarray:
    return np.array([[J[1, 1], -J[0, 1]], [-J[1, 0], J[0, 0]]]) / _det(J)


def curvature_matrix(xy: np.ndarray, p: np.ndarray, Tb: np.ndarray) -> tuple[np.ndarray, float]:
    r"""``B`` ``(3, 3n)`` with :math:`\kappa = B\,(w, \theta_x, \theta_y)` at reference point
    ``p``, and ``det J`` there."""
    n = len(xy)
    J = corner_shapes(n, p)[1] @ xy
    return _curvature(J, quadratic_shapes(n, p)[1], Tb), _det(J)


def _curvature(J: np.ndarray, dQ: np.ndarray, Tb: np.ndarray) -> np.ndarray:
    n = dQ.shape[1] // 2
    dx = _inv(J) @ dQ  # (2, 2n): d/dx, d/dy
    Bq = np.zeros((3, 4 * n))
    Bq[0, 0::2] = dx[0]
    Bq[1, 1::2] = dx[1]
    Bq[2, 0::2] = dx[1]
    Bq[2, 1::2] = dx[0]
    return Bq @ Tb


def bending_matrices_local(xy: np.ndarray, E: float, nu: float, t: float, mu: float,
                           rot: float) -> tuple[np.ndarray, np.ndarray]:
    """Bending stiffness and consistent mass ``(3n, 3n)`` of a DKT (``n = 3``) or DKQ
    (``n = 4``) element with corners ``xy`` in its plane, coordinates ``(w, theta_x,
    theta_y)`` corner by corner (module docstring); ``mu`` is the mass per area
    (:math:`\rho t` and any non-structural mass), ``rot`` the rotary inertia per area
    (:math:`\rho t^3 / 12`).

    Raises:
        ValueError: a corner angle of 180 degrees or more, or a side of zero length (``det J
            <= 0`` somewhere).
    """
    n = len(xy)
    Tb, Tw = kirchhoff_maps(xy)
    Db = plane_stress(E, nu) * t**3 / 12
    K = np.zeros((3 * n, 3 * n))
    for _, wq, _, dN, _, dQ in tabulated(n, "stiffness"):
        J = dN @ xy
        det = _det(J)
        if not det > 0:
            raise ValueError("the element is degenerate or not convex (det J <= 0)")
        B = _curvature(J, dQ, Tb)
        K += (wq * det) * B.T @ Db @ B
    M = np.zeros((3 * n, 3 * n))
    for _, wq, _, dN, N, _ in tabulated(n, "mass"):
        det = _det(dN @ xy)
        Nw = N @ Tw
        Nb = np.zeros((2, 4 * n))
        Nb[0, 0::2], Nb[1, 1::2] = N, N
        Nb = Nb @ Tb
        M += (wq * det) * (mu * np.outer(Nw, Nw) + rot * Nb.T @ Nb)
    return (K + K.T) / 2, (M + M.T) / 2
