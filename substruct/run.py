r"""From a validated case to a :class:`~substruct.result.Result`: build, couple, analyse.

Data flows one way (DESIGN.md section 3):

1. :func:`build_model` makes the substructures of the case (rods by assumed modes or finite
   elements with a node at every point the case names, ``nodes_at``; optional modal truncation,
   eqs 21-22; spring-mass-damper systems, eqs 17-20; matrices), resolves every point
   ``"sub@where"`` to a row ``u(point) = r @ q``, and stacks everything with the compatibility
   rows (eq 24) and the user constraints (eqs 41, 52) into ``A u = b + R F``
   (:func:`substruct.assembly.assemble`).
2. :func:`run_case` computes the coupled modes (eqs 28-34) with the main formulation and the
   check formulations, the variants (the same assembly with some constraint rows dropped), and
   the receptances (eqs 11-15) at the requested inputs and outputs:

   .. math::  H[k, i, j] = o_i \, \hat H(\omega_k)\, e_j, \qquad e_j = r(p_j)^T, \; o_i = r(p_i)

   (a unit force at point ``p_j`` is the generalized force ``r(p_j)^T``).  Its constraint
   residual is :math:`\max |A \hat q - R E| / \max |H|` over all frequencies.

Every problem with the input found on the way is a :class:`~substruct.case.CaseError` naming
the field of the case file.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, replace
from datetime import datetime, timezone
from typing import Any, Callable, NamedTuple, Sequence

import numpy as np
import scipy.sparse as sp

from substruct.assembly import Assembly, Connection, LinearConstraint, PointRef, assemble
from substruct.case import (Case, DiscreteSpec, FiniteElements, MatrixSpec, RodSpec,
                            parse_point)
from substruct.case_fields import gigabytes
from substruct.case_solids import SolidSpec
from substruct.case_substructures import MassSpec, SpringSpec
from substruct.constraints import ConstraintError, independent_rows
from substruct.coupling import receptance
from substruct.expressions import ExpressionError, scalar
from substruct.modes import Modes, coupled_modes, modes_agreement
from substruct.models.discrete import fixed_free, free_free, point_mass, spring
from substruct.models.rod import rod_assumed_modes, rod_fe
from substruct.reduction import modal_truncation
from substruct.result import Drawing, FrfResult, ModelInfo, ModeResult, Result
from substruct.run_solids import (build_solid, modes_solver, solid_where, sparse_mode_result,
                                  tie_and_reduce)
from substruct.substructure import Geometry, PointError, Substructure, as_csr

__all__ = ["Model", "build_model", "run_case", "Progress"]

#: ``progress(done, total, label)``, called during frequency sweeps.
Progress = Callable[[int, int, str], None]

#: Largest number of stacked coordinates for the dense coupled eigenproblem.
DENSE_MODES_LIMIT = 2500
#: Largest number of coordinates for the dense null-space receptance check.
DENSE_FRF_LIMIT = 4000
#: Largest constraint matrix (entries) whose consistency is checked densely before computing.
CONSISTENCY_LIMIT = 5_000_000
#: Frequencies per receptance call in a sweep (progress is reported between calls).
CHUNK = 10


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


@dataclass
class _PointUse:
    text: str
    loc: tuple


# ---------------------------------------------------------------------------- points


def _point_uses(case: Case) -> list[_PointUse]:
    """Every point of the case with the location of its field."""
    uses = []
    for i, chain in enumerate(case.connections):
        uses += [_PointUse(p, ("connections", i, j)) for j, p in enumerate(chain)]
    for k, con in enumerate(case.constraints):
        if not con.active:
            continue
        uses += [_PointUse(p, ("constraints", k, "terms", p)) for p in con.terms]
        uses += [_PointUse(p, ("constraints", k, "rhs_force", p)) for p in con.rhs_force]
    frf = case.analysis.frf
    if frf is not None:
        uses += [_PointUse(p, ("analysis", "frf", "inputs", i)) for i, p in enumerate(frf.inputs)]
        uses += [_PointUse(p, ("analysis", "frf", "outputs", i))
                 for i, p in enumerate(frf.outputs)]
    return uses


def _rod_position(case: Case, spec: RodSpec, where: str | None, use: _PointUse) -> float:
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


def _where(case: Case, spec: Any, where: str | None, use: _PointUse) -> Any:
    """What the substructure's locator understands for ``where``."""
    if isinstance(spec, RodSpec):
        return _rod_position(case, spec, where, use)
    if isinstance(spec, DiscreteSpec):
        return "boundary" if where is None else where
    if isinstance(spec, MassSpec):
        return "mass" if where is None else where
    if isinstance(spec, SpringSpec):
        if where is None and not spec.ground:
            raise case.error(use.loc, f"spring {spec.name!r} has two ends: write "
                             f"{spec.name}@i or {spec.name}@j", use.text)
        return "i" if where is None else where
    if isinstance(spec, SolidSpec):
        return solid_where(case, spec, where, use)
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


