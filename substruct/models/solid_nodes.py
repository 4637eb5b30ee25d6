"""Where the DOFs of a solid are, and how a case names them: nodes of a Lagrange basis,
support selectors (a box or a named set of the mesh) and points ``(xyz, component)``.

Selectors:

* ``{"box": [[xmin, ymin, zmin], [xmax, ymax, zmax]], "components": [0, 1, 2]}``: the DOFs
  whose node lies in the box (``components`` optional, default all; also ``"x"``, ``"y"``,
  ``"z"``), within :data:`substruct.models.selection.NODE_TOL` of the model size;
* ``{"set": "clamp", "components": ...}`` or just ``"clamp"``: a named set of the mesh.  A DOF
  belongs to the set when every vertex of its mesh entity (its node, edge, face or cell) does.

Points: ``(xyz, component)``, ``{"at": xyz, "component": "x"}`` or ``{"node": k,
"component": ...}``.  2D solids live in the plane ``z = 0`` and have no ``z`` displacement.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np
from skfem import Basis

from substruct.models.selection import (
    component_index,
    component_indices,
    nodes_in_box,
    parse_box,
)
from substruct.substructure import PointError

__all__ = ["Nodes", "basis_nodes", "set_nodes", "select_nodes", "fixed_dofs", "locate_point"]


@dataclass(frozen=True)
class Nodes:
    """Where the DOFs are: node ``k`` at ``xyz[k]`` carries DOFs ``dofs[k, c]`` (full basis).

    Attributes:
        xyz: ``(Nn, dim)`` node positions.
        dofs: ``(Nn, dim)`` indices into the full (unsupported) vector basis.
        entity: ``(Nn, nvert_max)`` vertices of the mesh entity a node sits on (-1 padded).
    """

    xyz: np.ndarray
    dofs: np.ndarray
    entity: np.ndarray


def basis_nodes(basis: Basis) -> Nodes:
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
    return Nodes(xyz=xyz, dofs=dofs, entity=entity)


def set_nodes(vertices: np.ndarray, nodes: Nodes) -> np.ndarray:
    """Nodes whose entity (vertex, edge, facet, cell) has all its vertices in ``vertices``."""
    member = np.zeros(int(nodes.entity.max()) + 2, dtype=bool)
    member[vertices] = True
    member[-1] = True  # the -1 padding counts as a member
    return np.flatnonzero(member[nodes.entity].all(axis=1))


def select_nodes(name: str, selector: Any, nodes: Nodes, sets: Mapping[str, np.ndarray],
                 tol: float) -> tuple[np.ndarray, Any]:
    """Node indices selected by a box (widened by ``tol``) or a named set, and the components
    asked for (``None``: all).

    Raises:
        ValueError: a selector of another form, a bad box, an unknown set.
    """
    if isinstance(selector, str):
        selector = {"set": selector}
    if not isinstance(selector, Mapping):
        raise ValueError(f"{name}: a support selector is a box {{'box': [[..], [..]]}} or a "
                         f"named set {{'set': name}}, got {selector!r}")
    unknown = set(selector) - {"box", "set", "components"}
    if unknown or ("box" in selector) == ("set" in selector):
        raise ValueError(f"{name}: a selector needs exactly one of 'box' or 'set' (and "
                         f"optionally 'components'), got keys {sorted(selector)}")
    if "box" in selector:
        lo, hi = parse_box(selector["box"], nodes.xyz.shape[1], name)
        return nodes_in_box(nodes.xyz, lo, hi, tol), selector.get("components")
    set_name = str(selector["set"])
    if set_name not in sets:
        raise ValueError(f"{name}: no named set {set_name!r} in the mesh; it has "
                         f"{sorted(sets) or 'none'}")
    return set_nodes(sets[set_name], nodes), selector.get("components")


def fixed_dofs(name: str, fixed: Sequence[Any], nodes: Nodes, sets: Mapping[str, np.ndarray],
               tol: float) -> np.ndarray:
    """The supported DOFs (full basis) of the support selectors ``fixed``.

    Raises:
        ValueError: a bad selector, or one that selects no node.
    """
    dim = nodes.xyz.shape[1]
    out = [np.zeros(0, dtype=np.int64)]
    for selector in fixed:
        picked, comps = select_nodes(name, selector, nodes, sets, tol)
        if picked.size == 0:
            raise ValueError(f"{name}: the support {selector!r} selects no node")
        comp = np.asarray(component_indices(comps, dim, name), dtype=np.int64)
        out.append(nodes.dofs[np.ix_(picked, comp)].ravel())
    return np.unique(np.concatenate(out))


def locate_point(name: str, where: Any, nodes: Nodes) -> tuple[np.ndarray, int, int | None]:
    """``(xyz (dim,), component, node or None)`` of a point reference.

    Raises:
        PointError: a reference of another form, no such node or component, coordinates that
            are not finite, or off the plane ``z = 0`` of a 2D solid.
    """
    dim = nodes.xyz.shape[1]
    node = None
    if isinstance(where, Mapping):
        keys = set(where)
        if keys == {"node", "component"}:
            node = int(where["node"])
            if not 0 <= node < len(nodes.xyz):
                raise PointError(f"{name}: no node {node} (0..{len(nodes.xyz) - 1})")
            return nodes.xyz[node], component_index(where["component"], dim, name), node
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
    return x[:dim], component_index(comp, dim, name), node
