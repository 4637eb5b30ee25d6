r"""Interface bases: a few displacement fields of an interface instead of all its node DOFs.

Craig-Bampton with interface reduction replaces the ``3 N`` physical displacements of an
interface of ``N`` nodes by ``r`` interface coordinates :math:`\xi`,

.. math::  u_\Gamma = R\, \xi, \qquad R^T R = I, \qquad R \in \mathbb{R}^{3N \times r},

so each part needs ``r`` constraint modes per interface instead of ``3 N``.

The basis here is a *Ritz basis that depends on the interface's node coordinates only*: the
polynomials of total degree :math:`\le p` in the (normalized) node coordinates, for each
displacement component,

.. math::

    R = \operatorname{orth}\big[\, P_a(s)\, P_b(t)\, P_c(w) \,\big]_{a + b + c \le p}
        \otimes I_3 ,

:math:`P_k` the Legendre polynomials, :math:`(s, t, w) = (x - x_0) / h` with :math:`x_0` the
centre of the interface's bounding box and :math:`h` half its largest side (so the values lie
in :math:`[-1, 1]` and nothing depends on the units), and ``orth`` the left singular vectors of
singular values above :data:`RANK_TOL` times the largest.  On a plane interface the normal
coordinate is constant, the polynomials in it are dependent and the rank step keeps
:math:`(p+1)(p+2)/2` fields per component; at :math:`p \ge 1` they include the six rigid-body
motions.  Because ``R`` is the same function of the coordinates on both sides of an interface
whose nodes match, the two parts share one set of coordinates :math:`\xi` and the coupling is
*conforming*: the global reduced space is a subspace of the monolithic finite-element space
(the parts coupled by shared interface coordinates in ``tests/reference_reduced_coupling.py``).
As ``p`` grows the basis spans every interface displacement (``p >= n - 1`` on an ``n x n``
grid of nodes), and the reduction becomes classical Craig-Bampton; ``degree=None`` gives that
limit directly, ``R = I``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.polynomial import legendre

from substruct.models.selection import node_tolerance, nodes_in_box, parse_box
from substruct.substructure import Substructure

__all__ = ["RANK_TOL", "InterfaceBasis", "interface_basis", "interface_basis_of_dofs", "lower_degree",
           "polynomial_fields"]

#: Relative singular-value threshold of the rank step (on values of polynomials of
#: coordinates normalized to [-1, 1], so it does not depend on the scale of the input).
RANK_TOL = 1e-9


@dataclass(frozen=True, eq=False)
class InterfaceBasis:
    """One interface of one part: its nodes, their coordinates in the part and the basis.

    Attributes:
        name: the interface's name, the same in the parts it joins.
        xyz: ``(N, 3)`` node positions.
        dofs: ``(dim N,)`` coordinates of the part, node-major (``dofs[dim k + c]`` is the
            displacement component ``c`` of node ``k``).
        basis: ``(dim N, r)`` orthonormal columns, rows in the order of ``dofs``.
        degree: the polynomial degree ``p``, or ``None`` for the full basis ``R = I``.
    """

    name: str
    xyz: np.ndarray
    dofs: np.ndarray
    basis: np.ndarray
    degree: int | None

    @property
    def r(self) -> int:
        """The number of interface coordinates."""
        return int(self.basis.shape[1])


def polynomial_fields(xyz: np.ndarray, degree: int) -> np.ndarray:
    r"""Orthonormal values at the nodes ``xyz`` of the polynomials of total degree
    :math:`\le p` (module docstring): an ``N x m`` matrix, ``m <= (p+1)(p+2)(p+3)/6`` after
    the rank step.

    Raises:
        ValueError: a negative degree, or no nodes.
    """
    pts = np.asarray(xyz, dtype=float)
    if pts.ndim != 2 or len(pts) == 0:
        raise ValueError("an interface basis needs at least one node")
    p = int(degree)
    if p != degree or p < 0:
        raise ValueError(f"interface basis degree must be an integer >= 0, got {degree!r}")
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    half = max(float((hi - lo).max()) / 2, 1e-300)
    s = (pts - (lo + hi) / 2) / half
    dim = pts.shape[1]
    # P_k(s_j) for k = 0..p, each coordinate j: (dim, p+1, N)
    vals = np.stack([np.stack([legendre.legval(s[:, j], np.eye(p + 1)[k])
                               for k in range(p + 1)]) for j in range(dim)])
    cols = []
    for powers in np.ndindex(*(p + 1,) * dim):
        if sum(powers) <= p:
            cols.append(np.prod([vals[j, powers[j]] for j in range(dim)], axis=0))
    V = np.column_stack(cols)
    U, sv, _ = np.linalg.svd(V, full_matrices=False)
    keep = sv > RANK_TOL * sv[0]
    return np.ascontiguousarray(U[:, keep])


def interface_basis(sub: Substructure, name: str, box: Any, degree: int | None,
                    tol: float | None = None) -> InterfaceBasis:
    r"""The interface ``name`` of the meshed ``sub``: its nodes inside ``box``
    (``[[xmin, ymin, zmin], [xmax, ymax, zmax]]``, widened by the node tolerance of
    :mod:`substruct.models.selection`) and the basis :math:`R = F \otimes I_{dim}`,
    ``F = polynomial_fields(xyz, degree)`` (``degree=None``: ``R = I``).

    Nodes are sorted by their rounded coordinates so that both sides of a matching interface
    list them alike.

    Raises:
        ValueError: ``sub`` has no mesh, the box selects no node, or an interface node has a
            supported (condensed) component: an interface must be free on both sides.
    """
    if sub.geometry is None:
        raise ValueError(f"{sub.name}: a substructure without a mesh has no interface nodes")
    dim = int(sub.meta.get("dim", 3))
    points = np.asarray(sub.geometry.points, dtype=float)
    tol_ = node_tolerance(points, tol)
    lo, hi = parse_box(box, dim, sub.name)
    nodes = nodes_in_box(points[:, :dim], lo, hi, tol_)
    if nodes.size == 0:
        raise ValueError(f"{sub.name}: interface {name!r}: the box {box!r} holds no node")
    grid = np.round((points[nodes] - points.min(axis=0)) / tol_ / 10).astype(np.int64)
    nodes = nodes[np.lexsort(grid.T[::-1])]
    interp = sub.geometry.interp.tocsr()
    rows = (3 * nodes[:, None] + np.arange(dim)[None, :]).ravel()
    dofs = np.empty(rows.size, dtype=np.int64)
    for i, row in enumerate(rows):
        a, b = interp.indptr[row], interp.indptr[row + 1]
        if b - a != 1 or interp.data[a] != 1.0:
            raise ValueError(f"{sub.name}: interface {name!r}: node {int(nodes[i // dim])} has "
                             "a supported component; an interface must be free")
        dofs[i] = interp.indices[a]
    return _basis(name, points[nodes], dofs, dim, degree)


def _basis(name: str, xyz: np.ndarray, dofs: np.ndarray, dim: int, degree: int | None
           ) -> InterfaceBasis:
    if degree is None:
        R = np.eye(dofs.size)
    else:
        R = np.kron(polynomial_fields(xyz[:, :dim], degree), np.eye(dim))
    return InterfaceBasis(name=name, xyz=xyz, dofs=dofs, basis=R, degree=degree)


def interface_basis_of_dofs(sub: Substructure, name: str, dofs: np.ndarray,
                            degree: int | None) -> InterfaceBasis:
    """The interface made of the nodal coordinates ``dofs`` of the meshed ``sub`` (each one a
    node's displacement component; every component of each node must be in ``dofs``), nodes
    sorted as :func:`interface_basis` sorts them, basis of ``degree``.

    Raises:
        ValueError: ``sub`` has no mesh, a coordinate that is not a nodal displacement, or a
            node with some of its components only.
    """
    if sub.geometry is None:
        raise ValueError(f"{sub.name}: a substructure without a mesh has no interface nodes")
    dim = int(sub.meta.get("dim", 3))
    interp = sub.geometry.interp.tocoo()
    unit = (interp.data == 1.0) & (interp.row % 3 < dim)
    where = dict(zip(interp.col[unit].tolist(), interp.row[unit].tolist()))
    wanted = np.unique(np.asarray(dofs, dtype=np.int64))
    try:
        rows = np.array([where[int(j)] for j in wanted], dtype=np.int64)
    except KeyError:
        raise ValueError(f"{sub.name}: interface {name!r}: a coordinate is not a nodal "
                         "displacement") from None
    nodes, count = np.unique(rows // 3, return_counts=True)
    if np.any(count != dim):
        raise ValueError(f"{sub.name}: interface {name!r}: an interface basis needs every "
                         "displacement component of each interface node")
    points = np.asarray(sub.geometry.points, dtype=float)
    tol_ = node_tolerance(points)
    grid = np.round((points[nodes] - points.min(axis=0)) / tol_ / 10).astype(np.int64)
    nodes = nodes[np.lexsort(grid.T[::-1])]
    col = {r: c for c, r in where.items()}
    ordered = np.array([col[3 * k + c] for k in nodes for c in range(dim)], dtype=np.int64)
    return _basis(name, points[nodes], ordered, dim, degree)


def lower_degree(face: InterfaceBasis, degree: int) -> InterfaceBasis:
    """The same interface with the polynomial basis of a lower ``degree`` (its span lies in
    the span of ``face.basis`` when ``degree <= face.degree``, and in any span for the full
    basis ``face.degree = None``).

    Raises:
        ValueError: ``degree`` above ``face.degree``.
    """
    if face.degree is not None and degree > face.degree:
        raise ValueError(f"interface {face.name!r}: degree {degree} above the basis's "
                         f"{face.degree}")
    return _basis(face.name, face.xyz, face.dofs, face.dofs.size // len(face.xyz), degree)
