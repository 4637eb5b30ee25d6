r"""Linear elastic solids from meshes (2D plane stress/strain, 3D), discretized with scikit-fem.

The weak form of elastodynamics over the body :math:`\Omega` (thickness :math:`t` in 2D),

.. math::

    \int_\Omega \rho\, \ddot u \cdot v \, t\,d\Omega
    + \int_\Omega \sigma(u) : \varepsilon(v) \, t\,d\Omega = 0, \qquad
    \sigma(u) = 2 \mu\, \varepsilon(u) + \lambda \operatorname{tr} \varepsilon(u)\, I,

gives the consistent mass :math:`M_{ij} = \int \rho\, \phi_i \cdot \phi_j` and the stiffness
:math:`K_{ij} = \int \sigma(\phi_i) : \varepsilon(\phi_j)` over a vector Lagrange basis
(P1/Q1 for ``order=1``, P2/Q2 for ``order=2``) on triangles, quadrilaterals, tetrahedra or
hexahedra (:mod:`substruct.models.elasticity`; meshes read by :mod:`substruct.models.mesh_io`).

Supports are Dirichlet conditions :math:`u_c = 0` on selected DOFs, which are *condensed*: the
substructure's coordinates are the free DOFs only.  Support selectors and point references are
described in :mod:`substruct.models.solid_nodes`.  At a node (within
:data:`~substruct.models.selection.NODE_TOL` of the model size) the row of a point is a unit
row; elsewhere it is the interpolation row :math:`u_c(x) = \sum_j \phi_j(x) q_j`
(``Basis.probes``).  A point outside the mesh raises
:class:`~substruct.substructure.PointError`.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any, ClassVar, Mapping, Sequence

import meshio
import numpy as np
import scipy.sparse as sp
from skfem import Mesh, MeshHex, MeshQuad, MeshTet, MeshTri
from skfem.io.meshio import to_meshio

from substruct.models.elasticity import MESH_KIND, elasticity_matrices, lame, rayleigh
from substruct.models.mesh_io import mesh_label, read_mesh
from substruct.models.selection import COMPONENTS, node_tolerance
from substruct.models.solid_nodes import Nodes, basis_nodes, fixed_dofs, locate_point, set_nodes
from substruct.substructure import Geometry, PointError, Substructure, as_csr

__all__ = ["BoxGrid", "RectangleGrid", "solid_from_mesh", "solid_box", "solid_rectangle"]


def _build(name: str, mesh: Mesh, sets: Mapping[str, np.ndarray], E: float, nu: float,
           rho: float, order: int, plane: str | None, thickness: float, fixed: Sequence[Any],
           damping: Any, source: str) -> Substructure:
    """The solid substructure of a scikit-fem mesh (see :func:`solid_from_mesh`)."""
    if type(mesh) not in MESH_KIND:
        raise ValueError(f"{name}: unsupported mesh type {type(mesh).__name__}")
    if order not in (1, 2):
        raise ValueError(f"{name}: order must be 1 or 2, got {order!r}")
    dim = mesh.dim()
    lam, mu = lame(name, E, nu, rho, dim, plane)
    t = float(thickness) if dim == 2 else 1.0
    if not (np.isfinite(t) and t > 0):
        raise ValueError(f"{name}: thickness must be positive, got {thickness!r}")
    alpha, beta = rayleigh(name, damping)
    basis, K, M = elasticity_matrices(mesh, order, lam, mu, float(rho), t)
    nodes = basis_nodes(basis)
    tol = node_tolerance(mesh.p.T)
    supported = fixed_dofs(name, list(fixed or []), nodes, sets, tol)
    n_full = dim * basis.N
    free = np.setdiff1d(np.arange(n_full), supported)
    col = np.full(n_full, -1, dtype=np.int64)
    col[free] = np.arange(free.size)
    K = as_csr(K[free][:, free])
    M = as_csr(M[free][:, free])
    C = as_csr(alpha * M + beta * K) if alpha or beta else as_csr(None, free.size)
    n = free.size
    labels = np.empty(n_full, dtype=object)
    for c in range(dim):
        labels[nodes.dofs[:, c]] = [f"n{k}.u{COMPONENTS[c]}" for k in range(len(nodes.xyz))]
    from scipy.spatial import cKDTree  # here, not at import: scipy.spatial is 0.1 s

    tree = cKDTree(nodes.xyz)

    def unit(dof: int) -> sp.csr_array:
        j = col[dof]
        if j < 0:  # a supported DOF: it does not move
            return sp.csr_array((1, n))
        return sp.csr_array(([1.0], ([0], [j])), shape=(1, n))

    def locate(where: Any) -> sp.csr_array:
        x, c, node = locate_point(name, where, nodes)
        if node is None:
            dist, k = tree.query(x)
            node = int(k) if dist <= tol else None
        if node is not None:
            return unit(int(nodes.dofs[node, c]))
        try:
            probe = sp.coo_array(basis.probes(x.reshape(dim, 1)))
        except ValueError:
            raise PointError(f"{name}: point {x.tolist()} is outside the mesh") from None
        cols = col[dim * probe.col + c]
        keep = (cols >= 0) & (abs(probe.data) > 1e-14)
        return sp.csr_array((probe.data[keep], (np.zeros(int(keep.sum()), dtype=np.int64),
                                                cols[keep])), shape=(1, n))

    def position(where: Any) -> np.ndarray:
        x, _, _ = locate_point(name, where, nodes)
        return np.pad(np.asarray(x, dtype=float), (0, 3 - dim))

    geometry = _geometry(mesh, nodes, col, n)
    meta = {"E": float(E), "nu": float(nu), "rho": float(rho), "order": int(order),
            "cell": MESH_KIND[type(mesh)], "dim": dim, "plane": plane, "thickness": t,
            "n_nodes": int(len(nodes.xyz)), "n_elements": int(mesh.t.shape[1]),
            "n_fixed": int(supported.size), "mesh": source,
            "node_sets": {k: set_nodes(v, nodes) for k, v in sets.items()},
            "damping": {"rayleigh": [alpha, beta]} if alpha or beta else None}
    return Substructure(name=name, M=M, K=K, C=C, dof_labels=tuple(labels[free]),
                        locate=locate, kind=f"solid/{MESH_KIND[type(mesh)]}{order}",
                        geometry=geometry, meta=meta, position=position)


def _geometry(mesh: Mesh, nodes: Nodes, col: np.ndarray, n: int) -> Geometry:
    """All DOF nodes as drawing points (vertices first), linear cells, unit interpolation."""
    dim = nodes.xyz.shape[1]
    points = np.zeros((len(nodes.xyz), 3))
    points[:, :dim] = nodes.xyz
    cols = col[nodes.dofs]  # (Nn, dim)
    rows = 3 * np.arange(len(nodes.xyz))[:, None] + np.arange(dim)[None, :]
    keep = cols >= 0
    interp = sp.csr_array((np.ones(int(keep.sum())), (rows[keep], cols[keep])),
                          shape=(3 * len(points), n))
    cells = [(c.type, np.asarray(c.data)) for c in to_meshio(mesh).cells]
    return Geometry(points=points, cells=cells, interp=interp)


# ------------------------------------------------------------------------------------ makers


def solid_from_mesh(name: str, mesh: str | os.PathLike | meshio.Mesh | Mesh, E: float,
                    nu: float, rho: float, order: int = 1, plane: str | None = None,
                    thickness: float = 1.0, fixed: Sequence[Any] = (),
                    damping: Any = None) -> Substructure:
    r"""A linear elastic solid substructure from a mesh file, a meshio mesh or a skfem mesh.

    .. math::

        M = \int_\Omega \rho\, \Phi^T \Phi \, t\, d\Omega, \qquad
        K = \int_\Omega \varepsilon(\Phi)^T D\, \varepsilon(\Phi)\, t\, d\Omega, \qquad
        C = \alpha M + \beta K,

    restricted to the free DOFs (supported DOFs condensed out).

    Args:
        name: substructure name.
        mesh: path of a file meshio reads (``.msh``, ``.vtu``, ``.xdmf``, ...), a
            ``meshio.Mesh`` or a ``skfem`` mesh (``MeshHex``, ``MeshTet``, ``MeshQuad``,
            ``MeshTri``).
        E, nu, rho: Young's modulus, Poisson's ratio, density.
        order: 1 (P1/Q1) or 2 (P2/Q2).
        plane: ``"stress"`` or ``"strain"`` for a 2D mesh, ``None`` for 3D.
        thickness: out-of-plane thickness of a 2D solid (scales ``M`` and ``K``).
        fixed: support selectors (:mod:`substruct.models.solid_nodes`).
        damping: ``None``, ``(alpha, beta)`` or ``{"rayleigh": [alpha, beta]}``.

    Returns:
        A :class:`Substructure` of kind ``"solid/<cell><order>"`` with DOF labels
        ``"n<node>.u<x|y|z>"``, a locator and ``position`` for points ``(xyz, component)`` /
        ``{"at": xyz, "component": c}`` / ``{"node": k, "component": c}``, and a geometry whose
        points are all DOF nodes (vertices first) with the mesh's linear cells.
        ``meta["node_sets"]`` maps each named set of the mesh to its node indices (into
        ``geometry.points``), for :mod:`substruct.assembly.interfaces`.

    Raises:
        ValueError: missing or corrupt mesh file (naming the path), bad material data, a
            support that selects nothing, an unknown named set.
    """
    mesh_obj, sets = read_mesh(mesh)
    return _build(name, mesh_obj, sets, E, nu, rho, order, plane, thickness, fixed, damping,
                  mesh_label(mesh))


@dataclass(frozen=True)
class _TensorGrid:
    """A tensor grid of ``len(lengths)`` axes: :math:`[o, o + L]` cut into ``divisions``
    equal elements per axis, cells of kind ``cell``."""

    lengths: Sequence[float]
    divisions: Sequence[int]
    cell: str
    origin: Sequence[float] | None = None
    #: the dimension and the cell kinds of the grid (set by the subclasses)
    DIM: ClassVar[int] = 0
    CELLS: ClassVar[dict[str, type[Mesh]]] = {}
    WHAT: ClassVar[str] = ""

    def __post_init__(self) -> None:
        dim = self.DIM
        L = np.asarray(self.lengths, dtype=float).ravel()
        d = np.asarray(self.divisions).ravel()
        o = np.zeros(dim) if self.origin is None else np.asarray(self.origin,
                                                                 dtype=float).ravel()
        if L.size != dim or d.size != dim or o.size != dim:
            raise ValueError(f"{self.WHAT}: lengths, divisions and origin need {dim} entries "
                             f"each")
        if np.any(~np.isfinite(L)) or np.any(L <= 0) or np.any(d < 1) or \
                np.any(d != np.round(d)):
            raise ValueError(f"{self.WHAT}: lengths must be positive and divisions integers "
                             f">= 1, got {L.tolist()}, {d.tolist()}")
        if self.cell not in self.CELLS:
            raise ValueError(f"{self.WHAT}: cell must be "
                             f"{' or '.join(repr(c) for c in self.CELLS)}, got {self.cell!r}")

    def mesh(self) -> Mesh:
        """The scikit-fem mesh of the grid."""
        L = np.asarray(self.lengths, dtype=float).ravel()
        d = np.asarray(self.divisions).ravel()
        o = np.zeros(self.DIM) if self.origin is None else np.asarray(self.origin,
                                                                      dtype=float).ravel()
        axes = [np.linspace(o[i], o[i] + L[i], int(d[i]) + 1) for i in range(self.DIM)]
        return self.CELLS[self.cell].init_tensor(*axes)

    def label(self) -> str:
        """How ``meta["mesh"]`` names the grid."""
        return f"{self.WHAT} {list(self.lengths)} / {list(self.divisions)} {self.cell}"


@dataclass(frozen=True)
class BoxGrid(_TensorGrid):
    """A 3D box :math:`[o, o + L]` cut into ``divisions = (n_x, n_y, n_z)`` hexahedra per
    side (``cell="tet"``: each hexahedron split into tetrahedra); ``origin`` the corner
    :math:`o` (``None``: 0).

    Raises:
        ValueError: not three lengths, divisions and origin entries, a length not positive, a
            division not an integer >= 1, an unknown cell.
    """

    cell: str = "hex"
    DIM: ClassVar[int] = 3
    CELLS: ClassVar[dict[str, type[Mesh]]] = {"hex": MeshHex, "tet": MeshTet}
    WHAT: ClassVar[str] = "box"


@dataclass(frozen=True)
class RectangleGrid(_TensorGrid):
    """A 2D rectangle :math:`[o, o + L]` cut into ``divisions = (n_x, n_y)`` quadrilaterals
    (``cell="tri"``: triangles); ``origin`` the corner :math:`o` (``None``: 0).

    Raises:
        ValueError: not two lengths, divisions and origin entries, a length not positive, a
            division not an integer >= 1, an unknown cell.
    """

    cell: str = "quad"
    DIM: ClassVar[int] = 2
    CELLS: ClassVar[dict[str, type[Mesh]]] = {"quad": MeshQuad, "tri": MeshTri}
    WHAT: ClassVar[str] = "rectangle"


def solid_box(name: str, grid: BoxGrid, E: float, nu: float, rho: float, order: int = 1,
              fixed: Sequence[Any] = (), damping: Any = None) -> Substructure:
    r"""A 3D box :math:`[o, o + L]` meshed by the tensor grid ``grid`` of hexahedra (or
    tetrahedra, :class:`BoxGrid`).  Other arguments as :func:`solid_from_mesh`.

    Examples:
        A free unit cube of one trilinear element: 8 nodes, 24 coordinates.

        >>> cube = solid_box("cube", BoxGrid((1, 1, 1), (1, 1, 1)), 2.1e11, 0.3, 7850)
        >>> cube.n_dof
        24
    """
    return _build(name, grid.mesh(), {}, E, nu, rho, order, None, 1.0, fixed, damping,
                  grid.label())


def solid_rectangle(name: str, grid: RectangleGrid, E: float, nu: float, rho: float,
                    order: int = 1, plane: str = "stress", thickness: float = 1.0,
                    fixed: Sequence[Any] = (), damping: Any = None) -> Substructure:
    r"""A 2D rectangle :math:`[o, o + L]` meshed by the tensor grid ``grid`` of quadrilaterals
    (or triangles, :class:`RectangleGrid`), plane stress/strain.  Other arguments as
    :func:`solid_from_mesh`.
    """
    return _build(name, grid.mesh(), {}, E, nu, rho, order, plane, thickness, fixed, damping,
                  grid.label())
