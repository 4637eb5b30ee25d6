r"""Interfaces between finite-element substructures: compatibility rows from node coordinates.

Two meshed substructures ``a`` and ``b`` that share a surface are tied by one compatibility
condition per interface node and displacement component (eq 24),

.. math::  u_c(x_k)\big|_a - u_c(x_k)\big|_b = 0 \qquad
           \Longleftrightarrow \qquad (r^a_{k,c} - r^b_{k,c})\, u = 0 ,

one row of ``A`` each (:class:`~substruct.assembly.stack.Connection`, ``r_a - r_b``).

* **Matching meshes** (:func:`tie_nodes`): every node of ``a`` on the interface has a node of
  ``b`` at the same place (within a tolerance); both rows are unit rows.
* **Non-matching meshes** (:func:`tie_nonmatching`): every node of the *slave* on the interface
  is tied to the master's displacement interpolated at that place,
  :math:`u^s_c(x_k) = \sum_j \phi^m_j(x_k)\, q^m_j` (``Basis.probes`` in the master's mesh).

Nodes are those of the substructures' drawings (``geometry.points``: all DOF nodes of a solid,
midside nodes of P2 elements included), so the ties also work after a reduction that kept the
interface DOFs (Craig-Bampton).  The interface is chosen by a box selector
``{"box": [[xmin, ymin, zmin], [xmax, ymax, zmax]]}`` (a flat box for a plane surface), a named
node set of the mesh ``{"set": name}``, or ``None`` (every node of ``a`` that has a partner).
Boxes, components and the matching tolerance are those of :mod:`substruct.models.selection`
(:data:`~substruct.models.selection.NODE_TOL` times the model size).
"""

from __future__ import annotations

from typing import Any, Mapping, Sequence

import numpy as np

from substruct.assembly.stack import Connection, PointRef
from substruct.models.selection import (
    COMPONENTS,
    component_indices,
    node_tolerance,
    nodes_in_box,
    parse_box,
)
from substruct.substructure import Geometry, PointError, Substructure

__all__ = ["InterfaceError", "interface_nodes", "node_dofs", "tie_nodes", "tie_nonmatching"]


class InterfaceError(ValueError):
    """Interface nodes that do not match."""


def _geometry(sub: Substructure) -> Geometry:
    if sub.geometry is None:
        raise ValueError(f"{sub.name}: a substructure without a mesh has no interface nodes")
    return sub.geometry


def _points(sub: Substructure) -> np.ndarray:
    return np.asarray(_geometry(sub).points, dtype=float)


def _dim(sub: Substructure) -> int:
    return int(sub.meta.get("dim", 3))


def interface_nodes(sub: Substructure, selector: Mapping[str, Any] | str | None = None,
                    tol: float | None = None) -> np.ndarray:
    """Indices of ``sub.geometry.points`` selected by a box, a named node set, or all (``None``).

    A box ``{"box": [[x0, y0, z0], [x1, y1, z1]]}`` is widened by ``tol`` (default
    :data:`~substruct.models.selection.NODE_TOL` times the mesh size) so that a flat box
    ``x0 = x1`` picks a plane of nodes.  A named set ``{"set": name}`` (or ``name``) is one of
    ``sub.meta["node_sets"]`` (solids from meshes).
    """
    pts = _points(sub)
    if selector is None:
        return np.arange(len(pts))
    if isinstance(selector, str):
        selector = {"set": selector}
    if not isinstance(selector, Mapping) or len(set(selector) & {"box", "set"}) != 1:
        raise ValueError(f"{sub.name}: an interface selector is {{'box': [[..], [..]]}} or "
                         f"{{'set': name}}, got {selector!r}")
    if "set" in selector:
        sets = sub.meta.get("node_sets") or {}
        if selector["set"] not in sets:
            raise ValueError(f"{sub.name}: no node set {selector['set']!r}; it has "
                             f"{sorted(sets) or 'none'}")
        return np.asarray(sets[selector["set"]], dtype=np.int64)
    dim = _dim(sub)
    lo, hi = parse_box(selector["box"], dim, sub.name)
    return nodes_in_box(pts[:, :dim], lo, hi, node_tolerance(pts, tol))


