"""The links of a case as rows of ``A``: the ``links:`` block (:mod:`substruct.case.links`)
and the rigid elements and MPC sets of its Nastran models (:mod:`substruct.builder.nastran`),
checked together (a coordinate dependent in two links is refused), then AUTOSPC of the Nastran
models with every link known.

Nodes of links are ``part@<id>`` on frames and Nastran models, ``part@n<k>`` or
``part@x,y,z`` on solids (:func:`link_node`).  Every problem is one line naming the field of
the case file (``links[0].dependents[1]``) or the file, line, card and id of a bulk data file.
"""

from __future__ import annotations

from typing import Any, Mapping, Sequence

from substruct.assembly.links import (
    Link, LinkError, NodeRef, interpolation_link, link_constraints, mpc, rigid_link,
)
from substruct.assembly.faces import face_node_refs, face_nodes, region_of, tributary_areas
from substruct.assembly.stack import LinearConstraint, PointRef
from substruct.builder.solids import solid_where
from substruct.case.bdf_fields import BdfError
from substruct.case.fields import parse_point
from substruct.case.frames import FrameSpec
from substruct.case.links import FaceSpec, InterpolationLinkSpec, MpcLinkSpec, RigidLinkSpec
from substruct.case.nastran import NastranSpec
from substruct.case.solids import SolidSpec
from substruct.substructure import PointError, Substructure

__all__ = ["link_node", "case_links", "link_point_texts"]


def link_point_texts(case: Any) -> list[tuple[str, tuple, str]]:
    """``(point text, loc, text as written)`` for every node of the case's links, with a
    component so that it is resolved (and kept by reductions) as any point: ``frame@5:ux``,
    ``box@n12:x`` ..., and every term of their MPCs."""
    out: list[tuple[str, tuple, str]] = []
    specs = {s.name: s for s in case.substructures}
    for k, link in enumerate(case.links):
        if isinstance(link, MpcLinkSpec):
            out += [(p, ("links", k, "terms", p), p) for p in link.terms]
            continue
        nodes: list[tuple[tuple, str]] = [(("independent",), link.independent)] \
            if isinstance(link, RigidLinkSpec) else [(("reference",), link.reference)]
        field = "dependents" if isinstance(link, RigidLinkSpec) else "nodes"
        items = (link.dependents if isinstance(link, RigidLinkSpec) else link.nodes) or []
        nodes += [((field, j), t) for j, t in enumerate(items)]
        for loc, text in nodes:
            spec = specs.get(parse_point(text)[0])
            comps = ("x", "y", "z") if isinstance(spec, SolidSpec) else ("ux",)
            out += [(f"{text}:{c}", ("links", k, *loc), text) for c in comps]
    return out


def link_node(case: Any, text: str, loc: tuple) -> NodeRef:
    """The node of ``part@id`` (frames, Nastran models), ``part@n<k>`` or ``part@x,y,z``
    (solids).

    Raises:
        CaseError: an unknown substructure, a substructure without nodes, a bad node.
    """
    sub, where = parse_point(text)
    spec = case.substructure(sub)
    if spec is None:
        raise case.error(loc, f"unknown substructure {sub!r}", text)
    where = (where or "").strip()
    if isinstance(spec, (FrameSpec, NastranSpec)):
        if not where.isdigit():
            raise case.error(loc, f"a node of {sub!r} is its id, as in {sub}@12", text)
        return NodeRef(sub, {"node": int(where)})
    if isinstance(spec, SolidSpec):
        use = type("Use", (), {"loc": loc, "text": text})()
        found = dict(solid_where(case, spec, f"{where}:x", use))
        found.pop("component", None)
        return NodeRef(sub, found)
    raise case.error(loc, "links join nodes of frames, solids and Nastran models; use "
                     "constraints: for other points", text)


def _term(case: Any, text: str, point: PointRef, loc: tuple) -> tuple[NodeRef, str]:
    """An MPC term's node and component."""
    where = point.where
    if isinstance(where, str) and ":" in where:
        node, comp = where.rsplit(":", 1)
        if node.strip().isdigit():
            return NodeRef(point.substructure, {"node": int(node)}), comp
    if isinstance(where, Mapping) and "component" in where:
        return NodeRef(point.substructure, {k: v for k, v in where.items()
                                            if k != "component"}), str(where["component"])
    raise case.error(loc, "terms of a link's mpc are node components of frames, solids and "
                     "Nastran models; use constraints: for other points", text)


