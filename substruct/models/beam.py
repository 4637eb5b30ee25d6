r"""Two-node 3D beam elements with rotational DOFs: Euler-Bernoulli and Timoshenko.

Each node has six coordinates, in the element's local axes ``(u, v, w, theta_x, theta_y,
theta_z)``; the local ``x`` axis runs from node 1 to node 2, ``y`` and ``z`` are the principal
axes of the section.  The element carries four uncoupled actions:

* axial, :math:`EA\,u'' = \rho A\,\ddot u` (linear shape functions);
* torsion, :math:`GJ\,\theta_x'' = \rho I_p\,\ddot\theta_x` (linear; ``I_p`` the polar moment
  of the section for its rotary inertia, ``I_y + I_z`` unless given);
* bending in the ``x-y`` plane, deflection ``v`` and rotation :math:`\theta_z` (``I_z``, shear
  factor :math:`\kappa_y`);
* bending in the ``x-z`` plane, deflection ``w`` and rotation :math:`\theta_y = -w'` (``I_y``,
  shear factor :math:`\kappa_z`).

**Bending** uses the interdependent interpolation of the Timoshenko beam (Friedman and
Kosmatka 1993), exact for the static beam, with :math:`\xi = x/L` and the shear parameter
:math:`\phi = 12 EI / (\kappa G A L^2)`:

.. math::

    N_v = \tfrac{1}{1+\phi}\bigl[2\xi^3 - 3\xi^2 - \phi\xi + 1 + \phi,\;
          L(\xi^3 - (2 + \tfrac\phi2)\xi^2 + (1 + \tfrac\phi2)\xi),\;
          -2\xi^3 + 3\xi^2 + \phi\xi,\; L(\xi^3 - (1 - \tfrac\phi2)\xi^2 - \tfrac\phi2 \xi)\bigr]

    N_\theta = \tfrac{1}{1+\phi}\bigl[\tfrac6L(\xi^2 - \xi),\; 3\xi^2 - (4 + \phi)\xi + 1 + \phi,\;
          -\tfrac6L(\xi^2 - \xi),\; 3\xi^2 - (2 - \phi)\xi\bigr]

.. math::

    K_b = \int_0^L EI\, N_\theta'^T N_\theta' + \kappa G A\, (N_v' - N_\theta)^T (N_v' - N_\theta)
          \,dx, \qquad
    M_b = \int_0^L \rho A\, N_v^T N_v + \rho I\, N_\theta^T N_\theta \,dx

integrated by 5-point Gauss quadrature (exact: the integrands are polynomials of degree 6).
``K_b`` is the classical closed form :math:`\frac{EI}{(1+\phi)L^3}[12, 6L, -12, 6L; \dots]`.
With ``theory="euler-bernoulli"`` :math:`\phi = 0` (Hermite cubics) and the rotary inertia term
is left out, so that the element converges to the classical Euler-Bernoulli beam
(:math:`\beta_n L = 1.8751, 4.6941, \dots`); ``"timoshenko"`` keeps both shear deformation and
rotary inertia and converges to the Timoshenko beam.

**Lumped mass** puts half of each element's mass on each node: ``rho A L / 2`` on the
translations, ``rho I_p L / 2`` on the twist and, on the bending rotations, the rotary inertia
of the half element about its node, ``rho A L^3 / 24`` (plus ``rho I L / 2`` for Timoshenko).
Both consistent and lumped masses converge to the same limit (measured in tests/test_beams.py:
Euler-Bernoulli frequency errors fall like ``h^4`` with the consistent, ``h^2`` with the lumped
mass; Timoshenko errors of a thick beam like ``h^2``, the shear strain being constant along an
element).

**Orientation**: the local ``y`` axis lies in the plane of the beam axis and an orientation
vector ``v`` (Nastran's CBAR convention): :math:`e_z = e_x \times v / |e_x \times v|`,
:math:`e_y = e_z \times e_x`.  Global matrices are :math:`T^T K T` with
``T = diag(R, R, R, R)``, the rows of ``R`` being :math:`e_x, e_y, e_z`.

**End releases** (pinned ends, Nastran's pin flags): released local coordinates are condensed
out statically, :math:`K^* = K_{rr} - K_{rc}K_{cc}^{-1}K_{cr}`, and the mass follows the same
static shapes (:math:`M^* = S^T M S`); the released coordinates keep zero rows.

The element matrices are written by hand: scikit-fem (12.0) has a scalar Hermite line element
(``ElementLineHermite``, a 1D Euler-Bernoulli beam along a line) but no 3D frame element with
six DOFs per node, orientation, torsion or Timoshenko shear.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

__all__ = ["THEORIES", "MASSES", "Section", "Material", "bending_matrices",
           "local_matrices", "rotation", "beam_matrices", "release"]

#: Beam theories: ``"euler-bernoulli"`` (no shear deformation, no rotary inertia) and
#: ``"timoshenko"`` (both).
THEORIES = ("euler-bernoulli", "timoshenko")
#: Mass matrices: ``"consistent"`` and ``"lumped"``.
MASSES = ("consistent", "lumped")

_GAUSS_X, _GAUSS_W = np.polynomial.legendre.leggauss(5)


@dataclass(frozen=True)
class Section:
    """Cross-section properties.

    Attributes:
        A: area.
        Iy, Iz: second moments of area about the local ``y`` and ``z`` axes (``Iz`` resists
            bending in the ``x-y`` plane).
        J: torsion constant.
        ky, kz: shear factors for shear along ``y`` and ``z`` (Timoshenko; 5/6 for a
            rectangle).
        Ip: polar moment for the rotary inertia of torsion (``Iy + Iz`` if ``None``).
    """

    A: float
    Iy: float
    Iz: float
    J: float
    ky: float = 5.0 / 6.0
    kz: float = 5.0 / 6.0
    Ip: float | None = None

    def __post_init__(self) -> None:
        for key in ("A", "Iy", "Iz", "J", "ky", "kz"):
            _positive(key, getattr(self, key))
        if self.Ip is not None:
            _positive("Ip", self.Ip)

    @property
    def polar(self) -> float:
        """``Ip`` (``Iy + Iz`` if not given)."""
        return float(self.Ip) if self.Ip is not None else float(self.Iy + self.Iz)


@dataclass(frozen=True)
class Material:
    """Isotropic elastic material: Young's modulus ``E``, shear modulus ``G``, density
    ``rho``."""

    E: float
    G: float
    rho: float

    def __post_init__(self) -> None:
        for key in ("E", "G", "rho"):
            _positive(key, getattr(self, key))


def _positive(key: str, value: float) -> None:
    v = float(value)
    if not (np.isfinite(v) and v > 0) or isinstance(value, bool):
        raise ValueError(f"{key} must be a finite positive number, got {value!r}")


def bending_matrices(L: float, EI: float, kGA: float | None, rhoA: float, rhoI: float
                     ) -> tuple[np.ndarray, np.ndarray]:
    r"""Stiffness and consistent mass (4 x 4) of bending in the ``x-y`` plane, coordinates
    ``(v_1, \theta_1, v_2, \theta_2)`` with :math:`\theta = v'` for Euler-Bernoulli.

    ``kGA=None`` is Euler-Bernoulli (:math:`\phi = 0`); ``rhoI`` the rotary inertia per unit
    length (0 to leave it out).  See the module docstring for the shape functions.
    """
    phi = 0.0 if kGA is None else 12.0 * EI / (kGA * L * L)
    s = 1.0 / (1.0 + phi)
    xi = (_GAUSS_X + 1.0) / 2.0
    w = _GAUSS_W * L / 2.0
    one = np.ones_like(xi)
    Nv = s * np.array([2 * xi**3 - 3 * xi**2 - phi * xi + 1 + phi,
                       L * (xi**3 - (2 + phi / 2) * xi**2 + (1 + phi / 2) * xi),
                       -2 * xi**3 + 3 * xi**2 + phi * xi,
                       L * (xi**3 - (1 - phi / 2) * xi**2 - phi / 2 * xi)])
    dNv = s / L * np.array([6 * xi**2 - 6 * xi - phi * one,
                            L * (3 * xi**2 - (4 + phi) * xi + (1 + phi / 2) * one),
                            -6 * xi**2 + 6 * xi + phi * one,
                            L * (3 * xi**2 - (2 - phi) * xi - phi / 2 * one)])
    Nt = s * np.array([6 / L * (xi**2 - xi), 3 * xi**2 - (4 + phi) * xi + 1 + phi,
                       -6 / L * (xi**2 - xi), 3 * xi**2 - (2 - phi) * xi])
    dNt = s / L * np.array([6 / L * (2 * xi - 1), 6 * xi - (4 + phi) * one,
                            -6 / L * (2 * xi - 1), 6 * xi - (2 - phi) * one])
    K = EI * (dNt * w) @ dNt.T
    if kGA is not None:
        gamma = dNv - Nt
        K = K + kGA * (gamma * w) @ gamma.T
    M = rhoA * (Nv * w) @ Nv.T
    if rhoI:
        M = M + rhoI * (Nt * w) @ Nt.T
    return (K + K.T) / 2, (M + M.T) / 2


def local_matrices(L: float, section: Section, material: Material,
                   theory: str = "euler-bernoulli", mass: str = "consistent"
                   ) -> tuple[np.ndarray, np.ndarray]:
    r"""Element stiffness and mass (12 x 12) in local axes, coordinates per node
    ``(u, v, w, \theta_x, \theta_y, \theta_z)`` (module docstring).

    Raises:
        ValueError: an unknown ``theory`` or ``mass``, or a length that is not positive.
    """
    if theory not in THEORIES:
        raise ValueError(f"theory must be one of {list(THEORIES)}, got {theory!r}")
    if mass not in MASSES:
        raise ValueError(f"mass must be one of {list(MASSES)}, got {mass!r}")
    _positive("element length", L)
    E, G, rho = material.E, material.G, material.rho
    A, Ip = section.A, section.polar
    timo = theory == "timoshenko"
    K = np.zeros((12, 12))
    M = np.zeros((12, 12))
    bar = np.array([[1.0, -1.0], [-1.0, 1.0]])
    bar_mass = np.array([[2.0, 1.0], [1.0, 2.0]]) / 6.0
    for dof, stiff, inertia in ((0, E * A, rho * A), (3, G * section.J, rho * Ip)):
        idx = np.ix_([dof, dof + 6], [dof, dof + 6])
        K[idx] = stiff / L * bar
        M[idx] = inertia * L * (bar_mass if mass == "consistent" else np.eye(2) / 2)
    # x-y plane: (v, theta_z) = (1, 5); x-z plane: (w, theta_y) = (2, 4), theta_y = -w'
    for v, t, I, kappa, sign in ((1, 5, section.Iz, section.ky, 1.0),
                                 (2, 4, section.Iy, section.kz, -1.0)):
        Kb, Mb = bending_matrices(L, E * I, kappa * G * A if timo else None, rho * A,
                                  rho * I if timo else 0.0)
        D = np.diag([1.0, sign, 1.0, sign])
        idx = np.ix_([v, t, v + 6, t + 6], [v, t, v + 6, t + 6])
        K[idx] = D @ Kb @ D
        if mass == "consistent":
            M[idx] = D @ Mb @ D
        else:
            rot = rho * A * L**3 / 24.0 + (rho * I * L / 2.0 if timo else 0.0)
            M[idx] = np.diag([rho * A * L / 2.0, rot, rho * A * L / 2.0, rot])
    return K, M


def rotation(xi: Sequence[float], xj: Sequence[float], orientation: Sequence[float]
             ) -> np.ndarray:
    r"""Rows :math:`e_x, e_y, e_z` of the local axes: :math:`e_x` from node ``i`` to ``j``,
    :math:`e_z = e_x \times v / |e_x \times v|`, :math:`e_y = e_z \times e_x`.

    Raises:
        ValueError: coincident nodes, or an orientation vector parallel to the axis (within
            ``1e-8`` of the angle, whatever the lengths).
    """
    d = np.asarray(xj, dtype=float) - np.asarray(xi, dtype=float)
    v = np.asarray(orientation, dtype=float)
    L, nv = float(np.linalg.norm(d)), float(np.linalg.norm(v))
    if not (L > 0 and np.isfinite(L)):
        raise ValueError(f"element from {np.asarray(xi, dtype=float).tolist()} to "
                         f"{np.asarray(xj, dtype=float).tolist()} has no length")
    if not (nv > 0 and np.isfinite(nv)):
        raise ValueError(f"orientation vector {v.tolist()} is not a finite non-zero vector")
    ex = d / L
    ez = np.cross(ex, v / nv)
    nz = float(np.linalg.norm(ez))
    if nz < 1e-8:
        raise ValueError(f"orientation vector {v.tolist()} is parallel to the element axis "
                         f"{ex.tolist()}")
    ez /= nz
    return np.vstack([ex, np.cross(ez, ex), ez])


def release(K: np.ndarray, M: np.ndarray, released: Sequence[int]
            ) -> tuple[np.ndarray, np.ndarray]:
    r"""Condense released local coordinates out of an element: with ``r`` kept and ``c``
    released, :math:`S = [I; -K_{cc}^{-1} K_{cr}]`, :math:`K^* = S^T K S`, :math:`M^* = S^T M S`
    (static shapes), the released rows and columns zero.

    Raises:
        ValueError: the releases leave a mechanism inside the element (singular ``K_cc``, e.g.
            the same rotation released at both ends).
    """
    c = np.unique(np.asarray(list(released), dtype=int))
    if c.size == 0:
        return K, M
    if np.any((c < 0) | (c >= K.shape[0])):
        raise ValueError(f"released coordinates must be in 0..{K.shape[0] - 1}, got {c.tolist()}")
    r = np.setdiff1d(np.arange(K.shape[0]), c)
    Kcc = K[np.ix_(c, c)]
    if np.linalg.cond(Kcc) > 1e10:
        raise ValueError(f"releasing local coordinates {c.tolist()} leaves a mechanism in the "
                         f"element")
    S = np.zeros((K.shape[0], r.size))
    S[r, np.arange(r.size)] = 1.0
    S[c] = -np.linalg.solve(Kcc, K[np.ix_(c, r)])
    Ks, Ms = np.zeros_like(K), np.zeros_like(M)
    Ks[np.ix_(r, r)] = S.T @ K @ S
    Ms[np.ix_(r, r)] = S.T @ M @ S
    return (Ks + Ks.T) / 2, (Ms + Ms.T) / 2


def beam_matrices(xi: Sequence[float], xj: Sequence[float], orientation: Sequence[float],
                  section: Section, material: Material, theory: str = "euler-bernoulli",
                  mass: str = "consistent", released: Sequence[int] = ()
                  ) -> tuple[np.ndarray, np.ndarray]:
    r"""Global stiffness and mass (12 x 12) of a beam from ``xi`` to ``xj``:
    :math:`T^T K_\ell T`, :math:`T^T M_\ell T` with ``T = diag(R, R, R, R)``
    (:func:`rotation`), after condensing the ``released`` local coordinates (0-11, node 1's
    ``u v w tx ty tz`` then node 2's; :func:`release`).
    """
    R = rotation(xi, xj, orientation)
    L = float(np.linalg.norm(np.asarray(xj, float) - np.asarray(xi, float)))
    K, M = local_matrices(L, section, material, theory, mass)
    K, M = release(K, M, released)
    T = np.kron(np.eye(4), R)
    return T.T @ K @ T, T.T @ M @ T
