"""Case-file links: the ``links:`` block, rows of ``A`` that join nodes rigidly, by interpolation
or by any linear relation (:mod:`substruct.assembly.links`).

.. code-block:: yaml

    links:
      - type: rigid                  # RBE2
        independent: frame@5         # a node: part@<id> (frames, Nastran models), part@n12 or
        dependents: [box@n12, box@0.1,0,0.2]   # part@x,y,z (solids)
        components: "123456"         # of the dependent nodes (default all six)
      - type: interpolation          # RBE3
        reference: frame@7
        nodes: [box@n3, box@n4, box@n9]
        weights: [1, 1, 2]           # default all 1
        components: "123456"         # of the reference node
        node_components: "123"       # of the nodes (translations)
      - type: interpolation          # beam-to-solid: the nodes of a face of a solid
        reference: frame@1
        face: {part: box, box: [[0, -1, -1], [0, 1, 1]]}   # or plane: {point, normal},
        weights: area                # uniform (default) or area      # tolerance
      - type: rigid                  # a rigid spider onto a face
        independent: frame@2
        face: {part: box, plane: {point: [0, 0, 1], normal: [0, 0, 1]}}
      - type: mpc                    # sum a_k u_k = 0, the first term dependent
        terms: {frame@5:ux: 1.0, other@3:uy: -1.0}

Each item may have a ``name`` (``link<k>`` otherwise), used in messages and in the labels of its
rows.  What can be checked before the model is built is checked here: the syntax of nodes and
points, component sets, the counts of weights, unique names.  Nodes, positions and the rank of
an interpolation are checked on the built substructures (:mod:`substruct.builder.links`).
"""

from __future__ import annotations

from typing import Annotated, Any, Literal, Union

from pydantic import Field, model_validator

from substruct.case.errors import FieldError
from substruct.case.fields import (
    Name, NonNegative, Number, Point, Positive, StrictModel, parse_point,
)

__all__ = ["FaceSpec", "PlaneSpec", "RigidLinkSpec", "InterpolationLinkSpec", "MpcLinkSpec", "LinkSpec",
           "component_set", "link_nodes"]

_NAMES = ("ux", "uy", "uz", "rx", "ry", "rz")


def component_set(value: Any, translations_only: bool = False) -> str:
    """Nastran digits of a component set: ``"123456"``, ``12``, ``[ux, rz]``, ``all``.

    Raises:
        ValueError: anything else (an unknown or repeated component, an empty set).
    """
    if isinstance(value, bool):
        raise ValueError("components are digits 1-6 or names ux uy uz rx ry rz")
    if isinstance(value, int):
        value = str(value)
    if isinstance(value, str) and value.strip().lower() == "all":
        value = "123456"
    if isinstance(value, str):
        text = value.strip()
        items: list[Any] = list(text) if text.isdigit() else [text]
    elif isinstance(value, list):
        items = value
    else:
        raise ValueError("components are a digit string such as '123456' or a list such as "
                         "[ux, rz]")
    digits = []
    for c in items:
        t = str(c).strip().lower()
        t = "u" + t if t in ("x", "y", "z") else t
        d = str(_NAMES.index(t) + 1) if t in _NAMES else t
        if d not in "123456" or len(d) != 1:
            raise ValueError("components are digits 1-6 or names ux uy uz rx ry rz")
        digits.append(d)
    if not digits or len(set(digits)) != len(digits):
        raise ValueError("components are a non-empty set, each once")
    if translations_only and any(d > "3" for d in digits):
        raise ValueError("node components of an interpolation are translations (1-3)")
    return "".join(sorted(digits))


def _node(text: str) -> str:
    sub, where = parse_point(text)
    if not sub or not where:
        raise ValueError("a node is part@id (a frame or Nastran grid), part@n<k> or "
                         "part@x,y,z (a solid)")
    if ":" in where:
        raise ValueError("a node has no component (the link's components say which)")
    return text.strip()


Node = Annotated[Point, Field(description="part@node")]


class PlaneSpec(StrictModel):
    """A plane through ``point`` with normal ``normal``."""

    point: Annotated[list[Number], Field(min_length=3, max_length=3)]
    normal: Annotated[list[Number], Field(min_length=3, max_length=3)]

    @model_validator(mode="after")
    def _check(self) -> "PlaneSpec":
        if not any(self.normal):
            raise FieldError("normal", "the normal of a plane must not be zero", self.normal)
        return self


class FaceSpec(StrictModel):
    """The nodes of a face of a solid or Nastran ``part``: those in a ``box``, on a ``plane``
    (within ``tolerance``, the part's node tolerance by default), or both."""

    part: Name
    box: tuple[list[Number], list[Number]] | None = None
    plane: PlaneSpec | None = None
    tolerance: NonNegative | None = None

    @model_validator(mode="after")
    def _check(self) -> "FaceSpec":
        if self.box is None and self.plane is None:
            raise ValueError("a face needs a box: [[xmin, ymin, zmin], [xmax, ymax, zmax]] or "
                             "a plane: {point: [x, y, z], normal: [nx, ny, nz]} or both")
        if self.box is not None:
            lo, hi = self.box
            if len(lo) != 3 or len(hi) != 3 or any(a > b for a, b in zip(lo, hi)):
                raise FieldError("box", "a box is [[xmin, ymin, zmin], [xmax, ymax, zmax]] "
                                 "with min <= max", [list(lo), list(hi)])
        if self.tolerance is not None and self.plane is None:
            raise FieldError("tolerance", "a tolerance is the distance from a plane: give a "
                             "plane", self.tolerance)
        return self

    def region(self) -> dict[str, Any]:
        """The region as :func:`substruct.assembly.faces.region_of` takes it."""
        return {"box": None if self.box is None else [list(b) for b in self.box],
                "plane": None if self.plane is None else self.plane.model_dump(),
                "tolerance": self.tolerance}


