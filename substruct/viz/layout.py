"""How a model is laid out for a mode picture, and where a mode moves its points.

Rods carry *axial* displacement, which is invisible when drawn along the rod.  When the model
is made of line drawings only, all moving along one axis, and the longest of them lies along
it, the picture takes the *axial view*: the displacement ``u`` is drawn transversely, so a rod
becomes the curve ``(x, u(x))`` over its undeformed axis, and short attachment springs are
stretched to a readable length (schematic only).  Otherwise (solids, shells, mixed models) the
points are warped by their displacement vector.  Either way the largest displayed displacement
is :data:`SCALE_FRACTION` of the model size.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from substruct.builder.drawing import Drawing
from substruct.io.export import CombinedMesh, combined_mesh

__all__ = ["SCALE_FRACTION", "MIN_SPRING", "WARP_SPRING", "Layout", "layout", "deformed",
           "drawing_layout",
           "aligned", "is_line_drawing", "is_spring", "view_normal"]

#: The largest displayed displacement as a fraction of the model size.
SCALE_FRACTION = 0.15
#: Shortest displayed spring of an attachment in the axial view, as a fraction of model size.
MIN_SPRING = 0.2
#: In a warped view, attachments end this fraction of the model size outside the body.
WARP_SPRING = 0.12


def is_line_drawing(d: Drawing) -> bool:
    """Whether a drawing is made of points and line cells only (rods, springs)."""
    return all(t == "vertex" or t.startswith("line") for t, _ in d.cells)


def is_spring(d: Drawing) -> bool:
    """A discrete attachment (mass on a spring) rather than a continuum."""
    return is_line_drawing(d) and ("mass" in d.glyphs or d.kind in ("fixed-free", "free-free")
                                   or "spring" in d.kind)


def _moving_axes(d: Drawing) -> set[int]:
    """Displacement axes (0, 1, 2) the drawing can move along."""
    rows = np.unique(d.interp.tocoo().row) if d.interp.nnz else np.zeros(0, int)
    return set((rows % 3).tolist())


@dataclass
class Layout:
    """How the model is drawn: axial view (axis ``axial`` drawn along ``transverse``) or
    vector warp (``axial is None``).

    Attributes:
        mesh: the drawings combined into one point set.
        drawings: the drawings, in the order of ``mesh``.
        points: display positions of the undeformed points (springs stretched).
        size: the model size (largest extent), the unit of the displayed displacement.
        axial: axis of the axial displacement, or ``None`` (vector warp).
        transverse: axis the axial displacement is drawn along.
    """

    mesh: CombinedMesh
    drawings: list[Drawing]
    points: np.ndarray
    size: float
    axial: int | None
    transverse: int


def layout(drawings: list[Drawing]) -> Layout:
    """The layout of a model's drawings: axial view for rods moving along their axis (with
    their attachments), vector warp otherwise."""
    mesh = combined_mesh(drawings)
    pts = mesh.points.copy()
    extent = np.ptp(pts, axis=0) if len(pts) else np.zeros(3)
    size = float(np.max(extent)) or 1.0
    axial, transverse = None, 1
    lines = [d for d in drawings if is_line_drawing(d) and d.interp.nnz]
    comps: set[int] = set().union(*(_moving_axes(d) for d in lines)) if lines else set()
    if len(comps) == 1 and all(is_line_drawing(d) for d in drawings):
        e = comps.pop()
        longest = max(lines, key=lambda d: np.ptp(np.asarray(d.points), axis=0).max())
        span = np.ptp(np.asarray(longest.points), axis=0)
        if span.max() > 0 and span[e] >= 0.9 * span.max():
            axial, transverse = e, (1 if e != 1 else 0)
            axis_t = float(np.median(np.asarray(longest.points)[:, transverse]))
            _stretch_springs(drawings, mesh, pts, transverse, axis_t, size)
    else:
        _off_the_body(drawings, mesh, pts, size)
    return Layout(mesh, drawings, pts, size, axial, transverse)


def drawing_layout(drawings: Sequence[Drawing], n_coordinates: int, what: str) -> Layout:
    """The :func:`layout` of a result's drawings, checked to take vectors of ``n_coordinates``
    (``what``: the vectors drawn, for the message).

    Raises:
        ValueError: no drawings, or drawings of another number of coordinates.
    """
    if not drawings:
        raise ValueError("the model has no drawings (nothing to draw)")
    lay = layout(list(drawings))
    if lay.mesh.interp.shape[1] != n_coordinates:
        raise ValueError(f"drawings expect {lay.mesh.interp.shape[1]} coordinates, the {what} "
                         f"have {n_coordinates}")
    return lay


def _exit_length(p0: np.ndarray, direction: np.ndarray, lo: np.ndarray, hi: np.ndarray
                 ) -> float:
    """How far a ray from ``p0`` along the unit ``direction`` runs inside the box [lo, hi]."""
    if np.any(p0 < lo) or np.any(p0 > hi):
        return 0.0
    ts = [((hi[k] if direction[k] > 0 else lo[k]) - p0[k]) / direction[k]
          for k in range(3) if abs(direction[k]) > 1e-12]
    return float(min(ts)) if ts else 0.0


def _off_the_body(drawings: list[Drawing], mesh: CombinedMesh, pts: np.ndarray,
                  size: float) -> None:
    """In a warped (solid) view, hang each attachment (spring-mass, absorber) from its point
    out of the body, on the side where it leaves the body soonest, and long enough to end
    :data:`WARP_SPRING` of the model size outside it (schematic only: the direction of motion
    is that of the drawing's rows, unchanged)."""
    body = [i for i, d in enumerate(drawings) if not is_line_drawing(d)]
    if not body:
        return
    inside = np.vstack([pts[mesh.point_offsets[i]:mesh.point_offsets[i + 1]] for i in body])
    tol = 1e-6 * size
    lo, hi = inside.min(axis=0) - tol, inside.max(axis=0) + tol
    for i, d in enumerate(drawings):
        if not is_spring(d) or d.kind == "spring":
            continue
        p = pts[mesh.point_offsets[i]:mesh.point_offsets[i + 1]]
        offset = p[1:] - p[0]
        reach = float(np.max(np.linalg.norm(offset, axis=1))) if len(offset) else 0.0
        if reach == 0:
            continue
        direction = offset[-1] / max(float(np.linalg.norm(offset[-1])), 1e-300)
        down, up = _exit_length(p[0], direction, lo, hi), _exit_length(p[0], -direction, lo, hi)
        sign = -1.0 if up < down else 1.0
        length = max(reach, min(down, up) + WARP_SPRING * size)
        p[1:] = p[0] + sign * offset * (length / reach)


def _stretch_springs(drawings: list[Drawing], mesh: CombinedMesh, pts: np.ndarray, t: int,
                     axis_t: float, size: float) -> None:
    """In the axial view, give short attachment springs a readable length (schematic only).
    A ``spring`` between two points is left as placed: its ends are where it is connected."""
    for i, d in enumerate(drawings):
        if not is_spring(d) or d.kind == "spring":
            continue
        sl = slice(mesh.point_offsets[i], mesh.point_offsets[i + 1])
        p = pts[sl]
        anchor = int(np.argmin(abs(p[:, t] - axis_t)))
        offset = p[:, t] - p[anchor, t]
        reach = float(np.max(abs(offset)))
        if 0 < reach < MIN_SPRING * size:
            p[:, t] = p[anchor, t] + offset * (MIN_SPRING * size / reach)


def aligned(disp: np.ndarray) -> np.ndarray:
    r"""Real displacement of a complex mode, rotated to its most real phase, largest entry > 0.

    .. math::  u = \operatorname{Re}\left(e^{-i\theta} \hat u\right), \qquad
               \theta = \tfrac12 \arg \textstyle\sum_k \hat u_k^2
    """
    flat = disp.ravel()
    if not np.iscomplexobj(flat):
        real = flat.astype(float)
    else:
        theta = 0.5 * np.angle(np.sum(flat * flat))
        real = (flat * np.exp(-1j * theta)).real
    if real.size and real[np.argmax(abs(real))] < 0:
        real = -real
    return real.reshape(disp.shape)


def deformed(lay: Layout, shape: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Display positions and normalised magnitude ``|u| / max |u|`` of the points for one mode
    shape (coordinates of the model)."""
    u = aligned(lay.mesh.displacement(shape))
    if lay.axial is not None:
        ua = u[:, lay.axial]
        mag = abs(ua)
        peak = float(mag.max()) if mag.size else 0.0
        scale = SCALE_FRACTION * lay.size / peak if peak > 0 else 0.0
        pos = lay.points.copy()
        pos[:, lay.transverse] += scale * ua
    else:
        mag = np.linalg.norm(u, axis=1)
        peak = float(mag.max()) if mag.size else 0.0
        scale = SCALE_FRACTION * lay.size / peak if peak > 0 else 0.0
        pos = lay.points + scale * u
    return pos, (mag / peak if peak > 0 else mag)


def view_normal(lay: Layout) -> np.ndarray:
    """Direction the camera looks along (the axial view is planar; a warp is isometric)."""
    n = np.zeros(3)
    if lay.axial is None:
        return np.array([1.0, 1.0, 1.0]) / np.sqrt(3.0)
    n[({0, 1, 2} - {lay.axial, lay.transverse}).pop()] = 1.0
    return n