# ---------------------------------------------------------------------- substructures


def _matrices_substructure(spec: MatrixSpec) -> Substructure:
    labels = spec.dof_labels()
    n = len(labels)
    index = {lab: k for k, lab in enumerate(labels)}

    def locate(where: Any) -> sp.csr_array:
        if where not in index:
            raise PointError(f"{spec.name}: no coordinate {where!r}")
        return sp.csr_array(([1.0], ([0], [index[where]])), shape=(1, n))

    K = as_csr(spec.matrix("K"))
    return Substructure(name=spec.name, M=as_csr(spec.matrix("M")), K=K,
                        C=as_csr(spec.matrix("C"), n), dof_labels=tuple(labels),
                        locate=locate, kind="matrices", geometry=_chain_geometry(K, index),
                        meta={"n_dof": n})


def _chain_geometry(K: sp.csr_array, index: dict[str, int]) -> Geometry | None:
    """Coordinates drawn as nodes at ``x = 0, 1, ...`` moving along ``x``, joined by a line
    wherever ``K`` couples two of them (the springs of a lumped model)."""
    n = K.shape[0]
    if n > 2000 or K.nnz > 40000:
        return None
    coo = sp.coo_array(sp.triu(K, k=1))
    pairs = np.column_stack([coo.row, coo.col])[coo.data != 0].astype(int)
    linked = np.zeros(n, dtype=bool)
    linked[pairs.ravel()] = True
    cells = [("line", pairs)] if len(pairs) else []
    if not linked.all():
        cells.append(("vertex", np.flatnonzero(~linked).reshape(-1, 1)))
    points = np.column_stack([np.arange(n, dtype=float), np.zeros(n), np.zeros(n)])
    interp = sp.csr_array((np.ones(n), (3 * np.arange(n), np.arange(n))), shape=(3 * n, n))
    return Geometry(points=points, cells=cells, interp=interp, glyphs=dict(index))


def _rod(case: Case, i: int, spec: RodSpec, nodes_at: list[float]) -> Substructure:
    disc = spec.discretization
    try:
        if isinstance(disc, FiniteElements):
            sub = rod_fe(spec.name, spec.length, spec.EA_function, spec.m_function,
                         disc.elements, order=disc.order, support=spec.support,
                         nodes_at=nodes_at)
        else:
            sub = rod_assumed_modes(spec.name, spec.length, spec.EA_function, spec.m_function,
                                    disc.n, support=spec.support, mapping=disc.mapping,
                                    nodes_at=nodes_at)
    except ValueError as err:
        raise case.error(("substructures", i, "discretization"), str(err)) from None
    if spec.reduce is not None:
        damping = spec.reduce.damping.as_argument() if spec.reduce.damping else None
        try:
            sub = modal_truncation(sub, spec.reduce.modes, damping)
        except ValueError as err:
            raise case.error(("substructures", i, "reduce", "modes"), str(err),
                             spec.reduce.modes) from None
    return sub


