r"""A reference for the tests and ``benchmarks/cb_assembly.py``: parts reduced with interface
bases coupled by shared interface coordinates, dense modes.

The program couples such parts through constraint rows instead (a case file's
``reduce: {method: craig-bampton, interface_degree: p}``,
:mod:`substruct.builder.interface_reduced`, then the coupled modes of the assembly); this
primal assembly is the independent formulation those rows are checked against.

Each part ``k`` (:class:`~substruct.models.interface_reduction.ReducedPart`) has coordinates
:math:`q_k = [\eta_k; \xi_k^{(1)}; \dots]`.  An interface joins the parts that list it by
name; its displacement is :math:`u_\Gamma = R_a \xi_a` on one side and :math:`R_b \xi_b` on
the other.  When the two bases span the same fields at the same nodes (the polynomial bases of
:mod:`substruct.models.interface_basis` on matching nodes), continuity
:math:`R_a \xi_a = P R_b \xi_b` (``P`` matching the nodes) holds exactly with

.. math::  \xi_b = G\, \xi_a, \qquad G = (P R_b)^T R_a

(orthonormal columns), so the first part that lists an interface owns its coordinates and the
others map to them.  The global coordinates ``x`` are every part's :math:`\eta_k` and one
:math:`\xi` per interface, :math:`q_k = L_k x` and

.. math::  K = \sum_k L_k^T \tilde K_k L_k, \qquad M = \sum_k L_k^T \tilde M_k L_k .

This is primal assembly with no constraint rows left.  Because each part's displacement is
:math:`T_k q_k` and the interface values agree, the coupled space is a subspace of the
monolithic finite-element space: the coupled eigenvalues are Rayleigh-Ritz approximations of
the monolithic ones, each one above its monolithic counterpart, and they decrease as the
fixed-interface modes and the interface degree grow.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
import scipy.linalg as sla
from scipy.spatial import cKDTree

from substruct.models.interface_basis import InterfaceBasis
from substruct.models.interface_reduction import ReducedPart
from substruct.models.selection import node_tolerance

__all__ = ["CONFORMITY_TOL", "ReducedAssembly", "couple_reduced", "reduced_modes"]

#: Largest relative residual :math:`\|P R_b G - R_a\|_F / \|R_a\|_F` of a conforming interface.
CONFORMITY_TOL = 1e-8


@dataclass(frozen=True, eq=False)
class ReducedAssembly:
    """Coupled reduced parts.

    Attributes:
        K, M, C: dense ``N x N`` global matrices.
        names: the parts' names.
        maps: per part, the ``m_k x N`` matrix :math:`L_k` with :math:`q_k = L_k x`.
        interfaces: per interface name, the slice of its coordinates in ``x``.
    """

    K: np.ndarray
    M: np.ndarray
    C: np.ndarray
    names: tuple[str, ...]
    maps: tuple[np.ndarray, ...]
    interfaces: dict[str, slice]

    def part_coordinates(self, k: int, x: np.ndarray) -> np.ndarray:
        """The reduced coordinates :math:`q_k = L_k x` of part ``k``."""
        return np.asarray(self.maps[k] @ x)


def _node_order(a: InterfaceBasis, b: InterfaceBasis, part_a: str, part_b: str) -> np.ndarray:
    """Indices ``perm`` with ``b.xyz[perm] == a.xyz`` within the node tolerance."""
    tol = node_tolerance(np.vstack([a.xyz, b.xyz]))
    dist, perm = cKDTree(b.xyz).query(a.xyz)
    if len(a.xyz) != len(b.xyz) or np.any(dist > tol) or np.unique(perm).size != perm.size:
        raise ValueError(f"interface {a.name!r}: the nodes of {part_a} and {part_b} do not "
                         "match; interface bases couple matching meshes only")
    return np.asarray(perm)


def couple_reduced(parts: Sequence[ReducedPart]) -> ReducedAssembly:
    r"""Assemble reduced parts by shared interface coordinates (module docstring).

    Raises:
        ValueError: interface nodes that do not match, or bases that do not span the same
            fields (:data:`CONFORMITY_TOL`).
    """
    owner: dict[str, tuple[int, InterfaceBasis]] = {}
    slices: dict[str, slice] = {}
    n_global = sum(p.n_modes for p in parts)
    for k, part in enumerate(parts):
        for face in part.interfaces:
            if face.name not in owner:
                owner[face.name] = (k, face)
                slices[face.name] = slice(n_global, n_global + face.r)
                n_global += face.r
    maps = []
    start = 0
    for k, part in enumerate(parts):
        L = np.zeros((part.size, n_global))
        L[:part.n_modes, start:start + part.n_modes] = np.eye(part.n_modes)
        start += part.n_modes
        for face in part.interfaces:
            own_k, own = owner[face.name]
            rows, cols = part.interface_slice(face.name), slices[face.name]
            if own_k == k:
                L[rows, cols] = np.eye(face.r)
                continue
            perm = _node_order(own, face, parts[own_k].name, part.name)
            dim = face.basis.shape[0] // len(face.xyz)
            rows_b = (dim * perm[:, None] + np.arange(dim)[None, :]).ravel()
            Rb = face.basis[rows_b]
            G = Rb.T @ own.basis
            scale = float(np.linalg.norm(own.basis)) or 1.0
            residual = float(np.linalg.norm(Rb @ G - own.basis)) / scale
            if face.r != own.r or residual > CONFORMITY_TOL:
                raise ValueError(f"interface {face.name!r}: the bases of {parts[own_k].name} "
                                 f"({own.r} fields) and {part.name} ({face.r} fields) do not "
                                 f"span the same displacements (residual {residual:.1e})")
            L[rows, cols] = G
        maps.append(L)
    K = sum(L.T @ p.K @ L for L, p in zip(maps, parts))
    M = sum(L.T @ p.M @ L for L, p in zip(maps, parts))
    C = sum(L.T @ p.C @ L for L, p in zip(maps, parts))
    return ReducedAssembly(K=np.asarray(K), M=np.asarray(M), C=np.asarray(C),
                           names=tuple(p.name for p in parts), maps=tuple(maps),
                           interfaces=slices)


def reduced_modes(asm: ReducedAssembly, n_modes: int) -> tuple[np.ndarray, np.ndarray]:
    r"""The ``n_modes`` lowest undamped modes of the coupled reduced system,
    :math:`K x = \omega^2 M x`, :math:`x^T M x = 1` (dense ``eigh``).

    Returns:
        ``(omega, X)``: circular frequencies (rad/s) ascending and the ``N x n_modes`` global
        coordinates; part ``k``'s displacements are ``parts[k].recover(asm.part_coordinates(k,
        X))``.
    """
    n = asm.K.shape[0]
    k = min(int(n_modes), n)
    lam, X = sla.eigh((asm.K + asm.K.T) / 2, (asm.M + asm.M.T) / 2,
                      subset_by_index=[0, k - 1])
    return np.sqrt(np.maximum(lam, 0.0)), X