class _Link(StrictModel):
    name: Name | None = None

    def check_nodes(self, nodes: list[tuple[Any, str]]) -> None:
        for key, text in nodes:
            try:
                _node(text)
            except ValueError as err:
                raise FieldError(key, str(err), text) from None

    def check_components(self, key: str, translations_only: bool = False) -> None:
        value = getattr(self, key)
        try:
            setattr(self, key, component_set(value, translations_only))
        except ValueError as err:
            raise FieldError(key, str(err), value) from None


class RigidLinkSpec(_Link):
    """A rigid link (RBE2): ``independent`` node, ``dependents`` and their ``components``."""

    type: Literal["rigid"]
    independent: Node
    dependents: Annotated[list[Node], Field(min_length=1)] | None = None
    face: FaceSpec | None = None
    components: Any = "123456"

    @model_validator(mode="after")
    def _check(self) -> "RigidLinkSpec":
        if (self.dependents is None) == (self.face is None):
            raise ValueError("a rigid link needs exactly one of dependents: [nodes] and "
                             "face: {part, box, plane}")
        if self.dependents is None:
            self.check_nodes([("independent", self.independent)])
            self.check_components("components")
            return self
        self.check_nodes([("independent", self.independent)] +
                         [(("dependents", j), d) for j, d in enumerate(self.dependents)])
        for j, d in enumerate(self.dependents):
            if d.replace(" ", "") == self.independent.replace(" ", "") or \
                    d.replace(" ", "") in [e.replace(" ", "") for e in self.dependents[:j]]:
                raise FieldError(("dependents", j), "a node appears twice in the link", d)
        self.check_components("components")
        return self


class InterpolationLinkSpec(_Link):
    """An interpolation link (RBE3): ``reference`` node fitted to ``nodes`` (``weights``)."""

    type: Literal["interpolation"]
    reference: Node
    nodes: Annotated[list[Node], Field(min_length=1)] | None = None
    face: FaceSpec | None = None
    weights: list[Positive] | Literal["uniform", "area"] | None = None
    components: Any = "123456"
    node_components: Any = "123"

    @model_validator(mode="after")
    def _check(self) -> "InterpolationLinkSpec":
        if (self.nodes is None) == (self.face is None):
            raise ValueError("an interpolation link needs exactly one of nodes: [nodes] and "
                             "face: {part, box, plane}")
        self.check_nodes([("reference", self.reference)] +
                         [(("nodes", j), d) for j, d in enumerate(self.nodes or [])])
        seen = [self.reference.replace(" ", "")]
        for j, d in enumerate(self.nodes or []):
            if d.replace(" ", "") in seen:  # as a rigid link's, and an RBE3's grids
                raise FieldError(("nodes", j), "a node appears twice in the link (or is the "
                                 "reference)", d)
            seen.append(d.replace(" ", ""))
        if isinstance(self.weights, list) and self.nodes is None:
            raise FieldError("weights", "the weights of a face are uniform or area",
                             self.weights)
        if self.weights == "area" and self.face is None:
            raise FieldError("weights", "area weights need a face: {part, box, plane}",
                             self.weights)
        if isinstance(self.weights, list) and len(self.weights) != len(self.nodes or []):
            raise FieldError("weights", f"one weight per node ({len(self.nodes or [])})",
                             self.weights)
        self.check_components("components")
        self.check_components("node_components", translations_only=True)
        return self


class MpcLinkSpec(_Link):
    """A multi-point constraint ``sum a_k u_k = 0``: ``terms`` point -> coefficient, the first
    dependent."""

    type: Literal["mpc"]
    terms: Annotated[dict[Point, Number], Field(min_length=1)]

    @model_validator(mode="after")
    def _check(self) -> "MpcLinkSpec":
        first = next(iter(self.terms))
        if self.terms[first] == 0:
            raise FieldError(("terms", first), "the first (dependent) coefficient must not "
                             "be zero", self.terms[first])
        return self


LinkSpec = Annotated[Union[RigidLinkSpec, InterpolationLinkSpec, MpcLinkSpec],
                     Field(discriminator="type")]


def link_nodes(link: Any) -> list[tuple[tuple, str]]:
    """``(loc, node text)`` of every node of a rigid or interpolation link (loc relative to the
    link)."""
    if isinstance(link, RigidLinkSpec):
        return [(("independent",), link.independent)] + \
            [(("dependents", j), d) for j, d in enumerate(link.dependents or [])]
    if isinstance(link, InterpolationLinkSpec):
        return [(("reference",), link.reference)] + \
            [(("nodes", j), d) for j, d in enumerate(link.nodes or [])]
    return []