def _substructures(case: Case, positions: dict[str, list[float]]) -> list[Substructure]:
    subs = []
    for i, spec in enumerate(case.substructures):
        if isinstance(spec, RodSpec):
            subs.append(_rod(case, i, spec, positions.get(spec.name, [])))
        elif isinstance(spec, DiscreteSpec):
            make = fixed_free if spec.type == "fixed-free" else free_free
            subs.append(make(spec.name, spec.mass, spec.stiffness, spec.damping))
        elif isinstance(spec, SpringSpec):
            subs.append(spring(spec.name, spec.stiffness, spec.damping, grounded=spec.ground))
        elif isinstance(spec, MassSpec):
            subs.append(point_mass(spec.name, spec.mass))
        elif isinstance(spec, SolidSpec):
            subs.append(build_solid(case, i, spec))
        else:
            subs.append(_matrices_substructure(spec))
    return subs


# ------------------------------------------------------------------------- drawings


def _lift(interp: sp.csr_array, offset: int, n_total: int) -> sp.csr_array:
    """Columns of a substructure's interpolation moved to its place in the stacked vector."""
    coo = sp.coo_array(interp)
    return sp.csr_array((coo.data, (coo.row, coo.col + offset)),
                        shape=(interp.shape[0], n_total))


def _is_rod(sub: Substructure) -> bool:
    return sub.kind.startswith("rod") or (sub.kind == "modal" and
                                          str(sub.meta.get("reduced_kind", "")).startswith("rod"))


def _place(sub: Substructure, where: Any, placed: dict[str, np.ndarray],
           shifts: dict[str, float] | None = None, scale: float = 1.0) -> np.ndarray | None:
    """Coordinates in space of a point of ``sub`` (``None`` if unknown); rods drawn shifted
    along ``x`` by ``shifts``, discrete systems ``scale`` times their local size."""
    if sub.position is not None:
        return np.asarray(sub.position(where), dtype=float)
    if sub.name in placed:  # a discrete system already placed
        g = sub.geometry
        if g is not None and isinstance(where, str) and where in g.glyphs:
            return g.points[g.glyphs[where]] * scale + placed[sub.name]
        return placed[sub.name]
    if _is_rod(sub):
        return np.array([float(where) + (shifts or {}).get(sub.name, 0.0), 0.0, 0.0])
    g = sub.geometry
    if g is not None and isinstance(where, str) and where in g.glyphs:
        return g.points[g.glyphs[where]]
    return None


def _rod_shifts(subs: dict[str, Substructure], connections: list[list[PointRef]],
                gap: float) -> dict[str, float]:
    """Where rods joined to each other (directly, or through a ``spring``) are drawn: one
    after the other along ``x``, the joined points together (or a spring length ``gap``
    apart), beyond the end of the first rod that its joined point is nearer to.  Other rods
    stay put."""
    rods = {name for name, s in subs.items() if _is_rod(s) and s.geometry is not None}
    links: list[tuple[PointRef, PointRef, float]] = []
    ends: dict[tuple[str, Any], PointRef] = {}
    for chain in connections:
        on_rods = [p for p in chain if p.substructure in rods]
        links += [(a, b, 0.0) for a, b in zip(on_rods, on_rods[1:])
                  if a.substructure != b.substructure]
        for p in chain:
            if subs[p.substructure].kind == "spring" and on_rods:
                ends.setdefault((p.substructure, p.where), on_rods[0])
    links += [(ends[(n, "i")], ends[(n, "j")], gap) for n, s in subs.items()
              if s.kind == "spring" and (n, "i") in ends and (n, "j") in ends
              and ends[(n, "i")].substructure != ends[(n, "j")].substructure]

    def span(name: str) -> tuple[float, float]:
        x = np.asarray(subs[name].geometry.points)[:, 0]
        return float(x.min()), float(x.max())

    shifts: dict[str, float] = {}
    todo = list(links)
    while todo:
        for a, b, g in todo:
            if (a.substructure in shifts) != (b.substructure in shifts):
                break
        else:  # no link touches a placed rod: the first rod of the next link stays put
            a, b, g = todo[0]
            shifts[a.substructure] = 0.0
        if b.substructure in shifts:
            a, b = b, a
        lo, hi = span(a.substructure)
        side = 1.0 if float(a.where) >= (lo + hi) / 2 else -1.0
        shifts[b.substructure] = shifts[a.substructure] + float(a.where) + side * g \
            - float(b.where)
        todo = [t for t in todo if not (t[0].substructure in shifts and
                                        t[1].substructure in shifts)]
    return shifts


