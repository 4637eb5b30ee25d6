"""The kinds of substructure of a case, by their ``type`` tag, and which kind a substructure is.

Each kind's model lives in its own module (:data:`SUBSTRUCTURE_KINDS`), imported only when a
case has a substructure of that kind (:class:`~substruct.case.lazy_models.LazyUnion`): a rod
case does not define the schema of solids, frames, superelements, Nastran models, matrix files
or measured receptances.  The layers above tell the kinds apart with the functions here, which
read the tag (the model a tag selects is always the same class) instead of importing every
kind's class for an ``isinstance``; for the type checker they narrow as ``isinstance`` does.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, TypeGuard

if TYPE_CHECKING:
    from substruct.case.frames import FrameSpec
    from substruct.case.frf_substructure import FrfSpec
    from substruct.case.matrices import MatrixSpec
    from substruct.case.nastran import NastranSpec
    from substruct.case.solids import SolidSpec
    from substruct.case.superelements import SuperelementSpec

__all__ = ["SUBSTRUCTURE_KINDS", "LINK_TYPES", "is_solid", "is_frame", "is_superelement", "is_nastran",
           "is_matrices", "is_frf", "has_frf_parts"]

_SUBS = "substruct.case.substructures"

#: ``type`` tag -> (module, model) of every kind of substructure, in the order of the docs.
SUBSTRUCTURE_KINDS: dict[str, tuple[str, str]] = {
    "rod": (_SUBS, "RodSpec"),
    "fixed-free": (_SUBS, "DiscreteSpec"),
    "free-free": (_SUBS, "DiscreteSpec"),
    "spring": (_SUBS, "SpringSpec"),
    "mass": (_SUBS, "MassSpec"),
    "matrices": ("substruct.case.matrices", "MatrixSpec"),
    "solid": ("substruct.case.solids", "SolidSpec"),
    "frf": ("substruct.case.frf_substructure", "FrfSpec"),
    "frame": ("substruct.case.frames", "FrameSpec"),
    "superelement": ("substruct.case.superelements", "SuperelementSpec"),
    "nastran": ("substruct.case.nastran", "NastranSpec"),
}

#: The ``type`` tags of the links (:mod:`substruct.case.links`), for the case's error lines.
LINK_TYPES = ("rigid", "interpolation", "mpc")


def _tag(spec: Any) -> Any:
    return getattr(spec, "type", None)


def is_solid(spec: Any) -> TypeGuard[SolidSpec]:
    """Whether ``spec`` is a ``type: solid`` substructure."""
    return _tag(spec) == "solid"


def is_frame(spec: Any) -> TypeGuard[FrameSpec]:
    """Whether ``spec`` is a ``type: frame`` substructure."""
    return _tag(spec) == "frame"


def is_superelement(spec: Any) -> TypeGuard[SuperelementSpec]:
    """Whether ``spec`` is a ``type: superelement`` substructure."""
    return _tag(spec) == "superelement"


def is_nastran(spec: Any) -> TypeGuard[NastranSpec]:
    """Whether ``spec`` is a ``type: nastran`` substructure."""
    return _tag(spec) == "nastran"


def is_matrices(spec: Any) -> TypeGuard[MatrixSpec]:
    """Whether ``spec`` is a ``type: matrices`` substructure."""
    return _tag(spec) == "matrices"


def is_frf(spec: Any) -> TypeGuard[FrfSpec]:
    """Whether ``spec`` is a ``type: frf`` substructure."""
    return _tag(spec) == "frf"


def has_frf_parts(case: Any) -> bool:
    """Whether a substructure of the case is ``type: frf`` (its parts are coupled by their
    receptances: :mod:`substruct.builder.frf_parts`)."""
    return any(is_frf(s) for s in case.substructures)
