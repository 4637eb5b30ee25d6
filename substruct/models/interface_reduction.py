r"""Craig-Bampton with interface reduction: one part reduced alone, to small dense matrices.

A part with interior coordinates ``i`` and interfaces :math:`\Gamma_1, \dots, \Gamma_J` (the
coordinates ``b``, :class:`~substruct.models.interface_basis.InterfaceBasis` each) keeps

* the ``g`` lowest *fixed-interface modes*, :math:`K_{ii}\Phi = M_{ii}\Phi\Omega^2`,
  :math:`\Phi^T M_{ii} \Phi = I` (all interfaces held), and
* one *constraint mode* per interface coordinate instead of one per boundary DOF: with
  :math:`u_b = R_b \xi`, :math:`R_b = \operatorname{diag}(R_1, \dots, R_J)` (``r = sum r_j``
  columns), the interior at static equilibrium,
  :math:`\Psi = -K_{ii}^{-1} K_{ib} R_b` (``r`` solves, not ``|b|``).

.. math::

    \begin{bmatrix} u_i \\ u_b \end{bmatrix} =
    \underbrace{\begin{bmatrix} \Phi & \Psi \\ 0 & R_b \end{bmatrix}}_{T}
    \begin{bmatrix} \eta \\ \xi \end{bmatrix}, \qquad
    \tilde K = T^T K T = \begin{bmatrix} \Omega^2 & 0 \\ 0 & R_b^T (K_{bb} R_b + K_{bi}\Psi)
    \end{bmatrix}, \qquad \tilde M = T^T M T .

One sparse factorization of :math:`K_{ii}` serves both the shift-invert Lanczos of the modes
and the ``r`` constraint solves (:func:`~substruct.models.craig_bampton.fixed_interface_modes`).
With :math:`R_b = I` this is classical Craig-Bampton
(:func:`~substruct.models.craig_bampton.craig_bampton`, same matrices in another column
order).  The reduced part is ``g + r`` coordinates: dense :math:`\tilde K, \tilde M`, the
interface bases for the coupling and, when asked, ``T`` to recover displacements
:math:`u = T [\eta; \xi]`.  Nothing else of the part is kept, so parts are reduced one at a
time (or as independent tasks) and the peak memory is that of the largest part.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
import scipy.sparse as sp

from substruct.linalg.factorize import Factorize
from substruct.models.craig_bampton import fixed_interface_modes
from substruct.models.interface_basis import InterfaceBasis, lower_degree
from substruct.substructure import Substructure, as_csr

__all__ = ["ReducedPart", "reduce_part", "truncate_part"]


@dataclass(frozen=True, eq=False)
class ReducedPart:
    r"""A part reduced by Craig-Bampton with interface reduction (module docstring).

    Attributes:
        name: the part's name.
        K, M, C: dense ``(g + r) x (g + r)`` reduced matrices, coordinates
            :math:`[\eta_1 .. \eta_g, \xi^{(1)}, \dots, \xi^{(J)}]`.
        n_modes: ``g``.
        interfaces: the interface bases, in the order of their coordinates.
        omega_fixed_interface: the ``g`` fixed-interface circular frequencies (rad/s).
        n_dof: coordinates of the unreduced part.
        T: ``n_dof x (g + r)`` recovery matrix, or ``None`` if not kept.
    """

    name: str
    K: np.ndarray
    M: np.ndarray
    C: np.ndarray
    n_modes: int
    interfaces: tuple[InterfaceBasis, ...]
    omega_fixed_interface: np.ndarray
    n_dof: int
    T: np.ndarray | None

    @property
    def size(self) -> int:
        """Number of reduced coordinates ``g + r``."""
        return int(self.K.shape[0])

    def interface_slice(self, name: str) -> slice:
        """Where the coordinates :math:`\\xi` of interface ``name`` are in this part."""
        start = self.n_modes
        for face in self.interfaces:
            if face.name == name:
                return slice(start, start + face.r)
            start += face.r
        raise KeyError(f"{self.name}: no interface {name!r}")

    def recover(self, q: np.ndarray) -> np.ndarray:
        """Displacements ``u = T q`` of the unreduced part from reduced coordinates ``q``
        (``(g + r,)`` or ``(g + r, k)``).

        Raises:
            ValueError: ``T`` was not kept.
        """
        if self.T is None:
            raise ValueError(f"{self.name}: reduced with keep_basis=False, nothing to recover")
        return np.asarray(self.T @ q)


def reduce_part(sub: Substructure, interfaces: Sequence[InterfaceBasis], n_modes: int, *,
                factorization: str | Factorize = "auto", dense_limit: int = 1500,
                ncv: int | None = None, keep_basis: bool = True) -> ReducedPart:
    r"""Reduce one part by Craig-Bampton with interface reduction (module docstring).

    .. math::  T = \begin{bmatrix} \Phi & -K_{ii}^{-1} K_{ib} R_b \\ 0 & R_b \end{bmatrix},
               \qquad \tilde K = T^T K T, \quad \tilde M = T^T M T, \quad \tilde C = T^T C T

    Args:
        sub: the part (``K_ii`` nonsingular: interfaces and supports hold the interior).
        interfaces: its interfaces (:func:`~substruct.models.interface_basis.interface_basis`),
            disjoint coordinate sets.
        n_modes: fixed-interface modes kept, ``0 <= g < n_i``.
        factorization: of ``K_ii`` (:func:`substruct.linalg.factorize.factorizer`).
        dense_limit: interiors up to this size are solved densely.
        ncv: Lanczos basis size.
        keep_basis: keep ``T`` for :meth:`ReducedPart.recover` (``n_dof x (g + r)`` floats).

    Raises:
        ValueError: no interface, overlapping interfaces, bad ``n_modes``, or a ``K_ii`` that
            the interfaces and supports do not hold.
    """
    if not interfaces:
        raise ValueError(f"{sub.name}: Craig-Bampton needs at least one interface")
    n = sub.n_dof
    b = np.concatenate([np.asarray(f.dofs, dtype=np.int64) for f in interfaces])
    if np.unique(b).size != b.size or b.min() < 0 or b.max() >= n:
        raise ValueError(f"{sub.name}: interfaces overlap or lie outside 0..{n - 1}")
    mask = np.ones(n, dtype=bool)
    mask[b] = False
    interior = np.flatnonzero(mask)
    ni, g = interior.size, int(n_modes)
    if g != n_modes or not 0 <= g <= ni:
        raise ValueError(f"{sub.name}: n_modes = {n_modes!r}, but the interior has {ni} "
                         f"coordinates (need 0 <= n_modes <= {ni})")
    r_each = [f.r for f in interfaces]
    Rb = np.zeros((b.size, sum(r_each)))
    row = col = 0
    for f in interfaces:
        Rb[row:row + f.dofs.size, col:col + f.r] = f.basis
        row, col = row + f.dofs.size, col + f.r
    K, M = as_csr(sub.K), as_csr(sub.M)
    solve, lam, Phi = fixed_interface_modes(sub.name, K, M, interior, g,
                                            factorization=factorization,
                                            dense_limit=dense_limit, ncv=ncv)
    KibR = np.asarray(K[interior][:, b] @ Rb)
    Psi = -np.asarray(solve(KibR)).reshape(ni, Rb.shape[1])
    del KibR
    T = np.zeros((n, g + Rb.shape[1]))
    T[interior, :g] = Phi
    T[interior, g:] = Psi
    T[b, g:] = Rb
    del Phi, Psi

    def project(A: sp.csr_array) -> np.ndarray:
        out = T.T @ np.asarray(A @ T)
        return np.asarray((out + out.T) / 2)

    Kr, Mr = project(K), project(M)
    C = as_csr(sub.C, n)
    Cr = project(C) if C.nnz else np.zeros_like(Kr)
    return ReducedPart(name=sub.name, K=Kr, M=Mr, C=Cr, n_modes=g,
                       interfaces=tuple(interfaces),
                       omega_fixed_interface=np.sqrt(np.maximum(lam, 0.0)), n_dof=n,
                       T=T if keep_basis else None)


def truncate_part(part: ReducedPart, n_modes: int, degree: int | None) -> ReducedPart:
    r"""The part as :func:`reduce_part` would give it with fewer modes and a lower interface
    degree, from the matrices already reduced (no solve).

    The fixed-interface modes are nested (the lowest ``g'`` of ``g``) and the constraint
    modes are linear in the interface basis, :math:`\Psi(R') = \Psi(R)\, R^T R'` when
    :math:`\operatorname{span} R' \subseteq \operatorname{span} R`, so with
    :math:`S = \operatorname{diag}(I_{g'} \text{ of } I_g,\ R_1^T R'_1, \dots)`

    .. math::  T' = T S, \qquad \tilde K' = S^T \tilde K S, \qquad \tilde M' = S^T \tilde M S.

    Args:
        part: a reduced part.
        n_modes: ``g' <= g``.
        degree: the new interface degree (``None``: keep the bases).

    Raises:
        ValueError: ``n_modes`` above ``g`` or ``degree`` above the bases' degree.
    """
    g = int(n_modes)
    if not 0 <= g <= part.n_modes:
        raise ValueError(f"{part.name}: n_modes {n_modes!r} outside 0..{part.n_modes}")
    faces = tuple(part.interfaces if degree is None else
                  (lower_degree(f, degree) for f in part.interfaces))
    S = np.zeros((part.size, g + sum(f.r for f in faces)))
    S[np.arange(g), np.arange(g)] = 1.0
    col = g
    for old, new in zip(part.interfaces, faces):
        S[part.interface_slice(old.name), col:col + new.r] = old.basis.T @ new.basis
        col += new.r

    def project(A: np.ndarray) -> np.ndarray:
        out = S.T @ A @ S
        return np.asarray((out + out.T) / 2)

    return ReducedPart(name=part.name, K=project(part.K), M=project(part.M),
                       C=project(part.C), n_modes=g, interfaces=faces,
                       omega_fixed_interface=part.omega_fixed_interface[:g],
                       n_dof=part.n_dof, T=None if part.T is None else part.T @ S)
