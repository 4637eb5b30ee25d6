"""Case-file frames: ``type: frame``, 3D beams and flat shells between numbered nodes with six
coordinates each (:mod:`substruct.models.frame`).

.. code-block:: yaml

    - name: portal
      type: frame
      nodes: {1: [0, 0, 0], 2: [0, 0, 3], 3: [4, 0, 3], 4: [4, 0, 0]}
      materials: {steel: {E: 2.1e11, G: 8.1e10, rho: 7850}}
      sections: {ipe: {A: 2.85e-3, Iy: 1.94e-5, Iz: 1.42e-6, J: 7.0e-8}}
      members:
        - {nodes: [1, 2], section: ipe, material: steel, orientation: [1, 0, 0], divisions: 8}
      shells:
        - {nodes: [1, 2, 3, 4], thickness: 0.01, material: steel, divisions: [8, 4]}
      supports: {1: "123456", 4: "123456"}
      mass: consistent            # or lumped
      node_masses: {2: 50.0}      # a mass on the translations, or a 6 x 6 matrix

Points are ``portal@2:uy`` (node 2, component ``uy``; ``ux uy uz rx ry rz`` or ``1`` - ``6``).
What can be checked before assembly is checked here: references between nodes, sections and
materials, component sets, and the size (refused before anything is built).
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import Field, model_validator

from substruct.case.errors import FieldError
from substruct.case.fields import (
    MAX_ELEMENTS, Count, Id, Name, NonNegative, Number, Positive, StrictModel,
)

__all__ = ["FrameMaterial", "FrameSection", "FrameMember", "FrameShell", "FrameSpec",
           "MAX_FRAME_NODES"]

#: Most nodes (given and made by ``divisions``) a case frame may have: six coordinates each,
#: the same order as the largest rods.
MAX_FRAME_NODES = MAX_ELEMENTS

_DIGITS = "123456"
_NAMES = ("ux", "uy", "uz", "rx", "ry", "rz", "x", "y", "z")


def _component_problem(value: Any) -> str | None:
    """Why ``value`` is not a component set (``"123456"``, ``[ux, rz]``), or ``None``."""
    if isinstance(value, int) and not isinstance(value, bool):
        value = str(value)
    if isinstance(value, str):
        text = value.strip()
        items: list[Any] = list(text) if text.isdigit() else [text]
    elif isinstance(value, list):
        items = value
    else:
        return "components are a digit string such as '123456' or a list such as [ux, rz]"
    ok = [str(c).strip().lower() for c in items]
    if not ok or any(c not in _NAMES and c not in _DIGITS for c in ok) or \
            len(set(ok)) != len(ok):
        return "components are digits 1-6 or names ux uy uz rx ry rz, each once"
    return None


class FrameMaterial(StrictModel):
    """``{E, G, rho}``: Young's and shear moduli, density."""

    E: Positive
    G: Positive
    rho: Positive


class FrameSection(StrictModel):
    """``{A, Iy, Iz, J}`` and optional Timoshenko shear factors ``ky``, ``kz`` (5/6) and polar
    moment ``Ip`` (``Iy + Iz``) for the rotary inertia of torsion."""

    A: Positive
    Iy: Positive
    Iz: Positive
    J: Positive
    ky: Positive = 5.0 / 6.0
    kz: Positive = 5.0 / 6.0
    Ip: Positive | None = None


class FrameMember(StrictModel):
    """A member: end ``nodes``, ``section`` and ``material`` names, ``orientation`` vector,
    ``theory``, ``divisions`` and Nastran pin flags ``pin_a``/``pin_b``."""

    nodes: tuple[Id, Id]
    section: Name
    material: Name
    orientation: tuple[Number, Number, Number]
    theory: Literal["euler-bernoulli", "timoshenko"] = "euler-bernoulli"
    divisions: Count = 1
    pin_a: str = ""
    pin_b: str = ""

    @model_validator(mode="after")
    def _pins(self) -> "FrameMember":
        for key in ("pin_a", "pin_b"):
            value = getattr(self, key)
            if value.strip() and (not value.strip().isdigit() or
                                  _component_problem(value) is not None):
                raise FieldError(key, "pin flags are digits 1-6, each once (local "
                                 "components released at that end)", value)
        return self


