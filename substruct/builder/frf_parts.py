"""Substructures known by receptances (``type: frf``): the parts of a case that frequency-based
substructuring couples, and the rest of the case, which is built as usual.

An FRF substructure has no ``M``, ``C``, ``K`` and so cannot be a
:class:`~substruct.substructure.Substructure`.  A case with FRF substructures is therefore
split (:func:`split_frf_case`) into

* the finite-element case: every other substructure, the connections among them, and an
  ``analysis.frf`` whose inputs and outputs are the points of those substructures that the
  case uses (its own inputs and outputs and the points joined to FRF substructures), so that
  the model's receptance is square on them; none if every substructure is ``type: frf``
  (an FRF-only assembly: :func:`assemble_frf_case` gives an empty model);
* the FRF parts (:class:`FrfPart`, one per ``type: frf`` substructure; one with
  ``decouple: true`` enters with its receptance negated, so that coupling removes it) and
  the interface pairs of point names, each joining two coordinates.

:mod:`substruct.run.frf_route` computes the model's receptances, couples everything by
LM-FBS (:mod:`substruct.analysis.frf.coupling`) and reports the case's inputs and outputs.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

import numpy as np
import scipy.sparse as sp

from substruct.assembly.stack import Assembly
from substruct.builder.frf_part import FrfPart
from substruct.builder.model import Model, assemble_case
from substruct.builder.points import point_uses, resolve_point
from substruct.case.fields import parse_point
from substruct.case.frf_files import grid_problem
from substruct.case.frf_substructure import FrfSpec
from substruct.case.kinds import has_frf_parts
from substruct.case.loader import Case
from substruct.substructure import Substructure

__all__ = ["FrfPart", "FrfSplit", "MODEL_PART", "has_frf_parts", "split_frf_case",
           "frf_case_points", "assemble_frf_case", "empty_model"]

#: The name of the part that stands for the assembled finite-element model.
MODEL_PART = "model"


@dataclass(frozen=True)
class FrfSplit:
    """A case with FRF substructures, split (:func:`split_frf_case`).

    Attributes:
        model_case: the case of the other substructures (``analysis.frf`` square on
            ``model_points``); ``None`` if every substructure is ``type: frf``.
        model_points: the points of the model the coupling needs, in order.
        parts: the FRF parts, in case order.
        pairs: interface pairs of point names (each joins two coordinates).
    """

    model_case: Case | None
    model_points: list[str]
    parts: list[FrfPart]
    pairs: list[tuple[str, str]]


def frf_case_points(case: Case) -> tuple[list[str], list[str]]:
    """The case's ``analysis.frf`` inputs and outputs (empty if it has none)."""
    frf = case.analysis.frf
    return ([], []) if frf is None else (list(frf.inputs), list(frf.outputs))


