r"""The 20-grid CHEXA (serendipity hexahedron) and the 15-grid CPENTA (quadratic wedge) as
element matrices, computed for all elements at once.

Grid numbering (Nastran's connection figures of CHEXA and CPENTA in the MSC Nastran Quick
Reference Guide; the CPENTA's remark 2, "G1, G10 and G4 are on the same edge", states it in
words): the corners first, then one grid on each edge,

* CHEXA: G1-G4 one face, G5-G8 the opposite one (G5 opposite G1); G9 (1-2), G10 (2-3),
  G11 (3-4), G12 (4-1) around the first face, G13 (1-5), G14 (2-6), G15 (3-7), G16 (4-8)
  between the faces, G17 (5-6), G18 (6-7), G19 (7-8), G20 (8-5) around the second face;
* CPENTA: G1-G3 one triangle, G4-G6 the other (G4 opposite G1); G7 (1-2), G8 (2-3),
  G9 (3-1), G10 (1-4), G11 (2-5), G12 (3-6), G13 (4-5), G14 (5-6), G15 (6-4).

Shape functions.  Hexahedron on :math:`[-1, 1]^3`, a corner at :math:`\xi_i` and a grid on an
edge along :math:`\xi_k` (its :math:`\xi_{i,k} = 0`):

.. math::  N_i = \tfrac18 \prod_k (1 + \xi_{i,k} \xi_k) \Bigl(\sum_k \xi_{i,k} \xi_k - 2\Bigr),
           \qquad N_i = \tfrac14 (1 - \xi_k^2) \prod_{l \ne k} (1 + \xi_{i,l} \xi_l).

Wedge: area coordinates :math:`L_1 = 1 - r - s, L_2 = r, L_3 = s` of the triangle times
:math:`\zeta \in [-1, 1]` (:math:`\zeta_i = -1` on G1-G3, :math:`+1` on G4-G6),

.. math::  N_i = \tfrac12 L_a (2 L_a - 1)(1 + \zeta_i \zeta) - \tfrac12 L_a (1 - \zeta^2),
           \quad N_{ab} = 2 L_a L_b (1 + \zeta_i \zeta), \quad N_{a, a+3} = L_a (1 - \zeta^2),

with :math:`a` the triangle corner under corner :math:`i`.  Both spaces hold every quadratic
polynomial, so a straight-edged element reproduces any linear field exactly (patch test).

The isoparametric map :math:`x = \sum_j N_j x_j`, and

.. math::  K_e = \sum_p w_p\, B_p^T D B_p \,|\det J_p|, \qquad
           M_e = \rho \sum_p w_p\, \Phi_p^T \Phi_p \,|\det J_p|

with full Gauss integration (Nastran's ``IN = 3``, ``ISOP = FULL``): 3 x 3 x 3 points on the
hexahedron; on the wedge the 7-point triangle rule of degree 5 times 3 Gauss points along
:math:`\zeta` (degree 5).  On a parallelepiped or a straight prism (constant Jacobian) the
integrands of :math:`K` and :math:`M` are at most of degree 4 in each variable, so both rules
are exact there.  An element whose Jacobian vanishes or changes sign at a point of the rule or
at one of its grids is refused (a mid-side grid at or past the quarter point of its edge makes
it vanish at the corner).  Coordinates ``3 * grid + component``, grids in the card's order.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
from skfem.quadrature import get_quadrature
from skfem.refdom import RefTri

from substruct.models.nastran_bubble import strain_matrix

__all__ = ["hex20_matrices", "penta15_matrices", "HEX20_EDGES", "PENTA15_EDGES",
           "quadratic_solid_matrices", "hex_rule", "wedge_rule"]

#: The corners joined by each mid-side grid G9 - G20 of the CHEXA (0-based corner indices).
HEX20_EDGES = ((0, 1), (1, 2), (2, 3), (3, 0), (0, 4), (1, 5), (2, 6), (3, 7),
               (4, 5), (5, 6), (6, 7), (7, 4))
#: The corners joined by each mid-side grid G7 - G15 of the CPENTA.
PENTA15_EDGES = ((0, 1), (1, 2), (2, 0), (0, 3), (1, 4), (2, 5), (3, 4), (4, 5), (5, 3))

_HEX_CORNERS = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                         [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], dtype=float)
_HEX_NODES = np.vstack([_HEX_CORNERS] + [(_HEX_CORNERS[a] + _HEX_CORNERS[b]) / 2
                                          for a, b in HEX20_EDGES])
_PENTA_CORNERS = np.array([[0, 0, -1], [1, 0, -1], [0, 1, -1], [0, 0, 1], [1, 0, 1], [0, 1, 1]],
                          dtype=float)
_PENTA_NODES = np.vstack([_PENTA_CORNERS] + [(_PENTA_CORNERS[a] + _PENTA_CORNERS[b]) / 2
                                              for a, b in PENTA15_EDGES])


def _hex_shape(pts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Values ``(np, 20)`` and reference gradients ``(np, 20, 3)`` at points ``(np, 3)``."""
    npt = len(pts)
    N = np.zeros((npt, 20))
    dN = np.zeros((npt, 20, 3))
    for i, a in enumerate(_HEX_NODES):
        f = 1 + a[None, :] * pts  # (np, 3) the linear factors
        if i < 8:
            s = pts @ a - 2
            prod = f.prod(axis=1)
            N[:, i] = prod * s / 8
            for k in range(3):
                others = np.prod(np.delete(f, k, axis=1), axis=1)
                dN[:, i, k] = (a[k] * others * s + prod * a[k]) / 8
        else:
            k0 = int(np.flatnonzero(a == 0)[0])
            q = 1 - pts[:, k0] ** 2
            rest = [k for k in range(3) if k != k0]
            N[:, i] = q * f[:, rest[0]] * f[:, rest[1]] / 4
            dN[:, i, k0] = -2 * pts[:, k0] * f[:, rest[0]] * f[:, rest[1]] / 4
            dN[:, i, rest[0]] = q * a[rest[0]] * f[:, rest[1]] / 4
            dN[:, i, rest[1]] = q * f[:, rest[0]] * a[rest[1]] / 4
    return N, dN


