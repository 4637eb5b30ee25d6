"""How each substructure is drawn from the stacked coordinates: rods joined end to end one
after the other, discrete systems at the point they are attached to, springs between their ends,
frames with their beams as curves (:mod:`substruct.builder.frame_drawing`)."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np
import scipy.sparse as sp

from substruct.assembly.stack import Assembly, PointRef
from substruct.builder.drawing import Drawing
from substruct.models.selection import component_index
from substruct.substructure import Geometry, Substructure

__all__ = ["layout_drawings"]


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
        geometry = subs[name].geometry
        if geometry is None:  # rods without geometry are not linked
            return 0.0, 0.0
        x = np.asarray(geometry.points)[:, 0]
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


def layout_drawings(asm: Assembly, connections: list[list[PointRef]]) -> list[Drawing]:
    """Each substructure's geometry over the stacked coordinates; discrete systems are drawn
    at the point they are attached to, scaled to a tenth of the rest of the scene (a spring
    between two points from one to the other); rods joined end to end one after the other."""
    subs = {s.name: s for s in asm.substructures}
    discrete = {s.name for s in asm.substructures
                if s.kind in ("fixed-free", "free-free", "spring", "spring/grounded", "mass")}
    extent = 0.0
    for s in asm.substructures:
        if s.name not in discrete and s.geometry is not None and len(s.geometry.points):
            extent = max(extent, float(np.ptp(s.geometry.points, axis=0).max()))
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
        cells = [(t, np.asarray(c)) for t, c in g.cells]
        rotations = g.rotations
        if s.kind.startswith("frame"):  # beams drawn as curves bent by the end rotations
            from substruct.builder.frame_drawing import beam_curves

            points, cells, interp, rotations = beam_curves(s, points, cells, interp, rotations)
        out.append(Drawing(name=s.name, kind=s.kind, points=points, cells=cells,
                           interp=_lift(interp, int(asm.offsets[k]), asm.n_dof),
                           glyphs=dict(g.glyphs),
                           rotations=None if rotations is None else
                           _lift(rotations, int(asm.offsets[k]), asm.n_dof)))
    return out


def _component_axis(where: Any) -> int | None:
    """The axis (0, 1, 2) of a point ``{"component": "z", ...}`` on a solid, else ``None``."""
    if not isinstance(where, dict) or "component" not in where:
        return None
    return component_index(where["component"], 3, "a point")


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