def split_frf_case(case: Case) -> FrfSplit:
    """Split a case into the finite-element case, the FRF parts and the interface pairs.

    Raises:
        CaseError: modes asked of an assembly with FRF substructures; no ``analysis.frf``;
            a constraint on a point of an FRF substructure; a point of one that is not among
            its labels; a model none of whose points is joined or asked for.
    """
    frf_specs = {s.name: s for s in case.substructures if isinstance(s, FrfSpec)}
    if case.analysis.modes is not None:
        raise case.error(("analysis", "modes"), "the coupled modes of an assembly with FRF "
                         f"substructures ({', '.join(frf_specs)}) are not computed: ask for frf "
                         "only")
    spec = case.analysis.frf
    if spec is None:
        raise case.error(("analysis",), "an assembly with FRF substructures needs "
                         "analysis.frf")
    others = [s for s in case.substructures if not isinstance(s, FrfSpec)]

    def is_frf(point: str) -> bool:
        return parse_point(point)[0] in frf_specs

    for k, con in enumerate(case.constraints):
        for p in [*con.terms, *con.rhs_force]:
            if con.active and is_frf(p):
                raise case.error(("constraints", k, "terms", p), "a constraint cannot name a "
                                 "point of an FRF substructure: join it by a connection", p)
    pairs: list[tuple[str, str]] = []
    fe_chains: list[list[str]] = []
    for i, chain in enumerate(case.connections):
        for j, p in enumerate(chain):
            sub, where = parse_point(p)
            if sub in frf_specs and (where is None or where not in frf_specs[sub].dof_labels()):
                labels = frf_specs[sub].dof_labels()
                known = ", ".join(labels[:10]) + (", ..." if len(labels) > 10 else "")
                raise case.error(("connections", i, j), f"{sub} has no coordinate "
                                 f"{where!r} (it has {known})", p)
        for a, b in zip(chain[:-1], chain[1:]):
            if is_frf(a) or is_frf(b):
                pairs.append((a, b))
            else:
                fe_chains.append([a, b])
    specs = {s.name: s for s in case.substructures}
    for use in point_uses(case):  # the model's points, where the case names them
        sub, where = parse_point(use.text)
        if sub not in frf_specs:
            if sub not in specs:
                raise case.error(use.loc, f"unknown substructure {sub!r} (known: "
                                 f"{', '.join(specs)})", use.text)
            resolve_point(case, specs[sub], where, use)
    for where, points in (("inputs", spec.inputs), ("outputs", spec.outputs)):
        for i, p in enumerate(points):
            sub, lab = parse_point(p)
            if sub in frf_specs and lab not in frf_specs[sub].dof_labels():
                raise case.error(("analysis", "frf", where, i), f"{sub} has no coordinate "
                                 f"{lab!r}", p)
    needed = [p for pair in pairs for p in pair] + list(spec.inputs) + list(spec.outputs)
    model_points = list(dict.fromkeys(p for p in needed if not is_frf(p)))
    model_case = None
    if others:
        if not model_points:
            raise case.error(("connections",), "no point of the model is joined to the FRF "
                             "substructures or asked for")
        frf = spec.model_copy(update={"inputs": model_points, "outputs": model_points,
                                      "quantity": "receptance"})
        analysis = case.analysis.model_copy(update={"frf": frf})
        model_case = case.model_copy(update={"substructures": others,
                                             "connections": fe_chains, "analysis": analysis})
    parts = []
    grid = np.asarray(spec.omegas(), dtype=float)
    for k, s in enumerate(case.substructures):  # before any computation: grids agree
        if isinstance(s, FrfSpec):
            problem = grid_problem(s.name, s.measured()[0], grid, s.interpolate)
            if problem is not None:
                raise case.error(("substructures", k, "interpolate"), problem, s.interpolate)
    for s in frf_specs.values():
        omega, outs, ins, H = s.measured()
        parts.append(FrfPart(s.name, omega, outs, -H if s.decouple else H, s.interpolate,
                             s.decouple, None if ins is outs else ins))
    return FrfSplit(model_case, model_points, parts, pairs)


def empty_model() -> Model:
    """The finite-element model of an FRF-only assembly: no coordinates, no constraints."""
    empty = sp.csr_array((0, 0))
    asm = Assembly(substructures=[], offsets=np.zeros(1, dtype=int), M=empty, C=empty, K=empty,
                   A=empty, b=np.zeros(0), R=empty, constraint_labels=[], dof_labels=[])
    return Model(asm, [], [], {})


def assemble_frf_case(case: Case, prebuilt: Mapping[str, Substructure] | None = None
                      ) -> Model:
    """The finite-element part of a case with FRF substructures, assembled
    (:func:`substruct.builder.model.assemble_case` of :func:`split_frf_case`'s
    ``model_case``, with the ``prebuilt`` parts), or :func:`empty_model` if every
    substructure is ``type: frf``.

    Raises:
        CaseError: as :func:`split_frf_case` and :func:`~substruct.builder.model.assemble_case`.
    """
    model_case = split_frf_case(case).model_case
    return empty_model() if model_case is None else assemble_case(model_case, prebuilt)
