r"""Solids in a case: points ``"sub@x,y,z:c"``, building, interfaces, reduction; large models.

Called by :func:`substruct.run.runner.build_model` and :func:`substruct.run.runner.run_case`:

1. :func:`solid_where` reads a point on a solid, ``box@4,0.5,1:z`` (coordinates, then the
   displacement component) or ``box@n12:z`` (a node, numbered as in the DOF labels
   ``n12.uz``), into what the solid's locator takes (``{"at": [..], "component": "z"}``).
2. :func:`build_solid` reads or generates the mesh (sized before it is assembled, with an
   estimate, as rods are), checks the support selectors against it and makes the solid
   (:func:`substruct.models.solid.solid_from_mesh`).
3. :func:`tie_and_reduce` ties the solids of each ``interfaces:`` item
   (:func:`substruct.assembly.interfaces.tie_nodes` or
   :func:`~substruct.assembly.interfaces.tie_nonmatching`), then reduces the solids that ask
   for it: modal truncation, or Craig-Bampton with the boundary made of every coordinate that
   a tie, a connection, a constraint or an FRF point uses (so those rows stay exact) and the
   nodes of ``reduce.interface``.

Nodes, boxes and components are selected as everywhere else
(:mod:`substruct.models.selection`).  Every problem is a :class:`~substruct.case.loader.CaseError` naming the field of the case file.
"""

from __future__ import annotations

import math
from typing import Any, Collection, Mapping, Sequence

import numpy as np
import scipy.sparse as sp

from substruct.assembly.stack import Connection
from substruct.builder.interface_reduced import interface_reduced
from substruct.case.errors import MISSING
from substruct.case.expressions import ExpressionError, scalar
from substruct.case.fields import MAX_ELEMENTS, gigabytes, memory_limit
from substruct.case.solids import InterfaceSpec, SolidReduce, SolidSpec, solid_memory
from substruct.models.selection import (
    COMPONENTS,
    component_index,
    node_tolerance,
    nodes_in_box,
)
from substruct.substructure import PointError, Substructure

__all__ = ["solid_where", "mesh_of", "build_solid", "tie_and_reduce"]

# ---------------------------------------------------------------------------- points


def solid_where(case: Any, spec: SolidSpec, where: str | None, use: Any) -> dict[str, Any]:
    """``{"at": [x, y(, z)], "component": c}`` or ``{"node": k, "component": c}`` from the
    ``where`` of ``"sub@where"``: ``x,y,z:c`` (numbers or expressions of the parameters) or
    ``n<k>:c``."""
    example = (f"{spec.name}@x,y,z:c (c one of x, y, z), e.g. {spec.name}@0.5,0,0.1:z, or a "
               f"node, {spec.name}@n12:z")
    if where is None:
        raise case.error(use.loc, f"a point on solid {spec.name!r} needs a place and a "
                         f"component: {example}", use.text)
    place, colon, comp = where.rpartition(":")
    if not colon:
        raise case.error(use.loc, f"a point on solid {spec.name!r} needs a displacement "
                         f"component after ':': {example}", use.text)
    comp = comp.strip().lower()
    mesh_of(case, spec)  # the dimension of a mesh file is known once read
    dim = spec.dim()
    try:
        comp = COMPONENTS[component_index(comp, dim or 3, spec.name)]
    except PointError:
        raise case.error(use.loc, f"no displacement component {comp!r} on solid "
                         f"{spec.name!r} (one of {', '.join(COMPONENTS[:dim or 3])})",
                         use.text) from None
    place = place.strip()
    if len(place) > 1 and place[0] == "n" and place[1:].isdigit():
        return {"node": int(place[1:]), "component": comp}
    parts = [p.strip() for p in place.split(",")]
    if len(parts) not in (2, 3) or (dim is not None and len(parts) not in (dim, 3)):
        need = f"{dim}" if dim == 3 else "2 (or 3, z = 0)" if dim == 2 else "2 or 3"
        raise case.error(use.loc, f"a point on solid {spec.name!r} needs {need} coordinates "
                         f"x,y,z before ':', or a node n<k>: {example}", use.text)
    coords = []
    for p in parts:
        try:
            v = float(p)
        except ValueError:
            try:
                v = scalar(p, dict(case.parameters))
            except ExpressionError as err:
                raise case.error(use.loc, f"not a place on solid {spec.name!r}: {err}",
                                 use.text) from None
        if not math.isfinite(v):
            raise case.error(use.loc, f"not a place on solid {spec.name!r}: coordinate "
                             f"{p!r} is not finite", use.text)
        coords.append(float(v))
    return {"at": coords, "component": comp}


# ----------------------------------------------------------------------------- solids