def _spring_points(g: Geometry, ends: dict[str, np.ndarray], scale: float) -> np.ndarray:
    """A two-ended spring drawn from each connected end to where it is connected; an end
    connected to nothing at its local place, ``scale`` times, from the other end."""
    local = np.asarray(g.points, dtype=float) * scale
    if "i" in ends:
        anchor = ends["i"] - local[g.glyphs["i"]]
    elif "j" in ends:
        anchor = ends["j"] - local[g.glyphs["j"]]
    else:
        anchor = np.zeros(3)
    points = local + anchor
    for glyph, pos in ends.items():
        points[g.glyphs[glyph]] = pos
    return points


def _drawings(asm: Assembly, connections: list[list[PointRef]]) -> list[Drawing]:
    """Each substructure's geometry over the stacked coordinates; discrete systems are drawn
    at the point they are attached to, scaled to a tenth of the rest of the scene (a spring
    between two points from one to the other); rods joined end to end one after the other."""
    subs = {s.name: s for s in asm.substructures}
    discrete = {s.name for s in asm.substructures
                if s.kind in ("fixed-free", "free-free", "spring", "spring/grounded", "mass")}
    extent = 0.0
    for s in asm.substructures:
        if s.name not in discrete and s.geometry is not None and len(s.geometry.points):
            p = s.geometry.points
            extent = max(extent, float(np.ptp(p, axis=0).max()))
    scale = extent / 10 if extent > 0 else 1.0
    shifts = _rod_shifts(subs, connections, scale)
    placed: dict[str, np.ndarray] = {}
    axes: dict[str, int] = {}  # discrete systems on a displacement component of a solid
    ends: dict[str, dict[str, np.ndarray]] = {}
    for chain in connections:
        for p in chain:
            if p.substructure not in discrete or p.substructure in placed:
                continue
            for q in chain:
                if q.substructure == p.substructure:
                    continue
                pos = _place(subs[q.substructure], q.where, placed, shifts, scale)
                if pos is not None:
                    placed[p.substructure] = pos
                    axis = _component_axis(q.where)
                    if axis is not None:
                        axes[p.substructure] = axis
                    break
    for chain in connections:  # each end of a spring where it is connected
        for p in chain:
            if subs[p.substructure].kind != "spring" or p.where in ends.get(p.substructure, {}):
                continue
            for q in chain:
                pos = None if q.substructure == p.substructure else \
                    _place(subs[q.substructure], q.where, placed, shifts, scale)
                if pos is not None:
                    ends.setdefault(p.substructure, {})[p.where] = pos
                    axis = _component_axis(q.where)
                    if axis is not None:
                        axes[p.substructure] = axis
                    break
    out = []
    for k, s in enumerate(asm.substructures):
        g = s.geometry
        if g is None:
            continue
        points = np.array(g.points, dtype=float)
        interp = g.interp
        if s.name in axes:
            g = replace(g, points=_hang_along(points, axes[s.name]),
                        interp=_move_along(g.interp, axes[s.name]))
            points, interp = np.array(g.points, dtype=float), g.interp
        if s.kind == "spring":
            points = _spring_points(g, ends.get(s.name, {}), scale)
        elif s.name in discrete:
            points = points * scale + placed.get(s.name, np.zeros(3))
        elif s.name in shifts:
            points[:, 0] += shifts[s.name]
        out.append(Drawing(name=s.name, kind=s.kind, points=points,
                           cells=[(t, np.asarray(c)) for t, c in g.cells],
                           interp=_lift(interp, int(asm.offsets[k]), asm.n_dof),
                           glyphs=dict(g.glyphs)))
    return out


def _component_axis(where: Any) -> int | None:
    """The axis (0, 1, 2) of a point ``{"component": "z", ...}`` on a solid, else ``None``."""
    if not isinstance(where, dict) or "component" not in where:
        return None
    c = where["component"]
    return int(c) if isinstance(c, (int, np.integer)) else "xyz".index(str(c).lower())


