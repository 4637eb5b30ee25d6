r"""The 10-grid CTETRA (quadratic tetrahedron, mid-side grids G5-G10) as element matrices,
computed for all elements at once.

With the volume coordinates :math:`L_1 = 1 - r - s - t, L_2 = r, L_3 = s, L_4 = t` of the
reference tetrahedron, the corners G1-G4 and the mid-side grids on the edges in Nastran's
order G5 (1-2), G6 (2-3), G7 (3-1), G8 (1-4), G9 (2-4), G10 (3-4) have

.. math::  N_i = L_i (2 L_i - 1) \; (i = 1..4), \qquad N_{ab} = 4 L_a L_b,

the isoparametric map :math:`x = \sum_j N_j x_j` (a mid-side grid off its edge's middle curves
the element), and

.. math::  K_e = \sum_p w_p\, B_p^T D B_p \,|\det J_p|, \qquad
           M_e = \rho \sum_q w_q\, \Phi_q^T \Phi_q \,|\det J_q|

with :math:`B` the strain-displacement matrix of the gradients :math:`J^{-T} \partial_\xi N`,
:math:`D` the isotropic elasticity matrix, the 4-point rule of degree 2 for :math:`K` and
scikit-fem's degree-4 rule for :math:`M`: both exact on a straight-edged element (constant
Jacobian), where the stiffness is then the same whatever integration network a program uses.
Coordinates ``3 * grid + component``, grids in the card's order.
"""

from __future__ import annotations

import numpy as np
from skfem.quadrature import get_quadrature
from skfem.refdom import RefTet

from substruct.models.nastran_bubble import strain_matrix

__all__ = ["tet10_matrices", "TET10_EDGES"]

#: The corners joined by each mid-side grid G5 - G10 (0-based corner indices).
TET10_EDGES = ((0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3))


def _shape(pts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Values ``(np, 10)`` and reference gradients ``(np, 10, 3)`` at points ``(np, 3)``."""
    r, s, t = pts.T
    L = np.stack([1 - r - s - t, r, s, t], axis=1)
    dL = np.array([[-1.0, -1.0, -1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    N = np.zeros((len(pts), 10))
    dN = np.zeros((len(pts), 10, 3))
    N[:, :4] = L * (2 * L - 1)
    dN[:, :4] = (4 * L - 1)[:, :, None] * dL[None]
    for k, (a, b) in enumerate(TET10_EDGES):
        N[:, 4 + k] = 4 * L[:, a] * L[:, b]
        dN[:, 4 + k] = 4 * (L[:, b, None] * dL[a] + L[:, a, None] * dL[b])
    return N, dN


def tet10_matrices(X: np.ndarray, D: np.ndarray, rho: float
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness and consistent mass ``(ne, 30, 30)`` of the elements with grids ``X (ne, 10,
    3)`` (module docstring).

    Raises:
        ValueError: an element whose Jacobian vanishes or changes sign at a point of a rule
            (a mid-side grid moved too far, an inverted element).
    """
    X = np.asarray(X, dtype=float)
    ne = X.shape[0]
    out = []
    for order in (2, 4):
        pts, w = get_quadrature(RefTet, order)
        N, dN = _shape(pts.T)
        J = np.einsum("pid,eic->epcd", dN, X)  # dx_c / dxi_d
        det = np.linalg.det(J)
        scale = np.abs(det).max(initial=0.0)
        if not np.all(np.isfinite(det)) or np.any(np.abs(det) <= 1e-12 * scale) or \
                np.any(np.sign(det) != np.sign(det[:, :1])):
            raise ValueError("the Jacobian vanishes or changes sign inside the element")
        wd = w[None, :] * np.abs(det)
        if order == 2:
            B = strain_matrix(np.einsum("pid,epdc->epic", dN, np.linalg.inv(J)))
            out.append(np.einsum("ep,epik,ij,epjl->ekl", wd, B, D, B, optimize=True))
        else:
            Ms = rho * np.einsum("ep,pi,pj->eij", wd, N, N)
            M = np.zeros((ne, 30, 30))
            for c in range(3):
                M[:, c::3, c::3] = Ms
            out.append(M)
    K, M = out
    return (K + np.swapaxes(K, 1, 2)) / 2, (M + np.swapaxes(M, 1, 2)) / 2
