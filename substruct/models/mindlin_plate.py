r"""Reissner-Mindlin plate bending free of shear locking: the MITC4 quadrilateral and the MITC3
triangle, batched over elements.

Three coordinates at each corner, ``(w, theta_x, theta_y)`` in the element's plane, as the
Kirchhoff elements of :mod:`substruct.models.plate_bending`: the normal's rotations are
:math:`\beta_x = \theta_y`, :math:`\beta_y = -\theta_x`, and ``w`` and :math:`\beta` are both
interpolated with the corner shapes ``N`` (linear T3, bilinear Q4).  The energy is

.. math::  U = \tfrac12 \int_A \kappa^T D_b \kappa \, dA
           + \tfrac12 \int_A S\, \gamma^T \gamma \, dA, \qquad
           \kappa = (\beta_{x,x},\ \beta_{y,y},\ \beta_{x,y} + \beta_{y,x}), \quad
           \gamma = \nabla w + \beta

with :math:`D_b = \frac{E t^3}{12(1-\nu^2)}[\ldots]` and the transverse shear stiffness per
width :math:`S = \kappa_s G t` (:math:`\kappa_s = 5/6`; Nastran's ``TS/T`` times ``T`` and
MID3's ``G``).  Integrating :math:`\gamma` of the same ``N`` would *lock* (a thin plate's
constraint :math:`\gamma = 0` cannot hold with bilinear ``w`` and :math:`\beta`); the MITC
elements replace it by an assumed field tied to the covariant shear strains
:math:`e_\xi = \gamma \cdot x_{,\xi} = w_{,\xi} + \beta\cdot x_{,\xi}` at points where they
are right:

* **MITC4** (Bathe and Dvorkin 1985, eq. 11): :math:`e_\xi` at the mid-sides
  :math:`A = (0, -1)`, :math:`C = (0, 1)`, :math:`e_\eta` at :math:`D = (-1, 0)`,
  :math:`B = (1, 0)`,

  .. math::  \hat e_\xi = \tfrac{1-\eta}{2} e_\xi^A + \tfrac{1+\eta}{2} e_\xi^C, \qquad
             \hat e_\eta = \tfrac{1-\xi}{2} e_\eta^D + \tfrac{1+\xi}{2} e_\eta^B,

  and :math:`\gamma = J^{-1} (\hat e_\xi, \hat e_\eta)` (rows of ``J``: :math:`x_{,\xi},
  x_{,\eta}`); 2 x 2 Gauss points for both energies.
* **MITC3** (Lee and Bathe 2004, eqs. 8-9): with :math:`e_r^{(1)}` at :math:`(1/2, 0)`,
  :math:`e_s^{(2)}` at :math:`(0, 1/2)` and both at :math:`(1/2, 1/2)`,

  .. math::  \hat e_r = e_r^{(1)} + c\, s, \qquad \hat e_s = e_s^{(2)} - c\, r, \qquad
             c = e_s^{(2)} - e_r^{(1)} - e_s^{(3)} + e_r^{(3)}

  (the tangential strain constant along each side); the three mid-side points (exact for
  the quadratic integrand).  MITC3 rather than DSG3: it is isotropic (independent of the
  node numbering), which DSG3 is not; MITC3+ cures MITC3's residual locking with a cubic
  bubble on the rotations (an internal coordinate to condense) at a larger cost per element,
  where the stabilisation below does it at none.

**Shear stabilisation.** Alone, MITC3 still locks in thin plates (a simply supported plate at
t/a = 1e-3 on 8 x 8 x 2 triangles: 4.9 times Kirchhoff's fundamental eigenvalue, measured),
and MITC4 on coarse meshes of thick plates stores spurious shear energy at the tying points.
Both elements therefore use the stabilised shear stiffness of Lyly, Stenberg and Vihinen
(1993), convergent uniformly in ``t``,

.. math::  S_h = S\, \frac{t^2}{t^2 + \alpha h^2}, \qquad \alpha = 0.1
           \ (\text{:data:`STABILISATION`}),

with ``h`` the element's longest side: a change of order :math:`(h/t)^2` where the mesh
resolves the thickness, so the converged answer is Mindlin's (Nastran's CQUAD4 and CTRIA3
likewise add a residual bending flexibility to their transverse shear).  Measured:
the thin-plate triangle above 1.09 times Kirchhoff's, and the simply supported plate at
t/a = 0.1 on 8 x 8 quadrilaterals 2.5 % high (3.4 % without).

Both elements represent a constant curvature with zero shear (``w`` quadratic, :math:`\beta =
-\nabla w` linear: the tied strains are zero exactly, since a secant of a quadratic is its
tangent at the mid-side) and a constant shear exactly, so they pass the patch tests on
distorted meshes, and they converge to Kirchhoff's plate as ``t -> 0`` without locking
(measured in tests/test_mindlin_plate.py).

**Consistent mass** :math:`M = \int_A \mu N_w^T N_w + r N_\beta^T N_\beta\, dA` (``mu`` the mass
per area, ``r`` the rotary inertia :math:`\rho t^3/12`), 3 x 3 Gauss points or the 9-point
triangle rule (exact).  The lumped mass is the shells' (:mod:`substruct.models.shell`).

The element matrices are written here by hand: scikit-fem (12.0) has no MITC element (its
plate elements are Kirchhoff's: Morley, Argyris), and its mixed vector-scalar forms on a 2D
mesh would not give a flat-facet shell element in 3D with the drilling membrane of
:mod:`substruct.models.shell`.
"""

