"""The reduced substructures of a case made one by one, apart from the assembly.

A reduced substructure (a rod with ``reduce:``, modal truncation, eqs 21-22; a solid with
``reduce:``, modal truncation or Craig-Bampton) depends on its own specification and on the
points the case uses on it (finite-element nodes are put there; a Craig-Bampton boundary holds
them), and a solid tied by ``interfaces:`` on the ties too.  :func:`reduced_part` makes one
such part exactly as :func:`substruct.builder.model.assemble_case` would, so that it can be made
once, elsewhere (a Dask task), and given back to ``assemble_case(case, prebuilt=...)``: the
model is the same, bit for bit.
"""

from __future__ import annotations

from substruct.builder.factory import make_substructures
from substruct.builder.frf_parts import has_frf_parts, split_frf_case
from substruct.builder.model import point_positions
from substruct.builder.solids import tie_and_reduce
from substruct.case.loader import Case, RodSpec
from substruct.case.solids import SolidSpec
from substruct.substructure import Substructure

__all__ = ["reduced_names", "reduced_part"]


def reduced_names(case: Case) -> list[str]:
    """The substructures of ``case`` that are reduced (rods and solids with ``reduce:``)."""
    return [s.name for s in case.substructures
            if isinstance(s, (RodSpec, SolidSpec)) and s.reduce is not None]


def reduced_part(case: Case, name: str) -> Substructure:
    """The reduced substructure ``name`` of ``case``, as the assembled model holds it.

    A solid tied by an interface needs the other tied solids (unreduced) for its ties: they are
    made too, not reduced.  In a case with FRF substructures the part is made in the
    finite-element case the model is assembled from (:func:`substruct.builder.frf_parts.
    split_frf_case`).

    Raises:
        KeyError: ``name`` is not one of :func:`reduced_names`.
        CaseError: the part cannot be made or reduced (naming its field).
    """
    if name not in reduced_names(case):
        raise KeyError(f"{name!r} is not a reduced substructure of {case.name!r}")
    if has_frf_parts(case):  # the model is the finite-element part (builder.frf_parts)
        model_case = split_frf_case(case).model_case
        if model_case is None:
            raise KeyError(f"{case.name!r} has only FRF substructures")
        case = model_case
    _, _, positions = point_positions(case)
    spec = case.substructure(name)
    if isinstance(spec, RodSpec):
        return make_substructures(case, positions, only={name})[0]
    tied = {n for item in case.interfaces for n in item.between}
    need = {name} | (tied if name in tied else set())
    subs = make_substructures(case, positions, only=need)
    out, _ = tie_and_reduce(case, subs, positions, only={name})
    return next(s for s in out if s.name == name)