def _hang_along(points: np.ndarray, axis: int) -> np.ndarray:
    """A discrete system's local drawing (hanging along ``-y``) turned to hang along
    ``-axis``, the direction it acts in on a solid."""
    out = np.zeros_like(points)
    out[:, axis] = points[:, 1]
    return out


def _move_along(interp: sp.csr_array, axis: int) -> sp.csr_array:
    """Rows of a discrete system's drawing ``interp`` moved from ``x`` (its local direction of
    motion) to ``axis``: on a solid it moves along the component it is attached to."""
    if axis == 0:
        return interp
    n_rows = interp.shape[0]
    order = np.arange(n_rows)
    base = order - order % 3
    swapped = np.where(order % 3 == 0, base + axis, np.where(order % 3 == axis, base, order))
    return sp.csr_array(interp[swapped])


# ---------------------------------------------------------------------------- model


def build_model(case: Case) -> Model:
    """Make the substructures, resolve the points and assemble ``A u = b + R F``.

    Raises:
        CaseError: a model too large for the dense eigenproblem (refused before building),
            a point off its substructure or on an unknown one, a reduction that cannot be
            made, constraints whose terms cancel, nonhomogeneous constraints that cannot hold.
    """
    _check_dense_sizes(case, _min_size(case))
    specs = {s.name: s for s in case.substructures}
    uses = _point_uses(case)
    resolved: dict[str, tuple[str, Any]] = {}
    positions: dict[str, list[float]] = {}
    for use in uses:
        sub, where = parse_point(use.text)
        if sub not in specs:
            raise case.error(use.loc, f"unknown substructure {sub!r} (known: "
                             f"{', '.join(specs)})", use.text)
        value = _where(case, specs[sub], where, use)
        resolved[use.text] = (sub, value)
        if isinstance(specs[sub], SolidSpec):
            positions.setdefault(sub, []).append(value)
        if isinstance(specs[sub], RodSpec):
            positions.setdefault(sub, [])
            if all(abs(value - x) > 1e-12 * specs[sub].length for x in positions[sub]):
                positions[sub].append(value)
    subs = _substructures(case, positions)
    subs, interface_ties = tie_and_reduce(case, subs, positions)
    by_name = {s.name: s for s in subs}
    points: dict[str, PointRef] = {}
    for use in uses:
        sub, value = resolved[use.text]
        try:
            by_name[sub].row(value)
        except (PointError, ValueError) as err:
            raise case.error(use.loc, str(err), use.text) from None
        points[use.text] = PointRef(sub, value)

    connections, chains = [], []
    for i, chain in enumerate(case.connections):
        refs = [points[p] for p in chain]
        chains.append(refs)
        for j in range(len(chain) - 1):
            connections.append(Connection(refs[j], refs[j + 1],
                                          name=f"{chain[j]} = {chain[j + 1]}"))
            _check_connection_row(case, by_name, refs[j], refs[j + 1], (i, j + 1), chain)
    constraints, active = [], []
    for con in case.constraints:
        if not con.active:
            continue
        constraints.append(LinearConstraint(
            terms=tuple((points[p], c) for p, c in con.terms.items()), rhs=con.rhs,
            force_terms=tuple((points[p], c) for p, c in con.rhs_force.items()),
            name=con.name))
        active.append(con.name)
    connections += interface_ties  # rows of A after the case's connections
    try:
        asm = assemble(subs, connections, constraints)
    except ValueError as err:
        name = str(err).split(":")[0]
        k = next((k for k, c in enumerate(case.constraints) if c.name == name), None)
        if k is None:
            raise case.error(("constraints",), str(err)) from None
        raise case.error(("constraints", k, "terms"), str(err),
                         dict(case.constraints[k].terms)) from None
    _check_consistent(case, asm, len(connections))
    _warn_free_springs(case)
    return Model(asm, active, _drawings(asm, chains), points)