def _read_file(case: Any, i: int, spec: SolidSpec) -> tuple[Any, Any, dict]:
    """``(meshio mesh, skfem mesh, named vertex sets)`` of a mesh file."""
    from substruct.case.mesh_files import MeshFileError, read_mesh_file
    from substruct.models.solid import read_mesh

    loc = ("substructures", i, "mesh")
    path = case.base_dir / spec.mesh
    try:
        raw = read_mesh_file(path)
    except MeshFileError as err:  # checked before, during and after meshio reads it
        raise case.error(loc, str(err), spec.mesh) from None
    try:
        mesh, sets = read_mesh(raw)
    except ValueError as err:
        raise case.error(loc, str(err).replace("mesh Mesh:", f"mesh file {path}:"),
                         spec.mesh) from None
    return raw, mesh, sets


def _generated(spec: SolidSpec) -> Any:
    """The skfem mesh of a ``box`` or ``rectangle``, with its faces (edges) named ``xmin``,
    ``xmax``, ``ymin``, ``ymax`` (, ``zmin``, ``zmax``)."""
    from skfem import MeshHex, MeshQuad, MeshTet, MeshTri

    shape = spec.box if spec.box is not None else spec.rectangle
    if shape is None:  # the schema asks for exactly one of mesh, box and rectangle
        raise ValueError(f"{spec.name}: neither a mesh, nor a box, nor a rectangle")
    dim = len(shape.lengths)
    axes = [np.linspace(o, o + L, d + 1)
            for o, L, d in zip(shape.origin, shape.lengths, shape.divisions)]
    kind = {"hex": MeshHex, "tet": MeshTet, "quad": MeshQuad, "tri": MeshTri}[shape.cell]
    mesh = kind.init_tensor(*axes)
    tol = node_tolerance(np.asarray(mesh.p).T)
    faces = {}
    for c in range(dim):
        lo, hi = axes[c][0], axes[c][-1]
        faces[f"{COMPONENTS[c]}min"] = (lambda x, c=c, v=lo: np.abs(x[c] - v) <= tol)
        faces[f"{COMPONENTS[c]}max"] = (lambda x, c=c, v=hi: np.abs(x[c] - v) <= tol)
    return mesh.with_boundaries(faces)


def _estimate_nodes(mesh: Any, order: int) -> int:
    """Nodes of a Lagrange basis of ``order`` on ``mesh`` (exact for P1, close for P2)."""
    nv = int(mesh.nvertices)
    return nv if order == 1 else nv * 2 ** mesh.dim()


def _check_fixed(case: Any, i: int, spec: SolidSpec, mesh: Any, sets: dict) -> None:
    """Support selectors against the mesh: known sets, components of its dimension, boxes
    that hold at least one vertex."""
    dim = mesh.dim()
    p = np.asarray(mesh.p, dtype=float)
    tol = node_tolerance(p.T)
    for k, sel in enumerate(spec.fixed):
        loc = ("substructures", i, "fixed", k)
        if sel.set is not None and sel.set not in sets:
            known = ", ".join(sorted(sets)) or "none"
            raise case.error(loc, f"no named set {sel.set!r} in the mesh of {spec.name!r} "
                             f"(it has: {known})", sel.set)
        for j, c in enumerate(sel.components or []):
            try:
                component_index(c, dim, spec.name)
            except PointError:
                raise case.error((*loc, "components", j), f"no component {c!r} in the "
                                 f"{dim}D solid {spec.name!r}", c) from None
        if sel.box is not None:
            lo, hi = (np.asarray(b, dtype=float) for b in sel.box)
            if lo.size == 2 and dim == 3:
                raise case.error((*loc, "box"), f"a box on the 3D solid {spec.name!r} needs 3 "
                                 f"coordinates per corner", [list(b) for b in sel.box])
            if lo.size == 3 and dim == 2 and not lo[2] <= 0.0 <= hi[2]:
                raise case.error((*loc, "box"), f"the box misses the plane z = 0 of the 2D "
                                 f"solid {spec.name!r}", [list(b) for b in sel.box])
            if not nodes_in_box(p.T, lo[:dim], hi[:dim], tol).size:
                raise case.error((*loc, "box"), f"the box holds no node of {spec.name!r} "
                                 f"(the mesh spans {p.min(axis=1).tolist()} to "
                                 f"{p.max(axis=1).tolist()})", [list(b) for b in sel.box])


def mesh_of(case: Any, spec: SolidSpec) -> tuple[Any, Any, dict]:
    """``(what solid_from_mesh takes, skfem mesh, named vertex sets)`` of a solid, read (or
    generated) once and kept on the spec."""
    if spec._mesh is None:
        if spec.mesh is not None:
            raw, mesh, sets = _read_file(case, case.substructures.index(spec), spec)
            spec._mesh = (raw, mesh, sets)
        else:
            mesh = _generated(spec)
            spec._mesh = (mesh, mesh, {name: None for name in mesh.boundaries})
    return spec._mesh