def _penta_shape(pts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Values ``(np, 15)`` and reference gradients ``(np, 15, 3)`` at points ``(np, 3)`` of
    :math:`(r, s, \\zeta)`."""
    r, s, z = pts.T
    L = np.stack([1 - r - s, r, s], axis=1)
    dL = np.array([[-1.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    ez = np.array([0.0, 0.0, 1.0])
    npt = len(pts)
    N = np.zeros((npt, 15))
    dN = np.zeros((npt, 15, 3))
    bub, dbub = 1 - z ** 2, -2 * z
    for i in range(6):
        a, zi = i % 3, (-1.0 if i < 3 else 1.0)
        la = L[:, a]
        g = 1 + zi * z
        N[:, i] = la * (2 * la - 1) * g / 2 - la * bub / 2
        dN[:, i] = (((4 * la - 1) * g / 2 - bub / 2)[:, None] * dL[a]
                    + (la * (2 * la - 1) * zi / 2 - la * dbub / 2)[:, None] * ez)
    for k, (p, q) in enumerate(PENTA15_EDGES):
        i = 6 + k
        if q == p + 3:  # between the triangles
            N[:, i] = L[:, p] * bub
            dN[:, i] = bub[:, None] * dL[p] + (L[:, p] * dbub)[:, None] * ez
        else:  # on one triangle
            zi = -1.0 if p < 3 else 1.0
            a, b = p % 3, q % 3
            g = 1 + zi * z
            N[:, i] = 2 * L[:, a] * L[:, b] * g
            dN[:, i] = (2 * g[:, None] * (L[:, b, None] * dL[a] + L[:, a, None] * dL[b])
                        + (2 * L[:, a] * L[:, b] * zi)[:, None] * ez)
    return N, dN


def _gauss3() -> tuple[np.ndarray, np.ndarray]:
    return np.polynomial.legendre.leggauss(3)


def hex_rule() -> tuple[np.ndarray, np.ndarray]:
    """The 3 x 3 x 3 Gauss rule on :math:`[-1, 1]^3`: points ``(27, 3)``, weights (sum 8)."""
    x, w = _gauss3()
    P = np.array([[a, b, c] for a in x for b in x for c in x])
    W = np.array([a * b * c for a in w for b in w for c in w])
    return P, W


def wedge_rule() -> tuple[np.ndarray, np.ndarray]:
    """The 7-point triangle rule of degree 5 (scikit-fem's) times 3 Gauss points on
    :math:`\\zeta \\in [-1, 1]`: points ``(21, 3)``, weights summing to the reference
    wedge's volume 1."""
    tri, wt = get_quadrature(RefTri, 5)
    x, w = _gauss3()
    P = np.array([[tri[0, j], tri[1, j], z] for z in x for j in range(tri.shape[1])])
    W = np.array([wt[j] * wz for wz in w for j in range(tri.shape[1])])
    return P, W


def quadratic_solid_matrices(X: np.ndarray, D: np.ndarray, rho: float,
                             shape: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]],
                             rule: Callable[[], tuple[np.ndarray, np.ndarray]],
                             nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness and consistent mass ``(ne, 3n, 3n)`` of elements with grids ``X (ne, n, 3)``
    for the shape functions ``shape``, the rule ``rule`` and the grids' reference coordinates
    ``nodes (n, 3)`` (module docstring).

    Raises:
        ValueError: an element whose Jacobian vanishes or changes sign at a point of the rule
            or at a grid (a mid-side grid moved to or past the quarter point of its edge
            turns the Jacobian at the corner; an inverted element).
    """
    X = np.asarray(X, dtype=float)
    ne, n = X.shape[:2]
    pts, w = rule()
    N, dN = shape(pts)
    J = np.einsum("pid,eic->epcd", dN, X)  # dx_c / dxi_d
    det = np.linalg.det(J)
    det_all = np.concatenate([det, np.linalg.det(np.einsum("pid,eic->epcd", shape(nodes)[1],
                                                           X))], axis=1)
    scale = np.abs(det).max(initial=0.0)
    if not np.all(np.isfinite(det_all)) or np.any(np.abs(det_all) <= 1e-12 * scale) or \
            np.any(np.sign(det_all) != np.sign(det_all[:, :1])):
        raise ValueError("the Jacobian vanishes or changes sign inside the element")
    wd = w[None, :] * np.abs(det)
    B = strain_matrix(np.einsum("pid,epdc->epic", dN, np.linalg.inv(J)))
    K = np.einsum("ep,epik,ij,epjl->ekl", wd, B, D, B, optimize=True)
    Ms = rho * np.einsum("ep,pi,pj->eij", wd, N, N)
    M = np.zeros((ne, 3 * n, 3 * n))
    for c in range(3):
        M[:, c::3, c::3] = Ms
    return (K + np.swapaxes(K, 1, 2)) / 2, (M + np.swapaxes(M, 1, 2)) / 2


def hex20_matrices(X: np.ndarray, D: np.ndarray, rho: float) -> tuple[np.ndarray, np.ndarray]:
    """``K, M (ne, 60, 60)`` of 20-grid CHEXA with grids ``X (ne, 20, 3)`` in Nastran's order
    (module docstring), 3 x 3 x 3 Gauss points."""
    return quadratic_solid_matrices(X, D, rho, _hex_shape, hex_rule, _HEX_NODES)


def penta15_matrices(X: np.ndarray, D: np.ndarray, rho: float
                     ) -> tuple[np.ndarray, np.ndarray]:
    """``K, M (ne, 45, 45)`` of 15-grid CPENTA with grids ``X (ne, 15, 3)`` in Nastran's order
    (module docstring), 7 x 3 points."""
    return quadratic_solid_matrices(X, D, rho, _penta_shape, wedge_rule, _PENTA_NODES)