def _check_connection_row(case: Case, by_name: dict[str, Substructure], a: PointRef,
                          b: PointRef, loc: tuple[int, int], chain: Sequence[str]) -> None:
    r"""Refuse a connection whose row ``r_a - r_b`` of ``A`` (eq 24) is empty.

    That is the same point twice (``[rod@0.5, rod@L/2]``) or two supported points: the
    "connection" joins nothing, which is a slip, and a user constraint with an empty row is
    refused likewise (:func:`substruct.assembly.assemble`).
    """
    ra = sp.csr_array(by_name[a.substructure].row(a.where))
    rb = sp.csr_array(by_name[b.substructure].row(b.where))
    same = a.substructure == b.substructure
    moves = ra.count_nonzero() > 0
    empty = (ra - rb).count_nonzero() == 0 if same else not (moves or rb.count_nonzero())
    if empty:
        i, j = loc
        what = "the same coordinate" if same and moves else "supported (they cannot move)"
        raise case.error(("connections", i, j), f"connects nothing: {chain[j - 1]} and "
                         f"{chain[j]} are {what}, so u({chain[j - 1]}) = u({chain[j]}) is "
                         f"an empty row of A", chain[j])


def _warn_free_springs(case: Case) -> None:
    """One line on stderr for each ``spring`` with an end that no connection or active
    constraint uses: the spring then carries no force (the solver sets its massless free end
    aside, an infinite root), which is almost always a modelling slip (not an error)."""
    used = set()
    for use in _point_uses(case):
        if use.loc[0] in ("connections", "constraints"):
            sub, where = parse_point(use.text)
            used.add((sub, "i" if where is None else where))
    for k, spec in enumerate(case.substructures):
        if not isinstance(spec, SpringSpec):
            continue
        free = [p for p in spec.points() if (spec.name, p) not in used]
        if free:
            ends = " and ".join(f"{spec.name}@{p}" for p in free)
            what = "is" if len(free) == 1 else "are"
            hint = ", or ground: true for a spring to ground" if free == ["j"] else ""
            message = case.error(("substructures", k), f"spring {spec.name!r}: {ends} {what} "
                                 f"in no connection or constraint, so the spring carries no "
                                 f"force (connect {'it' if len(free) == 1 else 'them'}{hint})")
            sys.stderr.write(f"substruct: warning: {message}\n")


def _check_consistent(case: Case, asm: Assembly, n_connections: int) -> None:
    r"""Refuse nonhomogeneous constraints that cannot hold, before anything is computed.

    A row of ``A`` that is a combination ``W`` of independent rows must have the same
    combination of right-hand sides (``b`` and ``R``):

    .. math::  A_d = W A_k \;\Rightarrow\; b_d = W b_k,\; R_d = W R_k

    (the check :func:`substruct.constraints.check_consistent` makes again when the receptances
    are computed; here it names the constraint in the case file).
    """
    A = asm.A
    m, N = A.shape
    if m == 0 or (asm.R.nnz == 0 and not np.any(asm.b)) or m * N > CONSISTENCY_LIMIT:
        return
    rows = independent_rows(A)
    if rows.dropped.size == 0:
        return
    labels = list(asm.constraint_labels)
    for field, rhs in (("rhs", asm.b.reshape(m, 1)), ("rhs_force", asm.R.toarray())):
        scale = max(float(np.abs(rhs).max()), 1e-300)
        err = np.abs(rhs[rows.dropped] - rows.combination @ rhs[rows.keep]).max(axis=1) / scale
        bad = np.flatnonzero(err > 1e-8)
        if bad.size:
            # the dependency  sum_r c_r A_r = 0  whose right-hand sides do not cancel
            c = np.zeros(m)
            c[rows.keep] = -rows.combination[bad[0]]
            c[rows.dropped[bad[0]]] = 1.0
            involved = np.flatnonzero(np.abs(c) > 1e-12 * np.abs(c).max())
            # blame the last user constraint involved (connections have no right-hand side)
            t = int(max(involved, key=lambda r: (r >= n_connections, r)))
            _inconsistent(case, field, labels, n_connections, t,
                          {int(r): -c[r] / c[t] for r in involved if r != t},
                          float(np.abs(c @ rhs).max() / abs(c[t]) / scale))


