r"""Linear elasticity on a mesh: material constants, Rayleigh damping and the consistent mass
and stiffness matrices (scikit-fem, Lagrange P1/Q1 or P2/Q2).

The Lamé parameters are

.. math::

    \mu = \frac{E}{2 (1 + \nu)}, \qquad
    \lambda = \frac{E \nu}{(1 + \nu)(1 - 2\nu)} \ \text{(3D, plane strain)}, \qquad
    \lambda = \frac{E \nu}{1 - \nu^2} \ \text{(plane stress)}.
"""

from __future__ import annotations

from typing import Any, Mapping

import numpy as np
import scipy.sparse as sp
from skfem import (
    Basis,
    BilinearForm,
    ElementHex1,
    ElementHex2,
    ElementQuad1,
    ElementQuad2,
    ElementTetP1,
    ElementTetP2,
    ElementTriP1,
    ElementTriP2,
    Mesh,
    MeshHex,
    MeshQuad,
    MeshTet,
    MeshTri,
    asm,
)
from skfem.models.elasticity import lame_parameters, plane_stress

__all__ = ["MESH_KIND", "lame", "rayleigh", "elasticity_matrices"]

#: The cell kind of each scikit-fem mesh type a solid can be made of.
MESH_KIND: dict[type, str] = {MeshHex: "hex", MeshTet: "tet", MeshQuad: "quad", MeshTri: "tri"}

_ELEMENTS = {
    ("hex", 1): ElementHex1, ("hex", 2): ElementHex2,
    ("tet", 1): ElementTetP1, ("tet", 2): ElementTetP2,
    ("quad", 1): ElementQuad1, ("quad", 2): ElementQuad2,
    ("tri", 1): ElementTriP1, ("tri", 2): ElementTriP2,
}


def rayleigh(name: str, damping: Any) -> tuple[float, float]:
    """``(alpha, beta)`` of Rayleigh damping ``C = alpha M + beta K`` from ``None``,
    ``(alpha, beta)`` or ``{"rayleigh": [alpha, beta]}``.

    Raises:
        ValueError: another form, or coefficients that are negative or not finite.
    """
    if damping is None:
        return 0.0, 0.0
    if isinstance(damping, Mapping):
        if set(damping) != {"rayleigh"}:
            raise ValueError(f"{name}: damping must be {{'rayleigh': [alpha, beta]}} (modal "
                             f"damping is given on reduction), got keys {sorted(damping)}")
        damping = damping["rayleigh"]
    try:
        alpha, beta = (float(v) for v in damping)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: Rayleigh damping is (alpha, beta), got {damping!r}") from None
    if not (np.isfinite(alpha) and np.isfinite(beta) and alpha >= 0 and beta >= 0):
        raise ValueError(f"{name}: Rayleigh damping needs finite alpha, beta >= 0, "
                         f"got ({alpha!r}, {beta!r})")
    return alpha, beta


def lame(name: str, E: float, nu: float, rho: float, dim: int, plane: str | None
         ) -> tuple[float, float]:
    """The Lamé parameters ``(lambda, mu)`` (see the module docstring).

    Raises:
        ValueError: ``E`` or ``rho`` not positive, ``nu`` outside (-1, 0.5), ``plane`` given
            for a 3D mesh or missing for a 2D one.
    """
    E, nu, rho = float(E), float(nu), float(rho)
    if not (np.isfinite(E) and E > 0 and np.isfinite(rho) and rho > 0):
        raise ValueError(f"{name}: E and rho must be positive and finite, got E={E}, rho={rho}")
    if not (np.isfinite(nu) and -1.0 < nu < 0.5):
        raise ValueError(f"{name}: Poisson's ratio must lie in (-1, 0.5), got {nu}")
    if dim == 3:
        if plane is not None:
            raise ValueError(f"{name}: plane={plane!r} given for a 3D mesh (use None)")
        return lame_parameters(E, nu)
    if plane == "stress":
        return plane_stress(E, nu)
    if plane == "strain":
        return lame_parameters(E, nu)
    raise ValueError(f"{name}: a 2D solid needs plane='stress' or 'strain', got {plane!r}")


def elasticity_matrices(mesh: Mesh, order: int, lam: float, mu: float, rho: float,
                        scale: float) -> tuple[Basis, sp.csr_array, sp.csr_array]:
    r"""Scalar basis, ``K`` and ``M`` in the interleaved vector numbering ``dim * node + c``.

    With the scalar matrices :math:`G^{ij}_{ab} = \int \partial_i \phi_a\, \partial_j \phi_b`,
    :math:`L = \sum_k G^{kk}` and :math:`S_{ab} = \int \rho\, \phi_a \phi_b`,

    .. math::

        K_{(a,i),(b,j)} = \mu\, \delta_{ij} L_{ab} + \mu\, G^{ji}_{ab} + \lambda\, G^{ij}_{ab},
        \qquad M_{(a,i),(b,j)} = \delta_{ij} S_{ab},

    which is :func:`skfem.models.elasticity.linear_elasticity` (``2 mu eps(u):eps(v) +
    lam div u div v``) on ``ElementVector``, assembled from a scalar basis: a vector basis
    holds ``dim^2`` times more per-quadrature-point data.  ``scale`` multiplies both (the
    thickness of a 2D solid).
    """
    kind = MESH_KIND[type(mesh)]
    dim = mesh.dim()
    # Gauss order 2p integrates the consistent mass exactly on affine cells
    basis = Basis(mesh, _ELEMENTS[kind, order](), intorder=2 * order)

    def grad_pair(i: int, j: int) -> sp.csr_array:
        @BilinearForm
        def form(u, v, w):  # rows: test v (a), columns: trial u (b)
            return v.grad[i] * u.grad[j]
        return sp.csr_array(asm(form, basis))

    @BilinearForm
    def mass(u, v, w):
        return rho * u * v

    G = {(i, j): grad_pair(i, j) for i in range(dim) for j in range(i, dim)}
    for i in range(dim):
        for j in range(i):
            G[i, j] = sp.csr_array(G[j, i].T)
    L = sum(G[k, k] for k in range(dim))
    eye = sp.eye_array(dim, format="csr")
    K = sp.kron(mu * L, eye, format="csr")
    for i in range(dim):
        for j in range(dim):
            E = sp.csr_array(([1.0], ([i], [j])), shape=(dim, dim))
            K = K + sp.kron(mu * G[j, i] + lam * G[i, j], E, format="csr")
    M = sp.kron(sp.csr_array(asm(mass, basis)), eye, format="csr")
    return basis, sp.csr_array(K * scale), sp.csr_array(M * scale)
