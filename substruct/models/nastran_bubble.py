r"""Stiffness of the 8-grid hexahedron and the 6-grid wedge with bubble functions (incompatible
modes), MSC Nastran's default CHEXA and CPENTA (PSOLID ``IN`` blank/``0``/``BUBBLE``, ``ISOP``
blank/``REDUCED``).

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

The wedge (corners :math:`L_i (1 \mp \zeta)/2` with the triangle's area coordinates
:math:`L_1 = 1 - r - s, L_2 = r, L_3 = s`, :math:`\zeta \in [-1, 1]`) takes four bubbles per
component, twelve internal coordinates: :math:`1 - \zeta^2` along its axis and the triangle's
three edge functions :math:`4 L_1 L_2, 4 L_2 L_3, 4 L_3 L_1`, which with the corners span
every quadratic in the triangle's plane.  The edge functions' reference gradients do not
integrate to zero over the triangle, so their mean over the reference wedge is subtracted
before the mapping above (:math:`\partial_\xi P_k - \overline{\partial_\xi P_k}`), which
again makes :math:`\int_{\Omega_e} \nabla P_k\, d\Omega = 0` and passes the patch test; the
3 x 2 rule (the triangle's three points, two Gauss points along the axis) integrates it.  A
wedge bent along its axis (triangles across the beam) then bends exactly with
:math:`\nu = 0`, where the plain wedge is four times too stiff; bent across its axis, the
edge functions remove part of the parasitic shear (a stack of wedges through the thickness)
or none of it (bending in the triangles' plane, whose linear field is of constant strain).
"""

from __future__ import annotations

import numpy as np

__all__ = ["bubble_hex_stiffness", "bubble_wedge_stiffness", "isotropic_D", "strain_matrix"]

# reference corners in Nastran's (and meshio's) order: G1-G4 at zeta = -1, G5-G8 at zeta = 1
_CORNERS = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                     [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], dtype=float)
_GAUSS = np.array([[a, b, c] for c in (-1, 1) for b in (-1, 1) for a in (-1, 1)],
                  dtype=float) / np.sqrt(3.0)
# the wedge's 3 x 2 rule on r, s >= 0, r + s <= 1, zeta in [-1, 1] (weights sum to 1)
_TRI = np.array([[1, 1], [4, 1], [1, 4]], dtype=float) / 6
_WEDGE_POINTS = np.array([[r, s, z] for z in (-1, 1) for r, s in _TRI]) * [1, 1, 1 / np.sqrt(3)]
_WEDGE_CENTRE = np.array([1 / 3, 1 / 3, 0.0])


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


def strain_matrix(G: np.ndarray) -> np.ndarray:
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


def _condensed(X: np.ndarray, D: np.ndarray, dN: np.ndarray, dN0: np.ndarray,
               dP: np.ndarray, weights: np.ndarray) -> np.ndarray:
    r""":math:`K_{cc} - K_{cb} K_{bb}^{-1} K_{bc}` (module docstring) of elements with corners
    ``X (ne, n, 3)``: corner gradients ``dN (ng, n, 3)`` at the rule's points and ``dN0
    (n, 3)`` at the centre, bubble gradients ``dP (ng, nb, 3)`` (reference axes), weights
    ``(ng,)``; the bubbles' mean gradient over the reference element is removed.

    Raises:
        ValueError: an element whose Jacobian is singular at a point of the rule or its centre.
    """
    ne, n = X.shape[:2]
    J = np.einsum("pid,eic->epcd", dN, X)  # dx_c / dxi_d: (ne, ng, 3, 3)
    J0 = np.einsum("id,eic->ecd", dN0, X)
    det, det0 = np.linalg.det(J), np.linalg.det(J0)
    both = np.concatenate([det, det0[:, None]], axis=1)
    if not np.all(np.isfinite(both)) or np.any(np.abs(both) <= 1e-14 * np.abs(both).max(
            initial=0.0)):
        raise ValueError("a singular Jacobian")
    gc = np.einsum("pid,epdc->epic", dN, np.linalg.inv(J))  # corner gradients (ne, ng, n, 3)
    dPc = dP - np.einsum("p,pkd->kd", weights, dP) / weights.sum()
    gb = np.einsum("pkd,edc->epkc", dPc, np.linalg.inv(J0)) * \
        (det0[:, None] / det)[..., None, None]
    Bc, Bb = strain_matrix(gc), strain_matrix(gb)
    w = weights * np.abs(det)
    DBc = np.einsum("ij,epjk->epik", D, Bc)
    DBb = np.einsum("ij,epjk->epik", D, Bb)
    Kcc = np.einsum("ep,epik,epil->ekl", w, Bc, DBc)
    Kcb = np.einsum("ep,epik,epil->ekl", w, Bc, DBb)
    Kbb = np.einsum("ep,epik,epil->ekl", w, Bb, DBb)
    K = Kcc - Kcb @ np.linalg.solve(Kbb, np.swapaxes(Kcb, 1, 2))
    K = (K + np.swapaxes(K, 1, 2)) / 2
    assert K.shape == (ne, 3 * n, 3 * n)
    return K