from __future__ import annotations

import numpy as np

from substruct.models.plate_bending import corner_shapes, tabulated

__all__ = ["mindlin_matrices_batch", "mindlin_matrices_local", "KAPPA_SHEAR", "STABILISATION"]

#: The transverse shear correction factor of a homogeneous plate.
KAPPA_SHEAR = 5.0 / 6.0
#: ``alpha`` of the MITC elements' shear stabilisation :math:`S\,t^2 / (t^2 + \alpha h^2)`.
STABILISATION = 0.1


def _inv2(J: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    det = J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0]
    inv = np.empty_like(J)
    inv[:, 0, 0], inv[:, 1, 1] = J[:, 1, 1], J[:, 0, 0]
    inv[:, 0, 1], inv[:, 1, 0] = -J[:, 0, 1], -J[:, 1, 0]
    return det, inv / np.where(det != 0, det, 1.0)[:, None, None]


def _covariant(xy: np.ndarray, p: tuple[float, float]) -> np.ndarray:
    r"""``(m, 2, 3n)``: :math:`(e_\xi, e_\eta) = J \gamma` at reference point ``p`` as rows on
    the element coordinates ``(w, theta_x, theta_y)`` corner by corner."""
    m, n = xy.shape[:2]
    N, dN = corner_shapes(n, np.asarray(p, dtype=float))
    J = np.einsum("ak,mkb->mab", dN, xy)  # J[a, b] = d x_b / d xi_a
    E = np.zeros((m, 2, 3 * n))
    E[:, :, 0::3] = dN[None]
    E[:, :, 2::3] = J[:, :, 0, None] * N  # beta_x = theta_y
    E[:, :, 1::3] = -J[:, :, 1, None] * N  # beta_y = -theta_x
    return E


def _assumed_shear(xy: np.ndarray, p: np.ndarray) -> np.ndarray:
    """``(m, 2, 3n)``: the MITC assumed covariant strains at ``p`` (module docstring)."""
    n = xy.shape[1]
    x, y = float(p[0]), float(p[1])
    if n == 4:
        A, C = _covariant(xy, (0.0, -1.0))[:, 0], _covariant(xy, (0.0, 1.0))[:, 0]
        D, B = _covariant(xy, (-1.0, 0.0))[:, 1], _covariant(xy, (1.0, 0.0))[:, 1]
        return np.stack([(1 - y) / 2 * A + (1 + y) / 2 * C,
                         (1 - x) / 2 * D + (1 + x) / 2 * B], axis=1)
    er1 = _covariant(xy, (0.5, 0.0))[:, 0]
    es2 = _covariant(xy, (0.0, 0.5))[:, 1]
    e3 = _covariant(xy, (0.5, 0.5))
    c = es2 - er1 - e3[:, 1] + e3[:, 0]
    return np.stack([er1 + c * y, es2 - c * x], axis=1)