class FrameShell(StrictModel):
    """A flat plate: 3 or 4 corner ``nodes`` in order around it, ``thickness``, ``material``
    (``nu = E / 2G - 1``), ``divisions`` (``[nx, ny]`` along sides 1-2 and 2-3, or one number
    for both; a triangle's are equal), a non-structural mass per area ``nsm`` and the plate
    theory of its ``bending``: ``kirchhoff`` (DKQ/DKT, the default) or ``mindlin`` (MITC4/
    MITC3, transverse shear stiffness 5/6 G t)."""

    nodes: Annotated[list[Id], Field(min_length=3, max_length=4)]
    thickness: Positive
    material: Name
    divisions: Count | tuple[Count, Count] = 1
    nsm: NonNegative = 0.0
    bending: Literal["kirchhoff", "mindlin"] = "kirchhoff"

    def counts(self) -> tuple[int, int]:
        """``(nx, ny)``."""
        d = self.divisions
        return (int(d), int(d)) if isinstance(d, int) else (int(d[0]), int(d[1]))

    def n_made(self) -> tuple[int, int]:
        """At most how many nodes and elements it makes."""
        nx, ny = self.counts()
        if len(self.nodes) == 4:
            return (nx + 1) * (ny + 1), nx * ny
        return (nx + 1) * (nx + 2) // 2, nx * nx


class FrameSpec(StrictModel):
    """A frame of 3D beams and shells (:func:`substruct.models.frame.frame`)."""

    name: Name
    type: Literal["frame"]
    nodes: Annotated[dict[Id, tuple[Number, Number, Number]], Field(min_length=1)]
    materials: Annotated[dict[Name, FrameMaterial], Field(min_length=1)]
    sections: dict[Name, FrameSection] = {}
    members: list[FrameMember] = []
    shells: list[FrameShell] = []
    supports: dict[Id, Any] = {}
    mass: Literal["consistent", "lumped"] = "consistent"
    node_masses: dict[Id, Any] = {}

    @model_validator(mode="after")
    def _references(self) -> "FrameSpec":
        if not self.members and not self.shells:
            raise FieldError("members", "a frame needs members or shells", [])
        made = sum(m.divisions - 1 for m in self.members) + \
            sum(s.n_made()[0] for s in self.shells)
        elements = sum(m.divisions for m in self.members) + \
            sum(s.n_made()[1] for s in self.shells)
        if len(self.nodes) + made > MAX_FRAME_NODES or elements > MAX_ELEMENTS:
            raise FieldError("members" if not self.shells else "shells",
                             f"up to {len(self.nodes) + made} nodes in {elements} elements; "
                             f"at most {MAX_FRAME_NODES} nodes and {MAX_ELEMENTS} elements "
                             f"are accepted", len(self.members) + len(self.shells))
        for k, sh in enumerate(self.shells):
            if sh.material not in self.materials:
                raise FieldError(("shells", k, "material"), f"no material of that name "
                                 f"(known: {', '.join(self.materials)})", sh.material)
            for node in sh.nodes:
                if node not in self.nodes:
                    raise FieldError(("shells", k, "nodes"), f"no node {node}", sh.nodes)
            if len(set(sh.nodes)) != len(sh.nodes):
                raise FieldError(("shells", k, "nodes"), "corners are different nodes",
                                 sh.nodes)
            nx, ny = sh.counts()
            if len(sh.nodes) == 3 and nx != ny:
                raise FieldError(("shells", k, "divisions"), "a triangle is divided equally "
                                 "along its sides (one number)", [nx, ny])
            mat = self.materials[sh.material]
            nu = mat.E / (2 * mat.G) - 1
            if not -1 < nu < 0.5:
                raise FieldError(("materials", sh.material), f"a shell's material needs "
                                 f"-1 < nu = E / 2G - 1 < 0.5, got nu = {nu:.4g}",
                                 mat.model_dump())
        for k, m in enumerate(self.members):
            for key, table in (("section", self.sections), ("material", self.materials)):
                if getattr(m, key) not in table:
                    raise FieldError(("members", k, key), f"no {key} of that name (known: "
                                     f"{', '.join(table)})", getattr(m, key))
            for node in m.nodes:
                if node not in self.nodes:
                    raise FieldError(("members", k, "nodes"), f"no node {node}", list(m.nodes))
            if m.nodes[0] == m.nodes[1]:
                raise FieldError(("members", k, "nodes"), "a member joins two different nodes",
                                 list(m.nodes))
        for where, held in (("supports", self.supports), ("node_masses", self.node_masses)):
            for at, value in held.items():
                if at not in self.nodes:
                    raise FieldError((where, at), f"no node {at}", value)
        for node, value in self.supports.items():
            problem = _component_problem(value)
            if problem is not None:
                raise FieldError(("supports", node), problem, value)
        return self

    def n_dof(self) -> None:
        """Known once built (supports and divisions decide it)."""
        return None
