r"""From a validated case to an assembled :class:`Model`.

:func:`assemble_case` makes the substructures of the case (rods by assumed modes or finite
elements with a node at every point the case names, ``nodes_at``; optional modal truncation,
eqs 21-22; spring-mass-damper systems, eqs 17-20; matrices; solids), resolves every point
``"sub@where"`` to a row ``u(point) = r @ q``, and stacks everything with the compatibility rows
(eq 24) and the user constraints (eqs 41, 52) into ``A u = b + R F``
(:func:`substruct.assembly.stack.assemble`).

Every problem with the input found on the way is a :class:`~substruct.case.loader.CaseError`
naming the field of the case file.
"""

from __future__ import annotations

from typing import Any, Mapping, NamedTuple

from substruct.assembly.stack import (
    Assembly,
    Connection,
    LinearConstraint,
    PointRef,
    assemble,
)
from substruct.builder.checks import (
    check_connection_row,
    check_connections_consistent,
    warn_free_springs,
)
from substruct.builder.drawing import Drawing
from substruct.builder.drawings import layout_drawings
from substruct.builder.factory import make_substructures
from substruct.builder.points import PointUse, point_uses, resolve_point
from substruct.case.loader import Case, RodSpec, parse_point
from substruct.case.kinds import is_nastran, is_solid
from substruct.linalg.constraints import ConstraintError
from substruct.substructure import PointError, Substructure

__all__ = ["Model", "assemble_case", "point_positions"]


class Model(NamedTuple):
    """The assembled model of a case.

    Attributes:
        assembly: the stacked substructures and the constraint matrix ``A`` (rows: the
            connections, then the active user constraints).
        constraints: names of the active user constraints, in row order after the connections.
        drawings: how to draw each substructure from the stacked coordinates.
        points: every point of the case, resolved, by its text.
    """

    assembly: Assembly
    constraints: list[str]
    drawings: list[Drawing]
    points: dict[str, PointRef]


def point_positions(case: Case) -> tuple[list[PointUse], dict[str, tuple[str, Any]],
                                          dict[str, list[Any]]]:
    """Every point the case uses, resolved: ``(uses, {text: (substructure, where)},
    positions)``, ``positions[sub]`` the places used on each rod (distinct, in order of use:
    finite-element meshes put nodes there) and each solid.

    Raises:
        CaseError: a point on an unknown substructure or off its substructure.
    """
    specs = {s.name: s for s in case.substructures}
    uses = point_uses(case)
    resolved: dict[str, tuple[str, Any]] = {}
    positions: dict[str, list[Any]] = {}
    for use in uses:
        sub, where = parse_point(use.text)
        if sub not in specs:
            raise case.error(use.loc, f"unknown substructure {sub!r} (known: "
                             f"{', '.join(specs)})", use.shown or use.text)
        value = resolve_point(case, specs[sub], where, use)
        resolved[use.text] = (sub, value)
        spec = specs[sub]
        if is_solid(spec):
            positions.setdefault(sub, []).append(value)
        if isinstance(spec, RodSpec):
            positions.setdefault(sub, [])
            if all(abs(value - x) > 1e-12 * spec.length for x in positions[sub]):
                positions[sub].append(value)
    return uses, resolved, positions


def assemble_case(case: Case, prebuilt: Mapping[str, Substructure] | None = None) -> Model:
    """Make the substructures, resolve the points and assemble ``A u = b + R F``.

    Args:
        case: the validated case.
        prebuilt: substructures already made and reduced from this same definition
            (:func:`substruct.builder.parts.reduced_part`), by name: used instead of making
            and reducing them again (a study shares the parts its parameters do not change).

    Raises:
        CaseError: a model too large for the dense eigenproblem (refused before building),
            a point off its substructure or on an unknown one, a reduction that cannot be
            made, constraints whose terms cancel, nonhomogeneous constraints that cannot hold.
    """
    uses, resolved, positions = point_positions(case)
    subs = make_substructures(case, positions, prebuilt)
    solids = any(is_solid(s) for s in case.substructures)
    nastran = any(is_nastran(s) for s in case.substructures)
    interface_ties: list[Connection] = []
    if solids or case.interfaces:  # the solids' and the links' modules for cases with them
        from substruct.builder.solids import tie_and_reduce

        subs, interface_ties = tie_and_reduce(case, subs, positions, prebuilt)
    by_name = {s.name: s for s in subs}
    points: dict[str, PointRef] = {}
    for use in uses:
        sub, value = resolved[use.text]
        try:
            by_name[sub].row(value)
        except (PointError, ValueError) as err:
            raise case.error(use.loc, str(err), use.shown or use.text) from None
        points[use.text] = PointRef(sub, value)
    link_rows: list[LinearConstraint] = []
    if case.links or nastran:
        from substruct.builder.links import case_links

        subs, link_rows = case_links(case, subs, points)  # rows of A after the constraints
    by_name = {s.name: s for s in subs}

    connections, chains = [], []
    for i, chain in enumerate(case.connections):
        refs = [points[p] for p in chain]
        chains.append(refs)
        for j in range(len(chain) - 1):
            connections.append(Connection(refs[j], refs[j + 1],
                                          name=f"{chain[j]} = {chain[j + 1]}"))
            check_connection_row(case, by_name, refs[j], refs[j + 1], (i, j + 1), chain)
    constraints: list[LinearConstraint] = []
    active: list[str] = []
    for con in case.constraints:
        if not con.active:
            continue
        name = con.name or ""  # the loader names every constraint
        constraints.append(LinearConstraint(
            terms=tuple((points[p], c) for p, c in con.terms.items()), rhs=con.rhs,
            force_terms=tuple((points[p], c) for p, c in con.rhs_force.items()),
            name=name))
        active.append(name)
    connections += interface_ties  # rows of A after the case's connections
    try:
        asm = assemble(subs, connections, constraints + link_rows)
    except (ConstraintError, PointError) as err:  # any other ValueError is a bug
        name = str(err).split(":")[0]
        k = next((k for k, c in enumerate(case.constraints) if c.name == name), None)
        if k is None:
            raise case.error(("constraints",), str(err)) from None
        raise case.error(("constraints", k, "terms"), str(err),
                         dict(case.constraints[k].terms)) from None
    check_connections_consistent(case, asm, len(connections))
    warn_free_springs(case)
    spiders: list[Drawing] = []
    if case.links or nastran:
        from substruct.builder.frame_drawing import bulk_spiders, link_spiders

        spiders = link_spiders(case, asm) + bulk_spiders(case, asm)
    return Model(asm, active, layout_drawings(asm, chains) + spiders, points)
