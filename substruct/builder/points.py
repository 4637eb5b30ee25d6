"""Points of a case resolved on their substructures: ``"sub@where"`` to what the
substructure's locator understands (a position on a rod, a coordinate label, a node of a solid)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from substruct.case.expressions import ExpressionError, scalar
from substruct.case.kinds import is_frame, is_nastran, is_solid, is_superelement
from substruct.case.loader import Case, DiscreteSpec, RodSpec
from substruct.case.substructures import MassSpec, SpringSpec

__all__ = ["PointUse", "point_uses", "rod_position", "resolve_point"]


@dataclass
class PointUse:
    """One place where a case names a point: the text (``"rod@200"``, ``"box@n12:z"``) and
    the location of its field (``("connections", 0, 1)``), for one-line errors."""

    text: str
    loc: tuple
    shown: str | None = None  # the text as written, when ``text`` adds to it (link nodes)


# ---------------------------------------------------------------------------- points


def point_uses(case: Case) -> list[PointUse]:
    """Every point of the case with the location of its field."""
    uses = []
    for i, chain in enumerate(case.connections):
        uses += [PointUse(p, ("connections", i, j)) for j, p in enumerate(chain)]
    for k, con in enumerate(case.constraints):
        if not con.active:
            continue
        uses += [PointUse(p, ("constraints", k, "terms", p)) for p in con.terms]
        uses += [PointUse(p, ("constraints", k, "rhs_force", p)) for p in con.rhs_force]
    frf = case.analysis.frf
    if frf is not None:
        uses += [PointUse(p, ("analysis", "frf", "inputs", i)) for i, p in enumerate(frf.inputs)]
        uses += [PointUse(p, ("analysis", "frf", "outputs", i))
                 for i, p in enumerate(frf.outputs)]
    tr = case.analysis.transient
    if tr is not None:
        uses += [PointUse(ld.point, ("analysis", "transient", "loads", i, "point"))
                 for i, ld in enumerate(tr.loads)]
        uses += [PointUse(p, ("analysis", "transient", "outputs", i))
                 for i, p in enumerate(tr.outputs)]
        if tr.base is not None:
            uses += [PointUse(p, ("analysis", "transient", "base", "at", i))
                     for i, p in enumerate(tr.base.at)]
        for key in ("displacement", "velocity"):
            uses += [PointUse(p, ("analysis", "transient", "initial", key, p))
                     for p in getattr(tr.initial, key) or {}]
    rnd = case.analysis.random
    if rnd is not None:  # analysis.random: force points, base supports, outputs
        uses += [PointUse(ld.at, ("analysis", "random", "forces", i, "at"))
                 for i, ld in enumerate(rnd.forces)]
        uses += [PointUse(p, ("analysis", "random", "base", "at", i))
                 for i, p in enumerate(rnd.base.at if rnd.base is not None else [])]
        uses += [PointUse(p, ("analysis", "random", "outputs", i))
                 for i, p in enumerate(rnd.outputs)]
        uses += [PointUse(p, ("analysis", "random", "bases", k, "at", i))
                 for k, b in enumerate(rnd.bases) for i, p in enumerate(b.at)]
    bfr = case.analysis.base_frf
    if bfr is not None:  # analysis.base_frf: base supports, outputs
        uses += [PointUse(p, ("analysis", "base_frf", "base", "at", i))
                 for i, p in enumerate(bfr.base.at if bfr.base is not None else [])]
        uses += [PointUse(p, ("analysis", "base_frf", "bases", k, "at", i))
                 for k, b in enumerate(bfr.bases) for i, p in enumerate(b.at)]
        uses += [PointUse(p, ("analysis", "base_frf", "outputs", i))
                 for i, p in enumerate(bfr.outputs)]
    if case.links:  # the links' module (and the solids' it uses) only for a case with links
        from substruct.builder.links import link_point_texts

        uses += [PointUse(text, loc, shown) for text, loc, shown in link_point_texts(case)]
    return uses


def rod_position(case: Case, spec: RodSpec, where: str | None, use: PointUse) -> float:
    """``x`` of a point on a rod: a number, ``x=..`` or an expression of ``L`` and parameters."""
    if where is None:
        raise case.error(use.loc, f"a point on rod {spec.name!r} needs a position, as in "
                         f"{spec.name}@{spec.length:g} or {spec.name}@L/2", use.text)
    text = where[2:] if where.startswith("x=") else where
    try:
        x = float(text)
    except ValueError:
        try:
            x = scalar(text, {**case.parameters, "L": float(spec.length)})
        except ExpressionError as err:
            raise case.error(use.loc, f"not a position on rod {spec.name!r}: {err}",
                             use.text) from None
    L = float(spec.length)
    if not math.isfinite(x) or x < -1e-9 * L or x > L * (1 + 1e-9):
        raise case.error(use.loc, f"point is not on rod {spec.name!r} [0, {L:g}]", use.text)
    return min(max(x, 0.0), L)


def resolve_point(case: Case, spec: Any, where: str | None, use: PointUse) -> Any:
    """What the substructure's locator understands for ``where``."""
    if isinstance(spec, RodSpec):
        return rod_position(case, spec, where, use)
    if isinstance(spec, DiscreteSpec):
        return "boundary" if where is None else where
    if isinstance(spec, MassSpec):
        return "mass" if where is None else where
    if isinstance(spec, SpringSpec):
        if where is None and not spec.ground:
            raise case.error(use.loc, f"spring {spec.name!r} has two ends: write "
                             f"{spec.name}@i or {spec.name}@j", use.text)
        return "i" if where is None else where
    if is_solid(spec):  # each kind's builder imported for a case that has it
        from substruct.builder.solids import solid_where

        return solid_where(case, spec, where, use)
    if is_frame(spec):
        from substruct.builder.frames import frame_where

        return frame_where(case, spec, where, use)
    if is_superelement(spec):
        from substruct.builder.superelements import superelement_where

        return superelement_where(case, spec, where, use)
    if is_nastran(spec):
        if where is None or ":" not in where:
            raise case.error(use.loc, f"a point on Nastran model {spec.name!r} is a grid and a "
                             f"component 1-6, as in {spec.name}@{min(spec.bulk.grids)}:3",
                             use.text)
        return where
    # matrices: a label, or a 1-based index
    if where is None:
        raise case.error(use.loc, f"a point on {spec.name!r} needs a coordinate, as in "
                         f"{spec.name}@{spec.dof_labels()[0]} or {spec.name}@1", use.text)
    labels = spec.dof_labels()
    if where in labels:
        return where
    try:
        k = float(where)
    except ValueError:
        k = math.nan
    if math.isfinite(k) and k == int(k) and 1 <= int(k) <= len(labels):
        return labels[int(k) - 1]
    shown = ", ".join(labels[:8]) + (" ..." if len(labels) > 8 else "")
    raise case.error(use.loc, f"{spec.name!r} has no coordinate {where!r} (labels: {shown}; "
                     f"or a 1-based index up to {len(labels)})", use.text)

