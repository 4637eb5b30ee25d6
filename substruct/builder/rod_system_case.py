"""A convergence study from a case file: the case's rod system as a :class:`RodSystemSpec`.

A convergence study (:mod:`substruct.studies.convergence`) refines one rod that carries spring-mass
attachments and homogeneous point constraints.  :func:`spec_from_case` reads that system out of a
validated case (:func:`substruct.case.loader.load_case`):

=============================================  ===============================================
case file                                      study
=============================================  ===============================================
the one ``type: rod`` substructure             ``RodSystemSpec(name, length, EA, m, support)``
                                               (its ``discretization`` is what the study
                                               varies, so it is not used)
``rod.reduce.modes``                           ``g`` of the fixed-``g`` series
a ``fixed-free``/``free-free`` substructure    an :class:`Attachment` at ``x``
connected at its boundary to ``rod@x``
an active constraint ``sum c_k u(rod@x_k) = 0``  a :class:`PointConstraint` (its ``name``)
``analysis.modes.count``                       ``n_modes`` (6 without ``analysis.modes``)
=============================================  ===============================================

Positions are resolved as ``substruct run`` resolves them (numbers, ``x=..``, expressions of
``L`` and the parameters such as ``rod@L/4``).  Whatever the study cannot represent is a
:class:`~substruct.case.loader.CaseError` naming the field and the value, one line: no rod or
several, a ``matrices`` substructure, modal damping of the rod, a discrete substructure that is not
attached to the rod (or attached twice, or at its mass when it has a separate boundary), a
connection that joins two rod points or no rod point, a constraint with a nonzero ``rhs``, with
``rhs_force`` terms, with a term off the rod, or whose terms cancel (inactive constraints are
left out, as ``substruct run`` leaves them out), a ``spring`` or ``mass`` substructure.
"""

from __future__ import annotations

from substruct.builder.points import PointUse, rod_position
from substruct.case.loader import Case, DiscreteSpec, MatrixSpec, RodSpec, parse_point
from substruct.case.substructures import MassSpec, SpringSpec
from substruct.builder.rod_system import Attachment, PointConstraint, RodSystemSpec

__all__ = ["spec_from_case", "DEFAULT_MODES"]

#: Modes studied when the case has no ``analysis.modes``.
DEFAULT_MODES = 6


def spec_from_case(case: Case) -> tuple[RodSystemSpec, int | None]:
    """The rod system of ``case`` and the ``g`` of its modal reduction.

    Args:
        case: a validated case.

    Returns:
        ``(spec, fixed_g)``: ``spec`` named ``case.name``; ``fixed_g`` is
        ``rod.reduce.modes``, or ``None`` if the rod is not reduced.

    Raises:
        CaseError: the case is not a rod with attachments and homogeneous point constraints
            (module docstring); one line naming the field and the value.
    """
    i_rod, rod = _the_rod(case)
    attachments = _attachments(case, rod)
    constraints = _constraints(case, rod)
    n_modes = case.analysis.modes.count if case.analysis.modes is not None else DEFAULT_MODES
    spec = RodSystemSpec(name=case.name, length=float(rod.length), EA=rod.EA_function,
                         m=rod.m_function, support=rod.support, attachments=attachments,
                         constraints=constraints, n_modes=int(n_modes))
    fixed_g = rod.reduce.modes if rod.reduce is not None else None
    return spec, fixed_g


# ------------------------------------------------------------------------------- the rod


def _the_rod(case: Case) -> tuple[int, RodSpec]:
    rods = [(i, s) for i, s in enumerate(case.substructures) if isinstance(s, RodSpec)]
    if not rods:
        types = [s.type for s in case.substructures]
        raise case.error(("substructures",), "a convergence study needs one substructure of "
                         "type rod, the case has none", types)
    if len(rods) > 1:
        i, second = rods[1]
        names = ", ".join(s.name for _, s in rods)
        raise case.error(("substructures", i, "type"), f"a convergence study refines one rod, "
                         f"the case has {len(rods)} ({names})", second.type)
    for i, s in enumerate(case.substructures):
        if isinstance(s, MatrixSpec):
            raise case.error(("substructures", i, "type"), "a convergence study refines a rod "
                             "with spring-mass attachments; a matrices substructure cannot be "
                             "refined", s.type)
        if isinstance(s, (SpringSpec, MassSpec)):
            raise case.error(("substructures", i, "type"), "a convergence study refines one "
                             "rod with fixed-free/free-free attachments; spring and mass "
                             "substructures are not supported by it (use substruct run with "
                             "rod discretizations of increasing size)", s.type)
    i, rod = rods[0]
    if rod.reduce is not None and rod.reduce.damping is not None:
        raise case.error(("substructures", i, "reduce", "damping"), "a convergence study "
                         "compares undamped rod models; modal damping of the rod has no finite-"
                         "element counterpart (remove it, e.g. --set "
                         f"substructures.{rod.name}.reduce.damping=null)",
                         rod.reduce.damping.model_dump(exclude_none=True))
    return i, rod


