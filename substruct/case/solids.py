"""Case-file solids and the interfaces between them.

A ``type: solid`` substructure is a linear elastic body meshed from a file (``mesh:``, any file
meshio reads, relative to the case file) or generated (``box:`` in 3D, ``rectangle:`` in 2D),
discretized by :mod:`substruct.models.solid`; it may be reduced by modal truncation or by
Craig-Bampton (:mod:`substruct.models.craig_bampton`).  A top-level ``interfaces:`` item ties two
solids node to node (:func:`substruct.assembly.interfaces.tie_nodes`) or through interpolation
(:func:`substruct.assembly.interfaces.tie_nonmatching`).  See ``docs/case-files.md``, section Solids.

What can be checked before anything is read or assembled is checked here: one geometry,
material ranges, selectors, the mesh file before its data is read (a regular file, its size,
its format, the counts its header declares: :mod:`substruct.case.mesh_files`), and the size of
generated meshes (refused with a memory estimate, as rods are).  Meshes read from files are sized when they are
read (:mod:`substruct.builder.solids`), before they are assembled.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import (
    BeforeValidator,
    Field,
    PrivateAttr,
    ValidationInfo,
    model_validator,
)

from substruct.case.errors import FieldError
from substruct.case.fields import (
    MAX_COUNT,
    MAX_ELEMENTS,
    Count,
    Name,
    NonNegative,
    Number,
    Positive,
    StrictModel,
    gigabytes,
    memory_limit,
)
from substruct.case.mesh_files import MAX_MESH_FILE, mesh_file_problem
from substruct.case.substructures import ModalDamping

__all__ = ["Component", "Selector", "BoxShape", "RectangleShape", "SolidDamping",
           "SolidReduce", "SolidSpec", "InterfaceSpec", "solid_memory", "MAX_MESH_FILE",
           "MAX_ASPECT", "MIN_RELATIVE_SIZE"]

#: Displacement components of a solid.
Component = Literal["x", "y", "z"]

# Peak memory of a solid through a whole run (assembly, then the sparse coupled modes by the
# generalized-inverse and null-space paths with SuperLU), measured with 1 BLAS thread:
# 3D Q1 boxes 14.9k / 70k coordinates 0.28 / 2.27 GB, Q2 14.9k / 70k 0.43 / 2.35 GB (3D fill
# grows like n^(4/3): bytes per coordinate = c n^(1/3)); 2D Q1 20k / 81k 0.10 / 0.41 GB, Q2
# 20k / 81k 0.13 / 0.52 GB (about constant per coordinate).
_C3 = {1: 800.0, 2: 1200.0}
_C2 = {1: 6000.0, 2: 8000.0}


def solid_memory(n_dof: int, dim: int, order: int) -> float:
    """Estimated peak memory (bytes) to assemble a solid of ``n_dof`` coordinates and solve
    for its lowest coupled modes with sparse factorizations (measured, see above)."""
    n = float(max(n_dof, 1))
    per = _C3[order] * n ** (1 / 3) if dim == 3 else _C2[order]
    return n * per


def _no_bool(value: Any) -> Any:
    if isinstance(value, bool):
        raise ValueError("must be a number, not true/false")
    return value


# -------------------------------------------------------------------------- selectors


def _selector(value: Any) -> Any:
    if isinstance(value, str):
        return {"set": value}
    if not isinstance(value, dict):
        raise ValueError("a selector is a named set of the mesh ('clamp'), "
                         "{box: [[xmin, ymin, zmin], [xmax, ymax, zmax]], components: [x, y, z]} "
                         "or {set: name, components: [x, y, z]}")
    return value


class _SelectorModel(StrictModel):
    """Nodes of a solid: a named set of the mesh, or the nodes in a box; and components."""

    box: tuple[list[Number], list[Number]] | None = None
    set: Annotated[str, Field(min_length=1)] | None = None
    components: Annotated[list[Component], Field(min_length=1)] | None = None

    @model_validator(mode="after")
    def _one(self) -> "_SelectorModel":
        if (self.box is None) == (self.set is None):
            raise ValueError("give exactly one of box: [[xmin, ymin, zmin], [xmax, ymax, zmax]] "
                             "and set: name")
        if self.box is not None:
            lo, hi = self.box
            if len(lo) not in (2, 3) or len(hi) != len(lo):
                raise FieldError("box", "a box is [[xmin, ymin, zmin], [xmax, ymax, zmax]] "
                                 "(2 or 3 coordinates each)", [list(lo), list(hi)])
            for k, (a, b) in enumerate(zip(lo, hi)):
                if a > b:
                    raise FieldError("box", f"min > max in coordinate {'xyz'[k]}",
                                     [list(lo), list(hi)])
        if self.components is not None and len(set(self.components)) != len(self.components):
            raise FieldError("components", "a component is listed twice", self.components)
        return self

    def as_argument(self) -> dict[str, Any]:
        """The selector as :mod:`substruct.models.solid` and :mod:`substruct.assembly.interfaces`
        take it."""
        out: dict[str, Any] = ({"box": [list(self.box[0]), list(self.box[1])]}
                               if self.box is not None else {"set": self.set})
        if self.components is not None:
            out["components"] = list(self.components)
        return out

    def describe(self) -> str:
        """``set 'clamp'`` / ``box [[..], [..]]``, for messages."""
        if self.box is None:
            return f"set {self.set!r}"
        return f"box {[list(self.box[0]), list(self.box[1])]}"


#: ``'clamp'``, ``{set: clamp, components: [x]}`` or ``{box: [[..], [..]], components: [..]}``.
Selector = Annotated[_SelectorModel, BeforeValidator(_selector)]


# ------------------------------------------------------------------------- geometries


#: Largest ratio of the longest to the shortest side of a generated element.
MAX_ASPECT = 1e6
#: Smallest side of a generated element relative to its coordinates (it must stay far above
#: their rounding, 2.2e-16 of them).
MIN_RELATIVE_SIZE = 1e-6


def _check_grid(lengths: tuple[float, ...], divisions: tuple[int, ...],
                origin: tuple[float, ...]) -> None:
    """Refuse a generated mesh whose elements are degenerate: sides more than
    :data:`MAX_ASPECT` apart, or too small to be told apart at their coordinates (a box far
    from the origin for its size).  Checked before anything is meshed."""
    sides = [length / n for length, n in zip(lengths, divisions)]
    axes = "xyz"
    for k, (side, o, length) in enumerate(zip(sides, origin, lengths)):
        reach = max(abs(o), abs(o + length))
        if side < MIN_RELATIVE_SIZE * reach:
            raise FieldError("origin", f"elements of side {side:.3g} along {axes[k]} at "
                             f"coordinates up to {reach:.3g} cannot be told apart (a side must "
                             f"be at least {MIN_RELATIVE_SIZE:g} of the coordinates): move the "
                             f"origin closer", list(origin))
    if max(sides) > MAX_ASPECT * min(sides):
        longest, shortest = sides.index(max(sides)), sides.index(min(sides))
        raise FieldError("lengths", f"elements {max(sides) / min(sides):.3g} times longer along "
                         f"{axes[longest]} than along {axes[shortest]} (sides "
                         f"{max(sides):.3g} and {min(sides):.3g}; at most {MAX_ASPECT:g}): "
                         f"change the lengths or the divisions", list(lengths))


class BoxShape(StrictModel):
    """``{lengths: [lx, ly, lz], divisions: [nx, ny, nz], origin: [x0, y0, z0], cell: hex}``."""

    lengths: tuple[Positive, Positive, Positive]
    divisions: tuple[Count, Count, Count]
    origin: tuple[Number, Number, Number] = (0.0, 0.0, 0.0)
    cell: Literal["hex", "tet"] = "hex"

    @model_validator(mode="after")
    def _grid(self) -> "BoxShape":
        _check_grid(self.lengths, self.divisions, self.origin)
        return self

    def n_elements(self) -> int:
        n = math.prod(self.divisions)
        return 6 * n if self.cell == "tet" else n


class RectangleShape(StrictModel):
    """``{lengths: [lx, ly], divisions: [nx, ny], origin: [x0, y0], cell: quad}``."""

    lengths: tuple[Positive, Positive]
    divisions: tuple[Count, Count]
    origin: tuple[Number, Number] = (0.0, 0.0)
    cell: Literal["quad", "tri"] = "quad"

    @model_validator(mode="after")
    def _grid(self) -> "RectangleShape":
        _check_grid(self.lengths, self.divisions, self.origin)
        return self

    def n_elements(self) -> int:
        n = math.prod(self.divisions)
        return 2 * n if self.cell == "tri" else n


class SolidDamping(StrictModel):
    """``{rayleigh: [alpha, beta]}``: ``C = alpha M + beta K``."""

    rayleigh: tuple[NonNegative, NonNegative]


class SolidReduce(StrictModel):
    """``{modes: g}`` (modal truncation) or ``{method: craig-bampton, modes: g, interface: ..,
    interface_degree: p}`` (``p``: each interface reduced to polynomial fields of degree
    ``<= p``, :mod:`substruct.models.interface_basis`)."""

    method: Literal["modal", "craig-bampton"] = "modal"
    modes: Annotated[int, BeforeValidator(_no_bool), Field(ge=0, le=MAX_COUNT)]
    interface: Selector | list[Selector] | None = None
    interface_degree: Annotated[int, BeforeValidator(_no_bool),
                                Field(ge=0, le=12)] | None = None
    damping: ModalDamping | None = None

    @model_validator(mode="after")
    def _consistent(self) -> "SolidReduce":
        if self.method == "modal":
            if self.modes < 1:
                raise FieldError("modes", "modal truncation keeps at least 1 mode",
                                 self.modes)
            if self.interface is not None:
                raise FieldError("interface", "an interface is for method: craig-bampton "
                                 "(modal truncation keeps no boundary)")
            if self.interface_degree is not None:
                raise FieldError("interface_degree", "an interface basis is for method: "
                                 "craig-bampton (modal truncation keeps no boundary)",
                                 self.interface_degree)
            if self.damping is not None and isinstance(self.damping.ratio, list) and \
                    len(self.damping.ratio) != self.modes:
                raise FieldError(("damping", "ratio"), f"one damping ratio per kept mode: "
                                 f"{self.modes} needed", self.damping.ratio)
        elif self.damping is not None:
            raise FieldError("damping", "modal damping is for modal truncation; a "
                             "Craig-Bampton reduction projects the solid's damping: "
                             "{rayleigh: [alpha, beta]}")
        return self

    def selectors(self) -> list[_SelectorModel]:
        """The interface selectors (a list, possibly empty)."""
        if self.interface is None:
            return []
        return list(self.interface) if isinstance(self.interface, list) else [self.interface]


class SolidSpec(StrictModel):
    """A linear elastic solid from a mesh file, a box (3D) or a rectangle (2D)."""

    name: Name
    type: Literal["solid"]
    mesh: Annotated[str, Field(min_length=1)] | None = None
    box: BoxShape | None = None
    rectangle: RectangleShape | None = None
    E: Positive
    nu: Number
    rho: Positive
    order: Literal[1, 2] = 1
    plane: Literal["stress", "strain"] | None = None
    thickness: Positive | None = None
    fixed: list[Selector] = Field(default_factory=list)
    damping: SolidDamping | None = None
    reduce: SolidReduce | None = None
    #: the mesh once read: (what solid_from_mesh takes, the skfem mesh, named vertex sets)
    _mesh: Any = PrivateAttr(default=None)

    @model_validator(mode="after")
    def _check(self, info: ValidationInfo) -> "SolidSpec":
        given = [k for k in ("mesh", "box", "rectangle") if getattr(self, k) is not None]
        if not given:
            raise FieldError("mesh", "a solid needs its geometry: mesh: file, box: {lengths, "
                             "divisions} (3D) or rectangle: {lengths, divisions} (2D)")
        if len(given) > 1:
            raise FieldError(given[1], f"give only one of mesh, box (3D) and rectangle (2D); "
                             f"{given[0]} is given too", getattr(self, given[1]).model_dump()
                             if given[1] != "mesh" else self.mesh)
        if not -1.0 < self.nu < 0.5:
            raise FieldError("nu", "Poisson's ratio must lie in (-1, 0.5)", self.nu)
        if self.damping is not None and self.reduce is not None and \
                self.reduce.damping is not None:
            raise FieldError(("reduce", "damping"), "the kept modes' damping replaces the "
                             "solid's damping (rayleigh), which would be ignored: give one of "
                             "the two (without reduce.damping the Rayleigh damping is "
                             "projected on the modes)", "{...}")
        if self.box is not None:
            for key in ("plane", "thickness"):
                if getattr(self, key) is not None:
                    raise FieldError(key, f"{key} is for 2D solids (rectangle, or a 2D mesh)",
                                     getattr(self, key))
        if self.mesh is not None:
            base = Path((info.context or {}).get("base_dir", "."))
            path = base / self.mesh
            problem = mesh_file_problem(path)
            if problem == "no such mesh file":
                problem = f"no such mesh file ({path})"
            if problem is not None:
                raise FieldError("mesh", problem, self.mesh)
        else:
            self._size()
        return self

    def _size(self) -> None:
        shape = self.box if self.box is not None else self.rectangle
        if shape is None:  # a mesh file: sized when it is read
            return
        key = "box" if self.box is not None else "rectangle"
        dim = 3 if self.box is not None else 2
        elements = shape.n_elements()
        nodes = math.prod(int(self.order) * d + 1 for d in shape.divisions)
        need = solid_memory(dim * nodes, dim, self.order)
        if elements > MAX_ELEMENTS or need > memory_limit():
            raise FieldError((key, "divisions"), f"{elements} elements ({dim * nodes} "
                             f"coordinates) would need about {gigabytes(need)} of memory; at "
                             f"most {MAX_ELEMENTS} elements and the memory available on this "
                             f"machine are accepted", list(shape.divisions))

    def dim(self) -> int | None:
        """2 or 3; ``None`` for a mesh file not read yet."""
        if self.mesh is not None:
            return None if self._mesh is None else int(self._mesh[1].dim())
        return 3 if self.box is not None else 2

    def n_dof(self) -> int | None:
        """Number of coordinates after modal truncation; ``None`` if only known once meshed."""
        if self.reduce is not None and self.reduce.method == "modal":
            return self.reduce.modes
        return None


class InterfaceSpec(StrictModel):
    """Ties between two solids: each node of the first selected by ``nodes`` moves with the
    second at the same place (its node, or its interpolated displacement)."""

    name: Name | None = None
    between: tuple[Name, Name]
    nodes: Selector
    components: Annotated[list[Component], Field(min_length=1)] | None = None
    tolerance: Positive | None = None
    matching: bool = True

    @model_validator(mode="after")
    def _check(self) -> "InterfaceSpec":
        if self.between[0] == self.between[1]:
            raise FieldError("between", "an interface joins two different solids",
                             list(self.between))
        if self.nodes.components is not None:
            raise FieldError(("nodes", "components"), "give the components of an interface "
                             "beside nodes (components: [x, y, z]), not in the selector",
                             self.nodes.components)
        if self.components is not None and len(set(self.components)) != len(self.components):
            raise FieldError("components", "a component is listed twice", self.components)
        return self