def _inconsistent(case: Case, field: str, labels: list[str], n_connections: int, t: int,
                  combination: dict[int, float], diff: float) -> None:
    """Raise the :class:`CaseError` for row ``t = sum combination[r] row r`` of ``A``."""
    terms = sorted(combination.items(), key=lambda kv: -abs(kv[1]))
    combo = " + ".join(f"{w:.4g} x ({labels[r]})" for r, w in terms[:3])
    combo += " + ..." if len(terms) > 3 else ""
    problem = (f"inconsistent constraints: the left-hand side of {labels[t]!r} is {combo}, "
               f"but its {field} is not the same combination (differs by {diff:.3g}, "
               f"relative)")
    if t < n_connections:
        raise case.error(("constraints",), problem)
    con = [c for c in case.constraints if c.active][t - n_connections]
    k = case.constraints.index(con)
    raise case.error(("constraints", k, field), problem,
                     dict(con.rhs_force) if field == "rhs_force" else con.rhs)


# --------------------------------------------------------------------------- analyses


def _mode_result(modes: Modes, agreement: dict[str, float]) -> ModeResult:
    return ModeResult(method=modes.method, eigenvalues=modes.eigenvalues, omega=modes.omega,
                      damping_ratio=modes.damping_ratio, shapes=modes.shapes,
                      residual=modes.residual, spurious=modes.spurious,
                      spurious_reason=list(modes.spurious_reason), agreement=agreement)


def _checks(main: str, check: Sequence[str]) -> list[str]:
    return [m for k, m in enumerate(check) if m != main and m not in check[:k]]


def _modes(case: Case, asm: Assembly, A: sp.csr_array, loc: tuple) -> ModeResult:
    spec = case.analysis.modes
    if modes_solver(case, asm.n_dof) == "sparse":
        return sparse_mode_result(case, asm, A, loc)
    try:
        main = coupled_modes(asm.M, asm.C, asm.K, A, spec.method, spec.count)
        agreement = {m: modes_agreement(coupled_modes(asm.M, asm.C, asm.K, A, m, spec.count),
                                        main)
                     for m in _checks(spec.method, spec.check)}
    except ValueError as err:
        raise case.error(loc, str(err)) from None
    return _mode_result(main, agreement)


def _min_size(case: Case) -> int:
    """A lower bound of the number of stacked coordinates, known before building."""
    total = 0
    for spec in case.substructures:
        n = spec.n_dof() if hasattr(spec, "n_dof") else None
        disc = getattr(spec, "discretization", None)
        if n is None and isinstance(disc, FiniteElements):
            n = max(disc.elements * disc.order - 1, 1)  # nodes less at most two supports
        total += n or 0
    return total


def _check_dense_sizes(case: Case, N: int, at_least: bool = True) -> None:
    """Refuse dense eigenproblems (and dense receptance checks) too large for the memory."""
    size = f"at least {N}" if at_least else f"{N}"
    if case.analysis.modes is not None and N > DENSE_MODES_LIMIT and \
            modes_solver(case, N) == "dense":
        need = 8 * 8 * (2 * N) ** 2  # dense state-space pencil, eigenvectors, workspace
        raise case.error(("analysis", "modes"), f"the coupled eigenproblem is dense and the "
                         f"model has {size} coordinates (about {gigabytes(need)}); at most "
                         f"{DENSE_MODES_LIMIT}: reduce the large substructures "
                         f"(reduce: {{modes: ...}}), or solver: sparse", N)
    frf = case.analysis.frf
    if frf is not None and "null-space" in (frf.method, *frf.check) and N > DENSE_FRF_LIMIT:
        raise case.error(("analysis", "frf", "check"), f"the null-space receptance is dense: "
                         f"{size} coordinates need about {gigabytes(16 * N * N * 3)}; at most "
                         f"{DENSE_FRF_LIMIT}: use kkt", N)


def _check_dense_modes(case: Case, asm: Assembly) -> None:
    _check_dense_sizes(case, asm.n_dof, at_least=False)