def _position(case: Case, rod: RodSpec, text: str, where: str | None, loc: tuple) -> float:
    return rod_position(case, rod, where, PointUse(text, loc))


# --------------------------------------------------------------------------- attachments


def _attachments(case: Case, rod: RodSpec) -> tuple[Attachment, ...]:
    discrete = {s.name: s for s in case.substructures if isinstance(s, DiscreteSpec)}
    known = ", ".join(s.name for s in case.substructures)
    at: dict[str, float] = {}
    for i, chain in enumerate(case.connections):
        on_rod: list[tuple[int, str | None]] = []
        attached: list[tuple[int, str]] = []
        for j, text in enumerate(chain):
            sub, where = parse_point(text)
            if sub == rod.name:
                on_rod.append((j, where))
            elif sub in discrete:
                _check_boundary(case, discrete[sub], where, (i, j), text)
                if sub in at or any(sub == name for _, name in attached):
                    raise case.error(("connections", i, j), f"{sub!r} is connected a second "
                                     "time; a convergence study attaches each discrete "
                                     "substructure at one rod point", text)
                attached.append((j, sub))
            else:
                raise case.error(("connections", i, j), f"unknown substructure {sub!r} "
                                 f"(known: {known})", text)
        if not on_rod:
            raise case.error(("connections", i), f"joins no point of rod {rod.name!r}; a "
                             "convergence study attaches every discrete substructure to the "
                             "rod", list(chain))
        if len(on_rod) > 1:
            j = on_rod[1][0]
            raise case.error(("connections", i, j), f"a second point of rod {rod.name!r} in "
                             "one connection; a convergence study cannot refine a rod joined "
                             "to itself", chain[j])
        j, where = on_rod[0]
        x = _position(case, rod, chain[j], where, ("connections", i, j))
        for _, name in attached:
            at[name] = x
    out = []
    for k, s in enumerate(case.substructures):
        if not isinstance(s, DiscreteSpec):
            continue
        if s.name not in at:
            raise case.error(("substructures", k), f"{s.type} substructure {s.name!r} is not "
                             f"connected to rod {rod.name!r} (a convergence study needs a "
                             f"connection such as [{rod.name}@x, {s.name}])", s.name)
        out.append(Attachment(s.name, at[s.name], s.type, float(s.mass), float(s.stiffness),
                              float(s.damping)))
    return tuple(out)


def _check_boundary(case: Case, spec: DiscreteSpec, where: str | None, loc: tuple[int, int],
                    text: str) -> None:
    """An attachment is joined to the rod at its boundary (the mass itself if fixed-free)."""
    allowed = (None, "boundary") + (("mass",) if spec.type == "fixed-free" else ())
    if where not in allowed:
        shown = f"{spec.name} or {spec.name}@boundary"
        raise case.error(("connections", *loc), f"a convergence study attaches {spec.type} "
                         f"substructure {spec.name!r} to the rod at its boundary ({shown})",
                         text)


# --------------------------------------------------------------------------- constraints


def _constraints(case: Case, rod: RodSpec) -> tuple[PointConstraint, ...]:
    out = []
    L = float(rod.length)
    fixed = [0.0] if rod.support.startswith("fixed") else []
    fixed += [L] if rod.support.endswith("fixed") else []
    for k, con in enumerate(case.constraints):
        if not con.active:
            continue
        if con.rhs != 0:
            raise case.error(("constraints", k, "rhs"), "a convergence study takes homogeneous "
                             "constraints only (rhs: 0): a constant right-hand side does not "
                             "enter the modes", con.rhs)
        if con.rhs_force:
            raise case.error(("constraints", k, "rhs_force"), "a convergence study takes "
                             "homogeneous constraints only (no rhs_force): force terms change "
                             "receptances, not the modes it compares", dict(con.rhs_force))
        terms: list[tuple[float, float]] = []
        for text, c in con.terms.items():
            sub, where = parse_point(text)
            loc = ("constraints", k, "terms", text)
            if sub != rod.name:
                raise case.error(loc, f"a convergence study takes constraints on points of rod "
                                 f"{rod.name!r} only", text)
            terms.append((_position(case, rod, text, where, loc), float(c)))
        if not _acts(terms, fixed, L):
            raise case.error(("constraints", k, "terms"), "its terms cancel or lie only at "
                             "fixed ends of the rod (an empty row)", dict(con.terms))
        out.append(PointConstraint(tuple(terms), con.name or f"constraint{k + 1}"))
    return tuple(out)


def _acts(terms: list[tuple[float, float]], fixed: list[float], L: float) -> bool:
    """Whether the terms, merged by position and without fixed ends, leave a nonzero row."""
    merged: dict[float, float] = {}
    tol = 1e-9 * L
    for x, c in terms:
        if any(abs(x - f) <= tol for f in fixed):
            continue
        key = next((y for y in merged if abs(y - x) <= tol), x)
        merged[key] = merged.get(key, 0.0) + c
    scale = max((abs(c) for _, c in terms), default=0.0)
    return any(abs(c) > 1e-14 * scale for c in merged.values())