def _hex_gradients(pts: np.ndarray) -> np.ndarray:
    """d N_i / d xi_d of the trilinear corners at points ``(np, 3)``: ``(np, 8, 3)``."""
    s = _CORNERS
    one = 1 + pts[:, None, :] * s[None, :, :]
    dN = np.empty_like(one)
    for d in range(3):
        others = [k for k in range(3) if k != d]
        dN[..., d] = s[None, :, d] * one[..., others[0]] * one[..., others[1]] / 8
    return dN


def bubble_hex_stiffness(X: np.ndarray, D: np.ndarray) -> np.ndarray:
    """Condensed stiffness ``(ne, 24, 24)`` of hexahedra with corners ``X (ne, 8, 3)`` in
    Nastran's order (module docstring); coordinates ``3 * corner + component``.

    Raises:
        ValueError: an element whose Jacobian is singular at a Gauss point or its centre.
    """
    X = np.asarray(X, dtype=float)
    dP = np.zeros((8, 3, 3))  # d P_k / d xi_d at the Gauss points
    for k in range(3):
        dP[:, k, k] = -2 * _GAUSS[:, k]
    return _condensed(X, D, _hex_gradients(_GAUSS), _hex_gradients(np.zeros((1, 3)))[0], dP,
                      np.ones(8))


def _wedge_gradients(pts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Reference gradients at points ``(np, 3)`` of the wedge's corners ``(np, 6, 3)`` (G1-G3
    at zeta = -1, G4-G6 at zeta = 1) and of its bubbles ``(np, 4, 3)``: ``1 - zeta^2``,
    ``4 L1 L2``, ``4 L2 L3``, ``4 L3 L1``."""
    r, s, z = pts.T
    L = np.stack([1 - r - s, r, s], axis=-1)
    dL = np.array([[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]])  # d L_i / d(r, s)
    dN = np.zeros((len(pts), 6, 3))
    for first, sign in ((0, -1.0), (3, 1.0)):
        f = (1 + sign * z) / 2
        dN[:, first:first + 3, :2] = dL[None] * f[:, None, None]
        dN[:, first:first + 3, 2] = L * sign / 2
    dP = np.zeros((len(pts), 4, 3))
    dP[:, 0, 2] = -2 * z
    for k, (i, j) in enumerate(((0, 1), (1, 2), (2, 0))):
        dP[:, k + 1, :2] = 4 * (L[:, j, None] * dL[i] + L[:, i, None] * dL[j])
    return dN, dP


def bubble_wedge_stiffness(X: np.ndarray, D: np.ndarray) -> np.ndarray:
    """Condensed stiffness ``(ne, 18, 18)`` of wedges with corners ``X (ne, 6, 3)`` in
    Nastran's order, G1-G3 one triangle and G4-G6 the other (module docstring); coordinates
    ``3 * corner + component``.

    Raises:
        ValueError: an element whose Jacobian is singular at a point of the rule or its centre.
    """
    X = np.asarray(X, dtype=float)
    dN, dP = _wedge_gradients(_WEDGE_POINTS)
    dN0 = _wedge_gradients(_WEDGE_CENTRE[None])[0][0]
    return _condensed(X, D, dN, dN0, dP, np.full(6, 1 / 6))