def build_solid(case: Any, i: int, spec: SolidSpec) -> Substructure:
    """The (unreduced) solid of ``substructures[i]``.

    Raises:
        CaseError: a missing, corrupt or unsupported mesh file (naming the field and the path),
            a mesh too large (an estimate), ``plane``/``thickness`` on a 3D mesh, a support
            selector that names an unknown set, a component the solid lacks or no node.
    """
    from substruct.models.solid import solid_from_mesh

    loc = ("substructures", i)
    source, mesh, sets = mesh_of(case, spec)
    dim = mesh.dim()
    nodes = _estimate_nodes(mesh, spec.order)
    need = solid_memory(dim * nodes, dim, spec.order)
    if mesh.nelements > MAX_ELEMENTS or need > memory_limit():
        field = (*loc, "mesh") if spec.mesh is not None else loc
        raise case.error(field, f"{mesh.nelements} elements (about {dim * nodes} coordinates "
                         f"at order {spec.order}) would need about {gigabytes(need)} of memory; "
                         f"at most {MAX_ELEMENTS} elements and the memory available on this "
                         f"machine are accepted", spec.mesh if spec.mesh is not None else MISSING)
    if dim == 3:
        for key in ("plane", "thickness"):
            if getattr(spec, key) is not None:
                raise case.error((*loc, key), f"{key} is for 2D solids; the mesh of "
                                 f"{spec.name!r} is 3D", getattr(spec, key))
    _check_fixed(case, i, spec, mesh, sets)
    damping = {"rayleigh": list(spec.damping.rayleigh)} if spec.damping else None
    try:
        sub = solid_from_mesh(spec.name, source, spec.E, spec.nu, spec.rho, order=spec.order,
                              plane=(spec.plane or "stress") if dim == 2 else None,
                              thickness=spec.thickness or 1.0,
                              fixed=[s.as_argument() for s in spec.fixed], damping=damping)
    except (ValueError, PointError) as err:
        raise case.error(loc, " ".join(str(err).split())) from None
    sub.meta["mesh"] = spec.mesh if spec.mesh is not None else \
        ("box" if spec.box is not None else "rectangle")
    return sub


# ------------------------------------------------------------------------- interfaces


def _interface_ties(case: Any, k: int, spec: InterfaceSpec, subs: dict[str, Substructure]
                    ) -> list[Connection]:
    from substruct.assembly.interfaces import InterfaceError, tie_nodes, tie_nonmatching

    loc = ("interfaces", k)
    specs = {s.name: s for s in case.substructures}
    for j, name in enumerate(spec.between):
        if name not in specs:
            raise case.error((*loc, "between", j), f"unknown substructure {name!r} (known: "
                             f"{', '.join(specs)})", name)
        if not isinstance(specs[name], SolidSpec):
            raise case.error((*loc, "between", j), f"{name!r} is a {specs[name].type}, not a "
                             f"solid: interfaces tie solids (join other substructures with "
                             f"connections)", name)
    a, b = (subs[n] for n in spec.between)
    selector = spec.nodes.as_argument()
    try:
        if spec.matching:
            ties = tie_nodes(a, b, selector, spec.components, tol=spec.tolerance,
                             name=spec.name)
        else:  # the selected nodes of the first follow the second, interpolated
            ties = tie_nonmatching(b, a, selector, spec.components, tol=spec.tolerance,
                                   name=spec.name)
    except InterfaceError as err:
        text = " ".join(str(err).split()).replace(
            "use tie_nonmatching for non-matching meshes",
            "set matching: false for non-matching meshes")
        raise case.error(loc, text) from None
    except (ValueError, PointError) as err:
        raise case.error((*loc, "nodes"), " ".join(str(err).split()), selector) from None
    if not ties:
        raise case.error((*loc, "nodes"), f"nothing to tie: every selected node is supported "
                         f"on both {spec.between[0]!r} and {spec.between[1]!r}", selector)
    return ties