def node_dofs(sub: Substructure, selector: Mapping[str, Any] | str | None = None,
              components: Sequence[Any] | None = None, tol: float | None = None) -> np.ndarray:
    """Coordinates of ``sub`` that are nodal displacements at the selected nodes.

    Read from the drawing interpolation (a unit row of ``geometry.interp`` is a coordinate
    that *is* a nodal displacement); supported (condensed) DOFs have none and are skipped.
    The boundary set of a Craig-Bampton reduction, for example.
    """
    nodes = interface_nodes(sub, selector, tol)
    comps = component_indices(components, _dim(sub), sub.name)
    interp = _geometry(sub).interp.tocsr()
    rows = (3 * nodes[:, None] + np.asarray(comps)[None, :]).ravel()
    out = []
    for r in rows:
        lo, hi = interp.indptr[r], interp.indptr[r + 1]
        if hi - lo == 1 and interp.data[lo] == 1.0:
            out.append(int(interp.indices[lo]))
    return np.unique(np.asarray(out, dtype=np.int64))


def _point(xyz: np.ndarray, c: int) -> dict[str, Any]:
    return {"at": [float(v) for v in xyz], "component": COMPONENTS[c]}


def _moves(sub: Substructure, where: dict[str, Any]) -> bool:
    return sub.row(where).count_nonzero() > 0


def tie_nodes(a: Substructure, b: Substructure,
              selector: Mapping[str, Any] | str | None = None,
              components: Sequence[Any] | None = None, tol: float | None = None,
              name: str | None = None) -> list[Connection]:
    r"""Node-to-node ties between matching meshes: ``u(a, x_k) = u(b, x_k)`` per component.

    .. math::  A_{(k,c)} = r^a(x_k, c) - r^b(x_k, c)

    Args:
        a, b: the two substructures (solids, or their reductions keeping the interface).
        selector: the interface, applied to both (box, named set, or ``None``: every node of
            ``a`` with a node of ``b`` within ``tol``).  A named set is looked up in each.
        components: displacement components to tie (default all of the solid's).
        tol: largest distance of matching nodes (default
            :data:`~substruct.models.selection.NODE_TOL` times the larger mesh size).
        name: prefix of the connection names (default ``"<a>-<b>"``).

    Returns:
        One :class:`Connection` per node and component, with points
        ``PointRef(sub, {"at": xyz, "component": "x"})``.  Pairs where neither side moves (both
        supported) are left out: their row would be zero.

    Raises:
        InterfaceError: some selected node of either side has no partner within ``tol`` (the
            message gives how many and the worst distance), or nothing is selected.
    """
    from scipy.spatial import cKDTree  # here, not at import: scipy.spatial is 0.1 s

    pa, pb = _points(a), _points(b)
    t = tol if tol is not None else max(node_tolerance(pa), node_tolerance(pb))
    ia = interface_nodes(a, selector, t)
    ib = interface_nodes(b, selector, t)
    if selector is None:  # the common nodes
        dist, _ = cKDTree(pb).query(pa)
        ia = np.flatnonzero(dist <= t)
        dist, _ = cKDTree(pa).query(pb)
        ib = np.flatnonzero(dist <= t)
    if ia.size == 0 or ib.size == 0:
        raise InterfaceError(f"interface {a.name}-{b.name}: no node selected "
                             f"({ia.size} in {a.name}, {ib.size} in {b.name}) by {selector!r}")
    dist, j = cKDTree(pb[ib]).query(pa[ia])
    back, _ = cKDTree(pa[ia]).query(pb[ib])
    bad_a, bad_b = np.flatnonzero(dist > t), np.flatnonzero(back > t)
    if bad_a.size or bad_b.size:
        worst = max(dist.max(), back.max())
        where = pa[ia[bad_a[np.argmax(dist[bad_a])]]] if bad_a.size and dist.max() >= \
            back.max() else pb[ib[bad_b[np.argmax(back[bad_b])]]]
        raise InterfaceError(
            f"interface {a.name}-{b.name}: nodes do not match within {t:.3g}: "
            f"{bad_a.size} of {ia.size} nodes of {a.name} and {bad_b.size} of {ib.size} nodes "
            f"of {b.name} are unmatched; worst distance {worst:.3g} at {where.tolist()} "
            f"(use tie_nonmatching for non-matching meshes)")
    if len(np.unique(j)) != len(j):
        raise InterfaceError(f"interface {a.name}-{b.name}: several nodes of {a.name} match "
                             f"one node of {b.name} (tolerance {t:.3g} too large?)")
    prefix = name or f"{a.name}-{b.name}"
    comps = component_indices(components, _dim(a), a.name)
    out = []
    for k, jb in zip(ia, ib[j]):
        for c in comps:
            wa, wb = _point(pa[k], c), _point(pb[jb], c)
            if not (_moves(a, wa) or _moves(b, wb)):
                continue
            out.append(Connection(PointRef(a.name, wa), PointRef(b.name, wb),
                                  name=f"{prefix} node {pa[k].tolist()} u{COMPONENTS[c]}"))
    return out