def _face(case: Any, face: FaceSpec, subs: Mapping[str, Substructure], weights: Any,
          loc: tuple) -> tuple[list[NodeRef], list[float] | None]:
    """The nodes of a ``face:`` and their weights (``None``: uniform; ``area``: tributary
    areas, :mod:`substruct.assembly.faces`)."""
    spec = case.substructure(face.part)
    if spec is None or face.part not in subs:
        raise case.error(loc + ("part",), f"unknown substructure {face.part!r}", face.part)
    if not isinstance(spec, (SolidSpec, NastranSpec)):
        raise case.error(loc + ("part",), "a face is taken from a solid or a Nastran model",
                         face.part)
    sub = subs[face.part]
    try:
        picked = face_nodes(sub, region_of(face.region()))
        if picked.size == 0:
            raise ValueError("the region holds no node of the part")
        refs = face_node_refs(sub, picked)
        w = tributary_areas(sub, picked).tolist() if weights == "area" else None
    except ValueError as err:
        raise case.error(loc, str(err), face.region()) from None
    return refs, w


def _yaml_link(case: Any, k: int, spec: Any, subs: Mapping[str, Substructure],
               points: Mapping[str, PointRef]) -> Link:
    name = spec.name or f"link{k + 1}"
    loc = ("links", k)
    try:
        if isinstance(spec, RigidLinkSpec):
            if spec.face is not None:
                deps, _ = _face(case, spec.face, subs, None, loc + ("face",))
            else:
                deps = [link_node(case, d, loc + ("dependents", j))
                        for j, d in enumerate(spec.dependents or [])]
            return rigid_link(subs, link_node(case, spec.independent, loc + ("independent",)),
                              deps, spec.components, name)
        if isinstance(spec, InterpolationLinkSpec):
            weights = spec.weights if isinstance(spec.weights, list) else None
            if spec.face is not None:
                nodes, weights = _face(case, spec.face, subs, spec.weights, loc + ("face",))
            else:
                nodes = [link_node(case, d, loc + ("nodes", j))
                         for j, d in enumerate(spec.nodes or [])]
            return interpolation_link(
                subs, link_node(case, spec.reference, loc + ("reference",)), nodes,
                weights, spec.components, spec.node_components, name)
        terms = [(*_term(case, p, points[p], loc + ("terms", p)), float(a))
                 for p, a in spec.terms.items()]
        return mpc(subs, terms, name)
    except (LinkError, PointError) as err:
        field = {"rigid": "dependents", "interpolation": "nodes", "mpc": "terms"}[spec.type]
        if getattr(spec, "face", None) is not None:
            field = "face"
        raise case.error(loc + (field,), str(err).split(": ", 1)[-1]) from None


def case_links(case: Any, subs: Sequence[Substructure], points: Mapping[str, PointRef]
               ) -> tuple[list[Substructure], list[LinearConstraint]]:
    """The rows of every link of ``case`` and its substructures after AUTOSPC.

    Args:
        case: the validated case.
        subs: its substructures (Nastran models without AUTOSPC yet).
        points: every point of the case, resolved.

    Raises:
        CaseError: a link that cannot be made, or a coordinate dependent in two links (naming
            the ``links`` item, or the bulk data card).
    """
    by_name = {s.name: s for s in subs}
    links: list[Link] = []
    origin: dict[str, Any] = {}
    for spec in case.substructures:
        if isinstance(spec, NastranSpec) and spec.name in by_name:
            from substruct.builder.nastran import bulk_error, bulk_links  # Nastran: when used

            try:
                made = bulk_links(spec.name, spec.bulk, by_name)
            except BdfError as err:
                raise bulk_error(case, spec, err) from None
            for link, line, card, ident in made:
                links.append(link)
                origin[link.name] = (spec, line, card, ident)
    for k, spec in enumerate(case.links):
        link = _yaml_link(case, k, spec, by_name, points)
        links.append(link)
        origin[link.name] = k
    try:
        rows = link_constraints(links)
    except LinkError as err:
        name = next((n for n in origin if str(err).startswith(f"{n}: ")), None)
        text = str(err)[len(name) + 2:] if name else str(err)
        where = origin.get(name) if name else None
        if isinstance(where, tuple):
            from substruct.builder.nastran import bulk_error

            spec, line, card, ident = where
            raise bulk_error(case, spec, BdfError(spec.bulk.source, text, line=line, card=card,
                                                  ident=ident)) from None
        raise case.error(("links", where if where is not None else 0), text) from None
    refs = [(t.substructure, t.where) for r in rows for t, c in r.terms if c != 0.0]
    refs += [(p.substructure, p.where) for p in points.values()]
    out = []
    for sub in subs:
        spec = case.substructure(sub.name)
        if isinstance(spec, NastranSpec) and spec.bulk.autospc:
            from substruct.builder.nastran import autospc, used_columns

            sub = autospc(sub, used_columns(sub, refs))
        out.append(sub)
    return out, rows
