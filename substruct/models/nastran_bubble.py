r"""Stiffness of the 8-grid hexahedron with bubble functions (incompatible modes), MSC
Nastran's default CHEXA (PSOLID ``IN`` blank/``0``/``BUBBLE``, ``ISOP`` blank/``REDUCED``).

The displacement is the trilinear field of the corners plus three bubbles per component,

.. math::  u = \sum_{i=1}^{8} N_i(\xi)\, u_i + \sum_{k=1}^{3} P_k(\xi)\, a_k, \qquad
           P = (1 - \xi^2,\; 1 - \eta^2,\; 1 - \zeta^2),

nine internal coordinates :math:`a` per element (Wilson, Taylor, Doherty and Ghaboussi 1973).
Their strains use the Jacobian :math:`J_0` at the centre, scaled so that they integrate to
zero over any element (Taylor, Beresford and Wilson 1976, the form of Simo and Rifai 1990):

.. math::  \nabla P_k(\xi) = \frac{\det J_0}{\det J(\xi)}\, J_0^{-T} \partial_\xi P_k(\xi),
           \qquad \int_{\Omega_e} \nabla P_k \, d\Omega = 0,

so a constant strain stores no energy in the bubbles and the element passes the patch test
on any shape.  With :math:`B_c`, :math:`B_b` the strain-displacement matrices of the corners
and of the bubbles, and :math:`D` the isotropic elasticity matrix, 2 x 2 x 2 Gauss points
give :math:`K_{cc}, K_{cb}, K_{bb}` (:math:`K_{xy} = \int B_x^T D B_y\, d\Omega`), and the
bubbles are condensed statically in each element:

.. math::  K_e = K_{cc} - K_{cb} K_{bb}^{-1} K_{bc}.

A rectangular element then bends exactly (its strain field holds the linear bending strain
with no parasitic shear), which the fully integrated trilinear element cannot.  The bubbles
carry no mass.
"""

from __future__ import annotations

import numpy as np

__all__ = ["bubble_hex_stiffness", "isotropic_D"]

# reference corners in Nastran's (and meshio's) order: G1-G4 at zeta = -1, G5-G8 at zeta = 1
_CORNERS = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                     [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], dtype=float)
_GAUSS = np.array([[a, b, c] for c in (-1, 1) for b in (-1, 1) for a in (-1, 1)],
                  dtype=float) / np.sqrt(3.0)


def isotropic_D(E: float, nu: float) -> np.ndarray:
    r"""The 6 x 6 elasticity matrix in Voigt order :math:`(xx, yy, zz, yz, xz, xy)`, engineering
    shear strains: :math:`\lambda` off the normal diagonal, :math:`\lambda + 2\mu` on it and
    :math:`\mu` on the shear diagonal."""
    mu = E / (2 * (1 + nu))
    lam = E * nu / ((1 + nu) * (1 - 2 * nu))
    D = np.zeros((6, 6))
    D[:3, :3] = lam
    D[np.arange(3), np.arange(3)] = lam + 2 * mu
    D[np.arange(3, 6), np.arange(3, 6)] = mu
    return D


def _strain_matrix(G: np.ndarray) -> np.ndarray:
    """``B (..., 6, 3 n)`` from gradients ``G (..., n, 3)`` of ``n`` scalar functions, the
    coordinates ordered function by function (``3 j + c``)."""
    shape = G.shape[:-2]
    n = G.shape[-2]
    B = np.zeros(shape + (6, 3 * n))
    for c in range(3):
        B[..., c, c::3] = G[..., :, c]
    for row, (a, b) in zip((3, 4, 5), ((1, 2), (0, 2), (0, 1))):
        B[..., row, a::3] = G[..., :, b]
        B[..., row, b::3] = G[..., :, a]
    return B


def bubble_hex_stiffness(X: np.ndarray, D: np.ndarray) -> np.ndarray:
    """Condensed stiffness ``(ne, 24, 24)`` of hexahedra with corners ``X (ne, 8, 3)`` in
    Nastran's order (module docstring); coordinates ``3 * corner + component``.

    Raises:
        ValueError: an element whose Jacobian is singular at a Gauss point or its centre.
    """
    X = np.asarray(X, dtype=float)
    ne = X.shape[0]
    s = _CORNERS
    # dN/dxi at the Gauss points and the centre: (ng, 8, 3)
    pts = np.vstack([_GAUSS, np.zeros((1, 3))])
    one = 1 + pts[:, None, :] * s[None, :, :]  # (np, 8, 3)
    dN = np.empty_like(one)
    for d in range(3):
        others = [k for k in range(3) if k != d]
        dN[..., d] = s[None, :, d] * one[..., others[0]] * one[..., others[1]] / 8
    J = np.einsum("pid,eic->epcd", dN, X)  # (ne, np, 3 [x], 3 [xi]): dx_c / dxi_d
    det = np.linalg.det(J)
    if not np.all(np.isfinite(det)) or np.any(np.abs(det) <= 1e-14 * np.abs(det).max(
            initial=0.0)):
        raise ValueError("a singular Jacobian")
    Jinv = np.linalg.inv(J)  # dxi_d / dx_c: (ne, np, 3 [xi], 3 [x])
    gc = np.einsum("pid,epdc->epic", dN[:8], Jinv[:, :8])  # corner gradients (ne, 8, 8, 3)
    dP = np.zeros((8, 3, 3))  # d P_k / d xi_d at the Gauss points
    for k in range(3):
        dP[:, k, k] = -2 * _GAUSS[:, k]
    det0, Jinv0 = det[:, 8], Jinv[:, 8]
    gb = np.einsum("pkd,edc->epkc", dP, Jinv0) * (det0[:, None] / det[:, :8])[..., None, None]
    Bc, Bb = _strain_matrix(gc), _strain_matrix(gb)  # (ne, 8, 6, 24), (ne, 8, 6, 9)
    w = np.abs(det[:, :8])  # Gauss weights are 1
    DBc = np.einsum("ij,epjk->epik", D, Bc)
    DBb = np.einsum("ij,epjk->epik", D, Bb)
    Kcc = np.einsum("ep,epik,epil->ekl", w, Bc, DBc)
    Kcb = np.einsum("ep,epik,epil->ekl", w, Bc, DBb)
    Kbb = np.einsum("ep,epik,epil->ekl", w, Bb, DBb)
    K = Kcc - Kcb @ np.linalg.solve(Kbb, np.swapaxes(Kcb, 1, 2))
    K = (K + np.swapaxes(K, 1, 2)) / 2
    assert K.shape == (ne, 24, 24)
    return K
