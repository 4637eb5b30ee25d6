r"""Linear elastic solids from meshes (2D plane stress/strain, 3D), discretized with scikit-fem.

The weak form of elastodynamics over the body :math:`\Omega` (thickness :math:`t` in 2D),

.. math::

    \int_\Omega \rho\, \ddot u \cdot v \, t\,d\Omega
    + \int_\Omega \sigma(u) : \varepsilon(v) \, t\,d\Omega = 0, \qquad
    \sigma(u) = 2 \mu\, \varepsilon(u) + \lambda \operatorname{tr} \varepsilon(u)\, I,

gives the consistent mass :math:`M_{ij} = \int \rho\, \phi_i \cdot \phi_j` and the stiffness
:math:`K_{ij} = \int \sigma(\phi_i) : \varepsilon(\phi_j)` over a vector Lagrange basis
(P1/Q1 for ``order=1``, P2/Q2 for ``order=2``) on triangles, quadrilaterals, tetrahedra or
hexahedra.  The Lamé parameters are

.. math::

    \mu = \frac{E}{2 (1 + \nu)}, \qquad
    \lambda = \frac{E \nu}{(1 + \nu)(1 - 2\nu)} \ \text{(3D, plane strain)}, \qquad
    \lambda = \frac{E \nu}{1 - \nu^2} \ \text{(plane stress)}.

Supports are Dirichlet conditions :math:`u_c = 0` on selected DOFs, which are *condensed*: the
substructure's coordinates are the free DOFs only.  Selectors:

* ``{"box": [[xmin, ymin, zmin], [xmax, ymax, zmax]], "components": [0, 1, 2]}``: the DOFs whose
  node lies in the box (``components`` optional, default all; also ``"x"``, ``"y"``, ``"z"``);
* ``{"set": "clamp", "components": ...}`` or just ``"clamp"``: a named set of the mesh (meshio
  ``cell_sets`` / ``point_sets``, Gmsh physical groups, scikit-fem ``boundaries`` /
  ``subdomains``).  A DOF belongs to the set when every vertex of its mesh entity (its node,
  edge, face or cell) does.

Points: ``where = (xyz, component)`` or ``{"at": xyz, "component": "x"}`` (or
``{"node": k, "component": ...}``).  At a node the row is a unit row; elsewhere it is the
interpolation row :math:`u_c(x) = \sum_j \phi_j(x) q_j` (``Basis.probes``).  A point outside the
mesh raises :class:`~substruct.substructure.PointError`.  2D solids live in the plane ``z = 0``
and have no ``z`` displacement.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import meshio
import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree
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
from skfem.io.meshio import from_meshio, to_meshio
from skfem.models.elasticity import lame_parameters, plane_stress

from substruct.substructure import Geometry, PointError, Substructure, as_csr

__all__ = ["COMPONENTS", "read_mesh", "solid_from_mesh", "solid_box", "solid_rectangle"]

COMPONENTS = ("x", "y", "z")
"""Names of the displacement components (``0, 1, 2`` also accepted)."""

_ELEMENTS = {
    ("hex", 1): ElementHex1, ("hex", 2): ElementHex2,
    ("tet", 1): ElementTetP1, ("tet", 2): ElementTetP2,
    ("quad", 1): ElementQuad1, ("quad", 2): ElementQuad2,
    ("tri", 1): ElementTriP1, ("tri", 2): ElementTriP2,
}
_KIND = {MeshHex: "hex", MeshTet: "tet", MeshQuad: "quad", MeshTri: "tri"}
# meshio cell types we read (higher-order cells are read through their vertices)
_VOLUME = {"hexahedron": 8, "hexahedron20": 8, "hexahedron27": 8, "tetra": 4, "tetra10": 4}
_PLANAR = {"quad": 4, "quad8": 4, "quad9": 4, "triangle": 3, "triangle6": 3}


# ------------------------------------------------------------------------------------ meshes


def _mesh_label(source: Any) -> str:
    return os.fspath(source) if isinstance(source, (str, os.PathLike)) else type(source).__name__


def read_mesh(source: str | os.PathLike | meshio.Mesh | Mesh
              ) -> tuple[Mesh, dict[str, np.ndarray]]:
    """A scikit-fem mesh and its named vertex sets from a file, a meshio mesh or a skfem mesh.

    The cells of highest dimension are used (hexahedra or tetrahedra, else quadrilaterals or
    triangles; second-order cells through their vertices, i.e. straight-sided); points that no
    such cell uses are dropped.  Named sets (meshio ``cell_sets`` and ``point_sets``, Gmsh
    physical groups through ``field_data``, scikit-fem ``boundaries`` and ``subdomains``) become
    sets of vertex indices.

    Raises:
        ValueError: a missing or unreadable file (the message names the path), or a mesh with
            no supported cells or with mixed cell types.
    """
    if isinstance(source, Mesh):
        return source, _skfem_sets(source)
    if isinstance(source, (str, os.PathLike)):
        path = os.fspath(source)
        if not os.path.isfile(path):
            raise ValueError(f"mesh file {path!r} does not exist")
        try:
            # ".msh" is also ANSYS's: meshio would try that reader first (and print)
            fmt = "gmsh" if path.lower().endswith(".msh") else None
            source = meshio.read(path, file_format=fmt)
        except Exception as exc:  # meshio raises many kinds for a corrupt file
            raise ValueError(f"cannot read mesh file {path!r}: {type(exc).__name__}: {exc}"
                             ) from None
    if not isinstance(source, meshio.Mesh):
        raise ValueError(f"a mesh must be a file path, a meshio.Mesh or a skfem Mesh, "
                         f"got {type(source).__name__}")
    return _from_meshio(source, _mesh_label(source))


def _from_meshio(m: meshio.Mesh, label: str) -> tuple[Mesh, dict[str, np.ndarray]]:
    types = [c.type for c in m.cells]
    table = _VOLUME if any(t in _VOLUME for t in types) else _PLANAR
    blocks = [(i, c) for i, c in enumerate(m.cells) if c.type in table]
    if not blocks:
        raise ValueError(f"mesh {label}: no supported cells (found {sorted(set(types))}; "
                         f"supported: {sorted(_VOLUME) + sorted(_PLANAR)})")
    kinds = {table[c.type] for _, c in blocks}
    if len(kinds) > 1:
        raise ValueError(f"mesh {label}: mixed cell types {sorted({c.type for _, c in blocks})}"
                         " are not supported")
    nv = kinds.pop()
    conn = np.vstack([np.asarray(c.data)[:, :nv] for _, c in blocks])
    used = np.unique(conn)
    remap = np.full(len(m.points), -1, dtype=np.int64)
    remap[used] = np.arange(used.size)
    base = {8: "hexahedron", 4: "tetra" if table is _VOLUME else "quad", 3: "triangle"}[nv]
    points = np.asarray(m.points, dtype=float)[used]
    if table is _PLANAR and points.shape[1] == 3:
        if np.ptp(points[:, 2]) > 1e-12 * max(np.ptp(points[:, :2]), 1e-300):
            raise ValueError(f"mesh {label}: a planar mesh must lie in a plane z = const")
    try:
        mesh = from_meshio(meshio.Mesh(points, [(base, remap[conn])]))
    except Exception as exc:
        raise ValueError(f"mesh {label}: scikit-fem cannot use it: {exc}") from None
    return mesh, _meshio_sets(m, remap)


def _meshio_sets(m: meshio.Mesh, remap: np.ndarray) -> dict[str, np.ndarray]:
    """Named vertex sets of a meshio mesh, in the renumbered vertices."""
    sets: dict[str, list[np.ndarray]] = {}

    def add(name: str, pts: np.ndarray) -> None:
        sets.setdefault(str(name), []).append(np.asarray(pts, dtype=np.int64).ravel())

    for name, per_block in (m.cell_sets or {}).items():
        if str(name).startswith("gmsh:"):
            continue
        for block, idx in zip(m.cells, per_block):
            if idx is not None and len(idx):
                add(name, np.asarray(block.data)[np.asarray(idx, dtype=np.int64)])
    for name, idx in (m.point_sets or {}).items():
        add(name, idx)
    tags = m.cell_data.get("gmsh:physical") if m.cell_data else None
    if tags is not None and m.field_data:
        names = {int(v[0]): k for k, v in m.field_data.items()}
        for block, tag in zip(m.cells, tags):
            tag = np.asarray(tag)
            for t in np.unique(tag):
                if int(t) in names:
                    add(names[int(t)], np.asarray(block.data)[tag == t])
    out = {}
    for name, parts in sets.items():
        v = remap[np.unique(np.concatenate(parts))]
        out[name] = np.unique(v[v >= 0])
    return out


def _skfem_sets(mesh: Mesh) -> dict[str, np.ndarray]:
    out: dict[str, np.ndarray] = {}
    for name, facets in (mesh.boundaries or {}).items():
        out[name] = np.unique(mesh.facets[:, np.asarray(facets)])
    for name, cells in (mesh.subdomains or {}).items():
        out[name] = np.unique(mesh.t[:, np.asarray(cells)])
    return out


# ------------------------------------------------------------------------------ the FE model


@dataclass(frozen=True)
class _Nodes:
    """Where the DOFs are: node ``k`` at ``xyz[k]`` carries DOFs ``dofs[k, c]`` (full basis)."""

    xyz: np.ndarray       # (Nn, dim)
    dofs: np.ndarray      # (Nn, dim) indices into the full basis
    entity: np.ndarray    # (Nn, nvert_max) vertices of the entity a node sits on (-1 padded)


def _nodes(basis: Basis) -> _Nodes:
    """Nodes of a *scalar* Lagrange basis: node ``k`` is scalar DOF ``k``; its vector DOFs
    are ``dim * k + c`` (interleaved, as scikit-fem numbers ``ElementVector`` DOFs)."""
    mesh = basis.mesh
    dim = mesh.dim()
    xyz = basis.doflocs.T
    # the mesh entity each node sits on: vertex, edge (3D), facet or cell
    groups = [(basis.nodal_dofs, np.arange(mesh.nvertices)[None, :])]
    if dim == 3 and basis.edge_dofs.size:
        groups.append((basis.edge_dofs, mesh.edges))
    if basis.facet_dofs.size:
        groups.append((basis.facet_dofs, mesh.facets))
    if basis.interior_dofs.size:
        groups.append((basis.interior_dofs, mesh.t))
    width = max(g[1].shape[0] for g in groups)
    entity = np.full((len(xyz), width), -1, dtype=np.int64)
    for dofs, verts in groups:
        entity[dofs[0], :verts.shape[0]] = verts.T
    dofs = dim * np.arange(len(xyz))[:, None] + np.arange(dim)[None, :]
    return _Nodes(xyz=xyz, dofs=dofs, entity=entity)


def _components(name: str, comps: Any, dim: int) -> list[int]:
    if comps is None:
        return list(range(dim))
    if isinstance(comps, (str, int, np.integer)):
        comps = [comps]
    return [_component(name, c, dim) for c in comps]


def _component(name: str, c: Any, dim: int) -> int:
    if isinstance(c, str):
        key = c.strip().lower().removeprefix("u")
        if key in COMPONENTS:
            c = COMPONENTS.index(key)
    if isinstance(c, (int, np.integer)) and not isinstance(c, bool) and 0 <= c < dim:
        return int(c)
    raise PointError(f"{name}: no displacement component {c!r} in a {dim}D solid "
                     f"(use one of {list(COMPONENTS[:dim])} or 0..{dim - 1})")


def _select_nodes(name: str, selector: Any, nodes: _Nodes, sets: Mapping[str, np.ndarray],
                  diameter: float) -> tuple[np.ndarray, Any]:
    """Node indices selected by a box or a named set, and the components asked for."""
    if isinstance(selector, str):
        selector = {"set": selector}
    if not isinstance(selector, Mapping):
        raise ValueError(f"{name}: a support selector is a box {{'box': [[..], [..]]}} or a "
                         f"named set {{'set': name}}, got {selector!r}")
    unknown = set(selector) - {"box", "set", "components"}
    if unknown or ("box" in selector) == ("set" in selector):
        raise ValueError(f"{name}: a selector needs exactly one of 'box' or 'set' (and "
                         f"optionally 'components'), got keys {sorted(selector)}")
    dim = nodes.xyz.shape[1]
    if "box" in selector:
        lo, hi = _box(name, selector["box"], dim)
        tol = 1e-9 * diameter
        inside = np.all((nodes.xyz >= lo - tol) & (nodes.xyz <= hi + tol), axis=1)
        return np.flatnonzero(inside), selector.get("components")
    set_name = str(selector["set"])
    if set_name not in sets:
        raise ValueError(f"{name}: no named set {set_name!r} in the mesh; it has "
                         f"{sorted(sets) or 'none'}")
    return _set_nodes(sets[set_name], nodes), selector.get("components")


def _set_nodes(vertices: np.ndarray, nodes: _Nodes) -> np.ndarray:
    """Nodes whose entity (vertex, edge, facet, cell) has all its vertices in ``vertices``."""
    member = np.zeros(int(nodes.entity.max()) + 2, dtype=bool)
    member[vertices] = True
    member[-1] = True  # the -1 padding counts as a member
    return np.flatnonzero(member[nodes.entity].all(axis=1))


def _box(name: str, box: Any, dim: int) -> tuple[np.ndarray, np.ndarray]:
    try:
        lo, hi = (np.asarray(c, dtype=float).ravel() for c in box)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: a box is [[xmin, ymin, zmin], [xmax, ymax, zmax]], "
                         f"got {box!r}") from None
    if lo.size not in (dim, 3) or hi.size != lo.size or np.any(lo > hi):
        raise ValueError(f"{name}: a box is [[xmin, ymin, zmin], [xmax, ymax, zmax]] with "
                         f"min <= max ({dim} or 3 coordinates), got {box!r}")
    if lo.size == 3 and dim == 2 and not lo[2] <= 0.0 <= hi[2]:
        raise ValueError(f"{name}: the box {box!r} misses the plane z = 0 of a 2D solid")
    return lo[:dim], hi[:dim]


def _fixed_dofs(name: str, fixed: Sequence[Any], nodes: _Nodes,
                sets: Mapping[str, np.ndarray], diameter: float) -> np.ndarray:
    dim = nodes.xyz.shape[1]
    out = [np.zeros(0, dtype=np.int64)]
    for selector in fixed:
        picked, comps = _select_nodes(name, selector, nodes, sets, diameter)
        if picked.size == 0:
            raise ValueError(f"{name}: the support {selector!r} selects no node")
        out.append(nodes.dofs[np.ix_(picked, _components(name, comps, dim))].ravel())
    return np.unique(np.concatenate(out))


def _damping(name: str, damping: Any) -> tuple[float, float]:
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


def _material(name: str, E: float, nu: float, rho: float, dim: int, plane: str | None
              ) -> tuple[float, float]:
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


def _where(name: str, where: Any, dim: int, nodes: _Nodes) -> tuple[np.ndarray, int, int | None]:
    """``(xyz (dim,), component, node or None)`` of a point reference."""
    node = None
    if isinstance(where, Mapping):
        keys = set(where)
        if keys == {"node", "component"}:
            node = int(where["node"])
            if not 0 <= node < len(nodes.xyz):
                raise PointError(f"{name}: no node {node} (0..{len(nodes.xyz) - 1})")
            return nodes.xyz[node], _component(name, where["component"], dim), node
        if keys != {"at", "component"}:
            raise PointError(f"{name}: a point is {{'at': [x, y, z], 'component': 'x'}}, "
                             f"got keys {sorted(keys)}")
        xyz, comp = where["at"], where["component"]
    elif isinstance(where, (tuple, list)) and len(where) == 2:
        xyz, comp = where
    else:
        raise PointError(f"{name}: a point is (xyz, component) or {{'at': xyz, 'component': "
                         f"c}}, got {where!r}")
    try:
        x = np.asarray(xyz, dtype=float).ravel()
    except (TypeError, ValueError):
        raise PointError(f"{name}: bad coordinates {xyz!r}") from None
    if x.size not in (dim, 3) or not np.all(np.isfinite(x)):
        raise PointError(f"{name}: a point needs {dim} (or 3) finite coordinates, got {xyz!r}")
    if x.size == 3 and dim == 2 and x[2] != 0.0:
        raise PointError(f"{name}: point {x.tolist()} is off the plane z = 0 of a 2D solid")
    return x[:dim], _component(name, comp, dim), node


def _assemble(mesh: Mesh, order: int, lam: float, mu: float, rho: float, scale: float
              ) -> tuple[Basis, sp.csr_array, sp.csr_array]:
    r"""Scalar basis, ``K`` and ``M`` in the interleaved vector numbering ``dim * node + c``.

    With the scalar matrices :math:`G^{ij}_{ab} = \int \partial_i \phi_a\, \partial_j \phi_b`,
    :math:`L = \sum_k G^{kk}` and :math:`S_{ab} = \int \rho\, \phi_a \phi_b`,

    .. math::

        K_{(a,i),(b,j)} = \mu\, \delta_{ij} L_{ab} + \mu\, G^{ji}_{ab} + \lambda\, G^{ij}_{ab},
        \qquad M_{(a,i),(b,j)} = \delta_{ij} S_{ab},

    which is :func:`skfem.models.elasticity.linear_elasticity` (``2 mu eps(u):eps(v) +
    lam div u div v``) on ``ElementVector``, assembled from a scalar basis: a vector basis
    holds ``dim^2`` times more per-quadrature-point data.
    """
    kind = _KIND[type(mesh)]
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


def _build(name: str, mesh: Mesh, sets: Mapping[str, np.ndarray], E: float, nu: float,
           rho: float, order: int, plane: str | None, thickness: float, fixed: Sequence[Any],
           damping: Any, source: str) -> Substructure:
    if type(mesh) not in _KIND:
        raise ValueError(f"{name}: unsupported mesh type {type(mesh).__name__}")
    if order not in (1, 2):
        raise ValueError(f"{name}: order must be 1 or 2, got {order!r}")
    dim = mesh.dim()
    lam, mu = _material(name, E, nu, rho, dim, plane)
    t = float(thickness) if dim == 2 else 1.0
    if not (np.isfinite(t) and t > 0):
        raise ValueError(f"{name}: thickness must be positive, got {thickness!r}")
    alpha, beta = _damping(name, damping)
    basis, K, M = _assemble(mesh, order, lam, mu, float(rho), t)
    nodes = _nodes(basis)
    diameter = float(np.ptp(mesh.p, axis=1).max())
    fixed_dofs = _fixed_dofs(name, list(fixed or []), nodes, sets, diameter)
    n_full = dim * basis.N
    free = np.setdiff1d(np.arange(n_full), fixed_dofs)
    col = np.full(n_full, -1, dtype=np.int64)
    col[free] = np.arange(free.size)
    K = as_csr(K[free][:, free])
    M = as_csr(M[free][:, free])
    C = as_csr(alpha * M + beta * K) if alpha or beta else as_csr(None, free.size)
    n = free.size
    labels = np.empty(n_full, dtype=object)
    for c in range(dim):
        labels[nodes.dofs[:, c]] = [f"n{k}.u{COMPONENTS[c]}" for k in range(len(nodes.xyz))]
    tree = cKDTree(nodes.xyz)
    tol = 1e-9 * diameter

    def unit(dof: int) -> sp.csr_array:
        j = col[dof]
        if j < 0:  # a supported DOF: it does not move
            return sp.csr_array((1, n))
        return sp.csr_array(([1.0], ([0], [j])), shape=(1, n))

    def locate(where: Any) -> sp.csr_array:
        x, c, node = _where(name, where, dim, nodes)
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
        x, _, _ = _where(name, where, dim, nodes)
        return np.pad(np.asarray(x, dtype=float), (0, 3 - dim))

    geometry = _geometry(mesh, nodes, col, n)
    meta = {"E": float(E), "nu": float(nu), "rho": float(rho), "order": int(order),
            "cell": _KIND[type(mesh)], "dim": dim, "plane": plane, "thickness": t,
            "n_nodes": int(len(nodes.xyz)), "n_elements": int(mesh.t.shape[1]),
            "n_fixed": int(fixed_dofs.size), "mesh": source,
            "node_sets": {k: _set_nodes(v, nodes) for k, v in sets.items()},
            "damping": {"rayleigh": [alpha, beta]} if alpha or beta else None}
    return Substructure(name=name, M=M, K=K, C=C, dof_labels=tuple(labels[free]),
                        locate=locate, kind=f"solid/{_KIND[type(mesh)]}{order}", geometry=geometry,
                        meta=meta, position=position)


def _geometry(mesh: Mesh, nodes: _Nodes, col: np.ndarray, n: int) -> Geometry:
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
        fixed: support selectors (see the module docstring).
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
                  _mesh_label(mesh))


def _grid(name: str, lengths: Sequence[float], divisions: Sequence[int], origin: Any,
          dim: int) -> list[np.ndarray]:
    L = np.asarray(lengths, dtype=float).ravel()
    d = np.asarray(divisions).ravel()
    o = np.zeros(dim) if origin is None else np.asarray(origin, dtype=float).ravel()
    if L.size != dim or d.size != dim or o.size != dim:
        raise ValueError(f"{name}: lengths, divisions and origin need {dim} entries each")
    if np.any(~np.isfinite(L)) or np.any(L <= 0) or np.any(d < 1) or \
            np.any(d != np.round(d)):
        raise ValueError(f"{name}: lengths must be positive and divisions integers >= 1, "
                         f"got {L.tolist()}, {d.tolist()}")
    return [np.linspace(o[i], o[i] + L[i], int(d[i]) + 1) for i in range(dim)]


def solid_box(name: str, lengths: Sequence[float], divisions: Sequence[int], E: float,
              nu: float, rho: float, order: int = 1, cell: str = "hex",
              origin: Sequence[float] | None = None, fixed: Sequence[Any] = (),
              damping: Any = None) -> Substructure:
    r"""A 3D box :math:`[o, o + L]` meshed by a tensor grid of hexahedra (or tetrahedra).

    ``divisions = (n_x, n_y, n_z)`` elements per side (``cell="tet"`` splits each hexahedron
    into tetrahedra).  Other arguments as :func:`solid_from_mesh`.
    """
    axes = _grid(name, lengths, divisions, origin, 3)
    if cell not in ("hex", "tet"):
        raise ValueError(f"{name}: cell must be 'hex' or 'tet', got {cell!r}")
    mesh = (MeshHex if cell == "hex" else MeshTet).init_tensor(*axes)
    return _build(name, mesh, {}, E, nu, rho, order, None, 1.0, fixed, damping,
                  f"box {list(lengths)} / {list(divisions)} {cell}")


def solid_rectangle(name: str, lengths: Sequence[float], divisions: Sequence[int], E: float,
                    nu: float, rho: float, order: int = 1, cell: str = "quad",
                    plane: str = "stress", thickness: float = 1.0,
                    origin: Sequence[float] | None = None, fixed: Sequence[Any] = (),
                    damping: Any = None) -> Substructure:
    r"""A 2D rectangle :math:`[o, o + L]` of quadrilaterals (or triangles), plane stress/strain.

    ``divisions = (n_x, n_y)``.  Other arguments as :func:`solid_from_mesh`.
    """
    axes = _grid(name, lengths, divisions, origin, 2)
    if cell not in ("quad", "tri"):
        raise ValueError(f"{name}: cell must be 'quad' or 'tri', got {cell!r}")
    mesh = (MeshQuad if cell == "quad" else MeshTri).init_tensor(*axes)
    return _build(name, mesh, {}, E, nu, rho, order, plane, thickness, fixed, damping,
                  f"rectangle {list(lengths)} / {list(divisions)} {cell}")