def tie_nonmatching(master: Substructure, slave: Substructure,
                    selector: Mapping[str, Any] | str | None, components: Sequence[Any] | None
                    = None, tol: float | None = None, name: str | None = None
                    ) -> list[Connection]:
    r"""Ties of the slave's interface nodes to the master's interpolated displacement.

    .. math::  u^s_c(x_k) - \sum_j \phi^m_j(x_k)\, q^m_{j} = 0 \qquad
               \text{for every slave node } x_k \text{ on the interface}

    The slave's nodes follow the master's surface (the tie is one-sided, as in mortar-free
    node-to-surface coupling).  Make the *finer* mesh the slave: where its interface trace
    space holds the master's, the ties make the two traces equal everywhere (a conforming,
    upper-bound model); the other way round the finer side is free between the coarse nodes
    and the joint comes out too soft.  A slave node that falls outside the master's mesh by
    less than ``tol`` (default 100 times :data:`~substruct.models.selection.NODE_TOL` times the
    mesh size: the two meshes were written apart, each with its own round-off) is moved
    towards the master's nearest node until it is inside.

    Returns:
        One :class:`Connection` per slave node and component:
        ``PointRef(slave, {"at": x_k, ...})`` and ``PointRef(master, {"at": x_k, ...})``.

    Raises:
        InterfaceError: no slave node selected, or a slave node off the master's mesh.
    """
    from scipy.spatial import cKDTree

    ps, pm = _points(slave), _points(master)
    t = 100 * node_tolerance(np.vstack([ps, pm])) if tol is None else float(tol)
    idx = interface_nodes(slave, selector, t)
    if idx.size == 0:
        raise InterfaceError(f"interface {master.name}-{slave.name}: no slave node selected "
                             f"by {selector!r}")
    tree = cKDTree(pm)
    prefix = name or f"{master.name}-{slave.name}"
    comps = component_indices(components, _dim(slave), slave.name)
    out = []
    for k in idx:
        x = ps[k]
        xm = _inside(master, x, pm[tree.query(x)[1]], t, prefix)
        for c in comps:
            ws, wm = _point(x, c), _point(xm, c)
            if not (_moves(slave, ws) or _moves(master, wm)):
                continue
            out.append(Connection(PointRef(slave.name, ws), PointRef(master.name, wm),
                                  name=f"{prefix} node {x.tolist()} u{COMPONENTS[c]}"))
    return out


def _inside(master: Substructure, x: np.ndarray, nearest: np.ndarray, tol: float,
            prefix: str) -> np.ndarray:
    """``x`` itself if the master's mesh contains it, else ``x`` nudged towards ``nearest``."""
    dim = _dim(master)
    step = nearest - x
    length = float(np.linalg.norm(step))
    for frac in (0.0, 1e-9, 1e-6, 1e-3):
        y = x + (min(frac, tol / length) if length > 0 else 0.0) * step
        try:
            master.row({"at": list(y[:dim]) if dim == 2 else list(y), "component": "x"})
            return y
        except PointError:
            continue
    raise InterfaceError(f"interface {prefix}: slave node {x.tolist()} is off the master's "
                         f"mesh (nearest master node at distance {length:.3g})")