def mindlin_matrices_batch(xy: np.ndarray, Db: np.ndarray, shear: float, t: float, mu: float,
                           rot: float, consistent: bool = True
                           ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
    r"""Stiffness ``(m, 3n, 3n)``, consistent mass (``None`` unless ``consistent``) and the
    elements with ``det J > 0`` at every point, of ``m`` MITC4 (``n = 4``) or MITC3 (``n =
    3``) elements with corners ``xy`` ``(m, n, 2)`` in their planes (module docstring).

    ``Db``: the bending matrix ``(3, 3)`` (:math:`D_b`, with any ``12 I / T^3``); ``shear``:
    :math:`S = \kappa_s G t`; ``mu``: mass per area; ``rot``: rotary inertia per area."""
    xy = np.asarray(xy, dtype=float)
    m, n = xy.shape[:2]
    K = np.zeros((m, 3 * n, 3 * n))
    ok = np.ones(m, dtype=bool)
    h2 = (np.linalg.norm(xy - np.roll(xy, 1, axis=1), axis=2) ** 2).max(axis=1)
    S = shear * t**2 / (t**2 + STABILISATION * h2)
    for p, wq, _, dN, _, _ in tabulated(n, "stiffness"):
        det, inv = _inv2(np.einsum("ak,mkb->mab", dN, xy))
        ok &= det > 0
        dx = np.einsum("mab,bk->mak", inv, dN)  # (m, 2, n)
        Bb = np.zeros((m, 3, 3 * n))
        Bb[:, 0, 2::3] = dx[:, 0]
        Bb[:, 1, 1::3] = -dx[:, 1]
        Bb[:, 2, 2::3] = dx[:, 1]
        Bb[:, 2, 1::3] = -dx[:, 0]
        Bs = inv @ _assumed_shear(xy, p)  # (m, 2, 3n): gamma
        w = (wq * det)[:, None, None]
        K += w * (Bb.transpose(0, 2, 1) @ (Db @ Bb) + S[:, None, None] * Bs.transpose(0, 2, 1) @ Bs)
    K = (K + K.transpose(0, 2, 1)) / 2
    if not consistent:
        return K, None, ok
    M = np.zeros((m, 3 * n, 3 * n))
    for _, wq, N, dN, _, _ in tabulated(n, "mass"):
        det = _inv2(np.einsum("ak,mkb->mab", dN, xy))[0]
        nn = (wq * det)[:, None, None] * np.outer(N, N)
        M[:, 0::3, 0::3] += mu * nn
        M[:, 1::3, 1::3] += rot * nn
        M[:, 2::3, 2::3] += rot * nn
    return K, M, ok


def mindlin_matrices_local(xy: np.ndarray, Db: np.ndarray, shear: float, t: float,
                           mu: float, rot: float) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness and consistent mass ``(3n, 3n)`` of one MITC4 / MITC3 element
    (:func:`mindlin_matrices_batch` of a stack of one).

    Raises:
        ValueError: a corner angle of 180 degrees or more, or a side of zero length (``det J
            <= 0`` somewhere), or a shear stiffness that is not positive.
    """
    if not shear > 0:
        raise ValueError(f"the transverse shear stiffness must be positive, got {shear!r}")
    K, M, ok = mindlin_matrices_batch(np.asarray(xy, dtype=float)[None], Db, shear, t, mu,
                                     rot)
    if not ok[0]:
        raise ValueError("the element is degenerate or not convex (det J <= 0)")
    assert M is not None
    return K[0], M[0]