def _sweep(asm: Assembly, omegas: np.ndarray, R, method: str, E, O,
           progress: Progress | None, label: str) -> np.ndarray:
    out = []
    total = len(omegas)
    for start in range(0, total, CHUNK):
        w = omegas[start:start + CHUNK]
        out.append(receptance(asm.K, asm.M, asm.C, asm.A, w, R, method=method, inputs=E,
                              outputs=O, labels=asm.constraint_labels))
        if progress is not None:
            progress(min(start + CHUNK, total), total, label)
    return np.concatenate(out, axis=0)


def _frf(case: Case, model: Model, progress: Progress | None) -> FrfResult:
    spec = case.analysis.frf
    asm = model.assembly
    omegas = spec.omega.grid()
    E = sp.csc_array(asm.rows([model.points[p] for p in spec.inputs]).T)
    O_out = asm.rows([model.points[p] for p in spec.outputs])
    m = asm.A.shape[0]
    O = sp.csr_array(sp.vstack([O_out, asm.A])) if m else O_out
    R = asm.R if asm.R.nnz else None
    k_out = O_out.shape[0]
    try:
        full = _sweep(asm, omegas, R, spec.method, E, O, progress, spec.method)
        H = full[:, :k_out]
        scale = max(float(np.abs(H).max()), 1e-300)
        residual = 0.0
        if m:
            RE = (R @ E).toarray() if R is not None else np.zeros((m, E.shape[1]))
            residual = float(np.abs(full[:, k_out:] - RE[None]).max() / scale)
        agreement = {}
        for method in _checks(spec.method, spec.check):
            Hc = _sweep(asm, omegas, R, method, E, O_out, progress, method)
            agreement[method] = float(np.abs(Hc - H).max() / scale)
    except (ConstraintError, ValueError) as err:
        raise case.error(("analysis", "frf"), " ".join(str(err).split())) from None
    return FrfResult(method=spec.method, omega=omegas, H=H, inputs=list(spec.inputs),
                     outputs=list(spec.outputs), agreement=agreement,
                     constraint_residual=residual)


def _model_info(model: Model) -> ModelInfo:
    asm = model.assembly
    return ModelInfo(dof_labels=list(asm.dof_labels),
                     substructure_names=[s.name for s in asm.substructures],
                     substructure_kinds=[s.kind for s in asm.substructures],
                     offsets=np.asarray(asm.offsets), A=sp.csr_array(asm.A), b=np.asarray(asm.b),
                     R=sp.csr_array(asm.R), constraint_labels=list(asm.constraint_labels),
                     drawings=model.drawings)


def run_case(case: Case, progress: Progress | None = None, model: Model | None = None
             ) -> Result:
    """Run the analyses of a case.

    Args:
        case: a validated case (:func:`substruct.load_case`).
        progress: called as ``progress(done, total, label)`` during frequency sweeps.
        model: the case's model if already built (:func:`build_model`).

    Returns:
        The :class:`~substruct.result.Result`: modes (physical modes ascending, spurious roots
        set aside, agreement with the check formulations), variants, receptances, model data.

    Raises:
        CaseError: input that cannot be analysed (see :func:`build_model`; inconsistent
            constraints; a model too large for the dense eigenproblem).
    """
    from substruct import __version__

    model = build_model(case) if model is None else model
    asm = model.assembly
    _check_dense_modes(case, asm)
    attrs = {"substruct_version": __version__,
             "created": datetime.now(timezone.utc).isoformat(timespec="seconds"),
             "units": case.units, "description": case.description.strip(),
             "case_file": case.source, "overrides": "\n".join(case.overrides)}
    result = Result(case_name=case.name, case_yaml=case.text, model=_model_info(model),
                    attrs={k: v for k, v in attrs.items() if v})
    spec = case.analysis.modes
    if spec is not None:
        result.modes = _modes(case, asm, asm.A, ("analysis", "modes"))
        labels = list(asm.constraint_labels)
        for i, variant in enumerate(spec.variants):
            keep = [r for r, lab in enumerate(labels) if lab not in variant.drop]
            A = sp.csr_array(asm.A[keep]) if keep else sp.csr_array((0, asm.n_dof))
            result.variants[variant.name] = _modes(case, asm, A,
                                                   ("analysis", "modes", "variants", i))
    if case.analysis.frf is not None:
        result.frf = _frf(case, model, progress)
    return result
