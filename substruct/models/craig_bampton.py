r"""Craig-Bampton reduction: fixed-interface normal modes plus static constraint modes.

Partition the coordinates of a substructure into interior ``i`` and boundary ``b`` (those that
other substructures or constraints attach to).  With the boundary held fixed, the interior has
the normal modes

.. math::  K_{ii} \Phi_i = M_{ii} \Phi_i \Omega^2, \qquad \Phi_i^T M_{ii} \Phi_i = I,

and a unit displacement of each boundary coordinate, interior at static equilibrium, gives the
constraint modes :math:`\Psi = -K_{ii}^{-1} K_{ib}`.  The reduction keeps the ``n_modes``
lowest fixed-interface modes and all constraint modes,

.. math::

    \begin{bmatrix} q_i \\ q_b \end{bmatrix} =
    \underbrace{\begin{bmatrix} \Phi_i & \Psi \\ 0 & I \end{bmatrix}}_{T}
    \begin{bmatrix} \eta \\ q_b \end{bmatrix}, \qquad
    \tilde M = T^T M T, \quad \tilde K = T^T K T = \begin{bmatrix} \Omega^2 & 0 \\ 0 &
    K_{bb} + K_{bi} \Psi \end{bmatrix}, \quad \tilde C = T^T C T .

The boundary coordinates stay physical, so interface ties and point attachments at boundary
nodes keep their meaning (``row_new(x) = row(x) @ T``); the reduced model is exact for static
loads on the boundary and converges to the full one as ``n_modes`` grows.  One sparse
factorization of :math:`K_{ii}` serves the constraint modes and the shift-invert Lanczos
solve of the fixed-interface modes.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from substruct.linalg.factorize import Factorize, Solve, factorizer
from substruct.linalg.lanczos import rayleigh_ritz, shift_invert_lanczos
from substruct.linalg.massless import massless_split
from substruct.linalg.scaling import rigid_modes
from substruct.substructure import Substructure, as_csr

__all__ = ["craig_bampton", "fixed_interface_modes"]


def _boundary(sub: Substructure, boundary_dofs: Any) -> np.ndarray:
    n = sub.n_dof
    b = np.asarray(boundary_dofs)
    if b.dtype == bool:
        if b.shape != (n,):
            raise ValueError(f"{sub.name}: boundary mask of shape {b.shape}, expected ({n},)")
        b = np.flatnonzero(b)
    b = np.unique(b.astype(np.int64).ravel())
    if b.size == 0:
        raise ValueError(f"{sub.name}: Craig-Bampton needs at least one boundary coordinate")
    if b[0] < 0 or b[-1] >= n:
        raise ValueError(f"{sub.name}: boundary coordinates must lie in 0..{n - 1}")
    if b.size >= n:
        raise ValueError(f"{sub.name}: every coordinate is on the boundary; nothing to reduce")
    return b


#: A fixed-interface eigenvalue :math:`\mu = 1/\omega^2` of the inverse pencil at most this
#: fraction of the largest is a massless direction's (:math:`\omega = \infty`, round-off).
MASSLESS_MU = 1e-12


def fixed_interface_modes(name: str, K: sp.csr_array, M: sp.csr_array, interior: np.ndarray,
                          n_modes: int, *, factorization: str | Factorize = "auto",
                          dense_limit: int = 1500, ncv: int | None = None
                          ) -> tuple[Solve, np.ndarray, np.ndarray]:
    r"""One factorization of :math:`K_{ii}` and the ``n_modes`` lowest fixed-interface modes.

    .. math::  K_{ii} \Phi_i = M_{ii} \Phi_i \Omega^2, \qquad \Phi_i^T M_{ii} \Phi_i = I,

    each column's largest entry positive.  Interiors up to ``dense_limit`` coordinates are
    solved densely (Cholesky, ``eigh`` of the inverse pencil :math:`M_{ii} \phi = \mu K_{ii}
    \phi`, :math:`\omega^2 = 1/\mu`), larger ones by the registry's factorization and the
    shift-invert Lanczos (shift 0) with a Rayleigh-Ritz step; both allow massless interior
    coordinates (lumped-mass beams and shells), which have no finite mode.

    Returns:
        ``(solve, lam, Phi)``: ``b -> K_ii^{-1} b`` (for the constraint modes), the eigenvalues
        :math:`\omega^2` ascending and the ``n_i x n_modes`` mass-normalized modes.

    Raises:
        ValueError: more modes asked than the interior has masses, singular ``K_ii`` or a
            zero-frequency mode (the boundary and the supports do not hold the interior).
    """
    g = int(n_modes)
    ni = interior.size
    Kii = sp.csc_array(K[interior][:, interior])
    Mii = sp.csc_array(M[interior][:, interior])
    solve: Solve
    if ni <= dense_limit:
        Kd, Md = Kii.toarray(), Mii.toarray()
        try:
            cho = sla.cho_factor(Kd)
        except np.linalg.LinAlgError:
            raise ValueError(f"{name}: K_ii is singular: the boundary coordinates and the "
                             "supports do not hold the interior") from None

        def solve(rhs: np.ndarray) -> np.ndarray:
            return np.asarray(sla.cho_solve(cho, rhs))

        if g:
            # the inverse pencil, definite on the right whatever the mass: the g largest mu
            mu, V = sla.eigh(Md, Kd, subset_by_index=[ni - g, ni - 1])
            if mu[0] <= MASSLESS_MU * mu[-1]:
                raise ValueError(f"{name}: {g} fixed-interface modes asked of an interior "
                                 f"with {int(np.sum(mu > MASSLESS_MU * mu[-1]))} of them "
                                 "(its other coordinates have no mass)")
            lam, Phi = 1.0 / mu[::-1], V[:, ::-1]
        else:
            lam, Phi = np.zeros(0), np.zeros((ni, 0))
    else:
        try:
            solve = factorizer(factorization, spd=True)(Kii)
        except Exception as exc:
            raise ValueError(f"{name}: K_ii cannot be factorized ({exc}): the boundary "
                             "coordinates and the supports do not hold the interior") from None
        if g:
            # the operator K_ii^-1 M_ii spans only the directions with mass: so can the basis
            # (a point mass off its node without inertia: a combination of coordinates without
            # mass, made a coordinate, u = Q p, for the Lanczos run)
            split = massless_split(Mii)
            massive = ni - split.count
            if g >= massive:
                raise ValueError(f"{name}: {g} fixed-interface modes asked of an interior "
                                 f"with {massive} directions with mass")
            size = min(ncv or max(2 * g + 1, 20), massive)
            v0 = np.random.default_rng(0).standard_normal(ni)
            if split.rotated:
                Q = split.Q
                Kq = sp.csc_array(Q.T @ (Kii @ Q))
                solve_q = factorizer(factorization, spd=True)((Kq + Kq.T) / 2)
                _, vecs = shift_invert_lanczos(Kq, split.mass(Mii), g, 0.0, solve_q, v0, size)
                vecs = Q @ vecs
            else:
                _, vecs = shift_invert_lanczos(Kii, Mii, g, 0.0, solve, v0, size)
            lam, Phi = rayleigh_ritz(Kii, Mii, vecs)
        else:
            lam, Phi = np.zeros(0), np.zeros((ni, 0))
    # round-off of the interior's stiffness scale, not a fraction of the highest mode kept: a
    # part on soft springs has modes far below its elastic ones
    if g and rigid_modes(lam[:1], Phi[:, :1], Kii, Mii)[0]:
        raise ValueError(f"{name}: a fixed-interface mode has zero frequency: the boundary "
                         "and the supports do not hold the interior")
    if g:
        Phi = Phi / np.sqrt(np.einsum("ij,ij->j", Phi, Mii @ Phi))
        big = np.argmax(np.abs(Phi), axis=0)
        Phi = Phi * np.sign(Phi[big, np.arange(g)])
    return solve, lam, Phi


def craig_bampton(sub: Substructure, boundary_dofs: Sequence[int] | np.ndarray, n_modes: int,
                  *, factorization: str | Factorize = "auto", dense_limit: int = 1500,
                  ncv: int | None = None) -> Substructure:
    r"""Reduce ``sub`` to ``n_modes`` fixed-interface modes plus its boundary coordinates.

    .. math::  q = T \begin{bmatrix} \eta \\ q_b \end{bmatrix}, \quad
               T = \begin{bmatrix} \Phi_i & -K_{ii}^{-1} K_{ib} \\ 0 & I \end{bmatrix}

    Args:
        sub: the substructure (``K_ii`` must be nonsingular: the boundary and the supports
            together hold the interior; ``M_ii`` positive definite).
        boundary_dofs: indices (or a boolean mask) of the boundary coordinates, e.g.
            :func:`substruct.assembly.interfaces.node_dofs` of an interface.
        n_modes: number of fixed-interface normal modes kept (``0 <= n_modes <= n_i``; all of them: the
            reduction is exact).
        factorization: of ``K_ii`` (:func:`substruct.linalg.factorize.factorizer`; SPD; ``"auto"``:
            CHOLMOD if scikit-sparse is installed, else SuperLU).
        dense_limit: interiors up to this size are solved densely.
        ncv: Lanczos basis size for the sparse eigensolve.

    Returns:
        The reduced :class:`Substructure`: coordinates ``eta1 .. eta<g>`` then the boundary
        coordinates with their original labels; kind ``"craig-bampton"``;
        ``meta["omega_fixed_interface"]`` (rad/s), ``meta["n_modes"]``,
        ``meta["n_boundary"]``, ``meta["reduced_from"]``.  Damping is projected,
        :math:`T^T C T`.

    Raises:
        ValueError: bad boundary set or ``n_modes``, singular ``K_ii`` (the interior is not
            held), massless interior coordinates.
    """
    n = sub.n_dof
    b = _boundary(sub, boundary_dofs)
    interior = np.setdiff1d(np.arange(n), b)
    ni = interior.size
    g = int(n_modes)
    if g != n_modes or not 0 <= g <= ni:
        raise ValueError(f"{sub.name}: n_modes = {n_modes!r}, but the interior has {ni} "
                         f"coordinates (need 0 <= n_modes <= {ni})")
    K, M = as_csr(sub.K), as_csr(sub.M)
    Kib = K[interior][:, b].toarray()
    solve, lam, Phi = fixed_interface_modes(sub.name, K, M, interior, g,
                                            factorization=factorization,
                                            dense_limit=dense_limit, ncv=ncv)
    Psi = -np.asarray(solve(Kib)).reshape(ni, b.size)
    T = np.zeros((n, g + b.size))
    T[interior, :g] = Phi
    T[interior, g:] = Psi
    T[b, g + np.arange(b.size)] = 1.0
    labels = tuple(f"eta{j}" for j in range(1, g + 1)) + tuple(sub.dof_labels[i] for i in b)
    return sub.transformed(sp.csr_array(T), labels, kind="craig-bampton",
                           omega_fixed_interface=np.sqrt(np.maximum(lam, 0.0)), n_modes=g,
                           n_boundary=int(b.size), reduced_from=n, reduced_kind=sub.kind)