def _craig_bampton(case: Any, i: int, spec: SolidSpec, reduce: SolidReduce, sub: Substructure,
                   wheres: Sequence[Any], groups: Sequence[tuple[str, list[Any]]] = ()
                   ) -> Substructure:
    from substruct.assembly.interfaces import node_dofs
    from substruct.models.craig_bampton import craig_bampton

    loc = ("substructures", i, "reduce")
    cols = _columns(sub, wheres)
    faces: list[tuple[str, set[int]]] = [(label, _columns(sub, w)) for label, w in groups]
    for k, sel in enumerate(reduce.selectors()):
        field = (*loc, "interface", k) if isinstance(reduce.interface, list) else \
            (*loc, "interface")
        try:
            dofs = node_dofs(sub, sel.as_argument(), sel.components)
        except ValueError as err:
            raise case.error(field, " ".join(str(err).split()), sel.describe()) from None
        if dofs.size == 0:
            raise case.error(field, f"the interface selects no free coordinate of "
                             f"{spec.name!r}", sel.describe())
        cols.update(int(j) for j in dofs)
        faces.append((f"interface{k}", {int(j) for j in dofs}))
    if not cols:
        raise case.error(loc, f"Craig-Bampton needs boundary coordinates: {spec.name!r} is in "
                         f"no interface, no point is used on it and reduce.interface is not "
                         f"given (use reduce: {{modes: ...}} for a free-standing solid)")
    if reduce.interface_degree is not None:
        return interface_reduced(case, loc, reduce, sub, cols, faces)
    try:
        return craig_bampton(sub, np.array(sorted(cols)), reduce.modes)
    except ValueError as err:
        raise case.error((*loc, "modes"), " ".join(str(err).split()),
                         reduce.modes) from None


def _columns(sub: Substructure, wheres: Sequence[Any]) -> set[int]:
    """The coordinates of ``sub`` that the rows of the points ``wheres`` use."""
    cols: set[int] = set()
    for where in wheres:
        try:
            row = sp.csr_array(sub.row(where))
        except (PointError, ValueError):
            continue  # reported where the point is used
        cols.update(int(j) for j in row.indices[row.data != 0])
    return cols


def _modal(case: Any, i: int, r: SolidReduce, sub: Substructure) -> Substructure:
    from substruct.models.reduction import modal_truncation

    damping = r.damping.as_argument() if r.damping is not None else None
    try:
        return modal_truncation(sub, r.modes, damping)
    except ValueError as err:
        raise case.error(("substructures", i, "reduce", "modes"), " ".join(str(err).split()),
                         r.modes) from None


def tie_and_reduce(case: Any, subs: list[Substructure], positions: dict[str, list[Any]],
                   prebuilt: Mapping[str, Substructure] | None = None,
                   only: Collection[str] | None = None
                   ) -> tuple[list[Substructure], list[Connection]]:
    """Tie the solids of ``case.interfaces`` and reduce the solids that ask for it.

    Args:
        case: the case.
        subs: the substructures, in case order (solids unreduced); those left out of ``subs``
            are left out of the result.
        positions: the points (``where``) used on each solid by connections, constraints and
            the FRF.
        prebuilt: reduced substructures made before from the same definition: put in place
            instead of reducing again.
        only: reduce these names only (``None``: every solid that asks for it).

    Returns:
        The substructures with the reduced solids in place, and the ties (one
        :class:`Connection` per node and component, in ``interfaces`` order), computed on the
        unreduced solids: their points are places, so they hold for the reduced ones.
    """
    by_name = {s.name: s for s in subs}
    names = [s.name for s in case.substructures]
    seen: set[str] = set()
    ties: list[Connection] = []
    used: dict[str, list[Any]] = {n: list(positions.get(n, [])) for n in names}
    groups: dict[str, list[tuple[str, list[Any]]]] = {n: [] for n in names}
    for k, spec in enumerate(case.interfaces):
        if spec.name is not None:
            if spec.name in seen:
                raise case.error(("interfaces", k, "name"), "duplicate interface name",
                                 spec.name)
            seen.add(spec.name)
        conns = _interface_ties(case, k, spec, by_name)
        ties += conns
        label = spec.name if spec.name is not None else f"interfaces{k}"
        for side in ("a", "b"):
            on = {getattr(c, side).substructure for c in conns}
            for name in on:
                groups[name].append((label, [getattr(c, side).where for c in conns
                                             if getattr(c, side).substructure == name]))
        for c in conns:
            used[c.a.substructure].append(c.a.where)
            used[c.b.substructure].append(c.b.where)
    out = []
    for i, spec in enumerate(case.substructures):
        if spec.name not in by_name:
            continue
        sub = by_name[spec.name]
        if prebuilt and spec.name in prebuilt:
            sub = prebuilt[spec.name]
        elif isinstance(spec, SolidSpec) and spec.reduce is not None and \
                (only is None or spec.name in only):
            sub = _modal(case, i, spec.reduce, sub) if spec.reduce.method == "modal" else \
                _craig_bampton(case, i, spec, spec.reduce, sub, used[spec.name],
                               groups[spec.name])
        out.append(sub)
    return out, ties


