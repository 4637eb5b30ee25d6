"""One mode drawn into a pyvista subplot: continua and shells warped over their grey
undeformed edges, rods and beams as tubes over their grey axis (beams bent by their end
rotations, :mod:`substruct.builder.frame_drawing`), links as thin spiders, attachments as
zigzag springs with their masses, walls at fixed ends; colour is ``|u| / max |u|`` of the mode throughout.

``pv`` (the pyvista module) and the plotter are passed in: pyvista is imported only by the
function that makes a picture (:func:`substruct.viz.mode_picture.plot_modes`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from substruct.builder.drawing import Drawing
from substruct.viz.layout import Layout, is_line_drawing, is_spring, view_normal

__all__ = ["CMAP", "INK", "GHOST", "draw_mode", "vtk_text", "zigzag", "line_segments"]

#: Colour map of ``|u| / max |u|``.
CMAP = "viridis"
#: Colour of text and markers.
INK = "#222222"
#: Colour of the undeformed model.
GHOST = "#b8b8b8"


def vtk_text(text: str) -> str:
    """Text safe for VTK's renderer, which splits on '|' (table columns) and parses '$...$'
    as math."""
    return text.replace("|", "\u00a6").replace("$", "\uff04")


def zigzag(a: np.ndarray, b: np.ndarray, plane_normal: np.ndarray, width: float,
           coils: int = 6) -> np.ndarray:
    """Points of a zigzag spring from ``a`` to ``b`` in the plane with ``plane_normal``."""
    axis = b - a
    length = float(np.linalg.norm(axis))
    if length == 0:
        return np.array([a, b])
    d = axis / length
    side_dir = np.cross(plane_normal, d)
    if np.linalg.norm(side_dir) < 1e-9:
        side_dir = np.cross([0.0, 0.0, 1.0] if abs(d[2]) < 0.9 else [1.0, 0.0, 0.0], d)
    side_dir = side_dir / np.linalg.norm(side_dir)
    s = np.concatenate([[0.0, 0.2], 0.2 + 0.6 * (np.arange(2 * coils) + 0.5) / (2 * coils),
                        [0.8, 1.0]])
    side = np.concatenate([[0, 0], np.tile([1.0, -1.0], coils), [0, 0]])
    return a + np.outer(s * length, d) + np.outer(side * width, side_dir)


def line_segments(cells: list[tuple[str, np.ndarray]]) -> np.ndarray:
    """Two-node segments of the line cells (a quadratic ``line3`` gives two)."""
    segs = []
    for cell_type, conn in cells:
        c = np.asarray(conn)
        if not cell_type.startswith("line") or c.size == 0:
            continue
        if c.shape[1] == 3:  # meshio/VTK order: end, end, middle
            segs += [c[:, [0, 2]], c[:, [2, 1]]]
        else:
            segs.append(c[:, :2])
    return np.vstack(segs) if segs else np.zeros((0, 2), int)


def _polyline(pv: Any, pts: np.ndarray) -> Any:
    n = len(pts)
    return pv.PolyData(pts, lines=np.concatenate([[n], np.arange(n)]))


def _line_mesh(pv: Any, pts: np.ndarray, cells: list[tuple[str, np.ndarray]],
               scalars: np.ndarray | None = None) -> Any:
    conn = line_segments(cells)
    if not len(conn):
        return None
    lines = np.hstack([np.full((len(conn), 1), 2), conn]).ravel()
    poly = pv.PolyData(pts, lines=lines)
    if scalars is not None:
        poly.point_data["|u|"] = scalars
    return poly.strip(join=True)


def _meshio_mesh(points: np.ndarray, cells: list[tuple[str, np.ndarray]]) -> Any:
    import meshio

    return meshio.Mesh(points, [(t, np.asarray(c)) for t, c in cells])


def draw_mode(pv: Any, plotter: Any, lay: Layout, pos: np.ndarray, mag: np.ndarray) -> None:
    """Draw one mode (display positions ``pos``, magnitudes ``mag`` from
    :func:`substruct.viz.layout.deformed`) into the plotter's current subplot."""
    size = lay.size
    m = lay.mesh
    kw = dict(cmap=CMAP, clim=(0.0, 1.0), show_scalar_bar=False)
    for i, d in enumerate(lay.drawings):
        sl = slice(m.point_offsets[i], m.point_offsets[i + 1])
        p0, p, s = lay.points[sl], pos[sl], mag[sl]
        if not is_line_drawing(d):
            faces = [(t, c) for t, c in d.cells if not t.startswith("line")]
            grid = pv.from_meshio(_meshio_mesh(p0, faces))
            plotter.add_mesh(grid.extract_all_edges(), color=GHOST, line_width=1, opacity=0.6)
            warped = grid.copy()
            warped.points = p
            warped.point_data["|u|"] = s
            plotter.add_mesh(warped, scalars="|u|", show_edges=True, edge_color="#404040",
                             line_width=0.5, smooth_shading=False, **kw)
            _draw_lines(pv, plotter, d, p0, p, s, size, kw)  # beams of a frame with shells
            continue
        if is_spring(d):
            _draw_spring(pv, plotter, d, p0, p, s, lay, kw)
            continue
        _draw_lines(pv, plotter, d, p0, p, s, size, kw)
        nodes = [np.ravel(c) for t, c in d.cells if t == "vertex"]
        if nodes:
            dots = pv.PolyData(p[np.unique(np.concatenate(nodes))])
            dots.point_data["|u|"] = s[np.unique(np.concatenate(nodes))]
            plotter.add_mesh(dots.glyph(geom=pv.Sphere(radius=0.02 * size), scale=False,
                                        orient=False), scalars="|u|", **kw)
        for name, node in d.glyphs.items():
            plotter.add_mesh(pv.Sphere(radius=0.014 * size, center=p[node]), color=INK)
        if d.kind == "matrices" and lay.axial is not None and d.glyphs:
            _label_coordinates(plotter, d, p0, lay)
        if lay.axial is not None:
            _draw_supports(pv, plotter, d, p0, lay, lay.axial)


def _draw_lines(pv: Any, plotter: Any, d: Drawing, p0: np.ndarray, p: np.ndarray,
                s: np.ndarray, size: float, kw: dict[str, Any]) -> None:
    """The line cells of a drawing (rods, beams, the legs of a link's spider) as tubes over
    their grey rest position; a link's legs thinner."""
    ghost = _line_mesh(pv, p0, d.cells)
    if ghost is None:
        return
    thin = 0.4 if d.kind == "link" else 1.0
    rest = ghost.tube(radius=0.0035 * size * thin, n_sides=12)
    if rest.n_points:  # not a link between coincident nodes
        plotter.add_mesh(rest, color=GHOST)
    curve = _line_mesh(pv, p, d.cells, s).tube(radius=0.008 * size * thin, n_sides=16)
    if curve.n_points:
        plotter.add_mesh(curve, scalars="|u|", **kw)


def _label_coordinates(plotter: Any, d: Drawing, p0: np.ndarray, lay: Layout) -> None:
    """The coordinate names of a lumped model (``P@q1``, ...) under its rest positions."""
    names = sorted(d.glyphs, key=d.glyphs.__getitem__)
    spots = np.array([p0[d.glyphs[n]] for n in names], dtype=float)
    spots[:, lay.transverse] -= 0.06 * lay.size
    plotter.add_point_labels(spots, [vtk_text(f"{d.name}@{n}") for n in names], font_size=12,
                             text_color="#333333", shape=None, show_points=False,
                             always_visible=True, justification_horizontal="center",
                             justification_vertical="top")


def _fixed(d: Drawing, node: int) -> bool:
    """Whether drawing node ``node`` cannot move (its interpolation rows are zero)."""
    m = d.interp.tocsr()
    rows = np.asarray(m.data[m.indptr[3 * node]:m.indptr[3 * node + 3]])
    return rows.size == 0 or not np.any(rows)


def _draw_supports(pv: Any, plotter: Any, d: Drawing, p0: np.ndarray, lay: Layout,
                   a: int) -> None:
    """A wall at each end of a line drawing that is held fixed (axial view along ``a``)."""
    t, size = lay.transverse, lay.size
    ends = {int(np.argmin(p0[:, a])): -1.0, int(np.argmax(p0[:, a])): 1.0}
    for node, outward in ends.items():
        if not _fixed(d, node):
            continue
        dims = np.full(3, 0.012 * size)
        dims[t] = 0.13 * size
        center = p0[node].copy()
        center[a] += outward * dims[a] / 2
        plotter.add_mesh(pv.Cube(center=center, x_length=dims[0], y_length=dims[1],
                                 z_length=dims[2]), color="#6b6b6b")
        for k in range(7):  # hatching
            start = p0[node].copy()
            start[a] += outward * dims[a]
            start[t] += (k / 6 - 0.5) * dims[t] * 0.92
            end = start.copy()
            end[a] += outward * 0.025 * size
            end[t] -= 0.025 * size
            plotter.add_mesh(pv.Line(start, end), color="#6b6b6b", line_width=1.5)


def _draw_spring(pv: Any, plotter: Any, d: Drawing, p0: np.ndarray, p: np.ndarray,
                 s: np.ndarray, lay: Layout, kw: dict[str, Any]) -> None:
    """A discrete attachment: zigzag springs, the ground, the mass (with its rest position as a
    grey ghost), its name in the axial view."""
    size = lay.size
    t = lay.transverse if lay.axial is not None else 1
    for a, b in line_segments(d.cells):
        zig = zigzag(p[a], p[b], view_normal(lay), 0.016 * size)
        plotter.add_mesh(_polyline(pv, zig).tube(radius=0.0022 * size, n_sides=8),
                         color="#555555")
    ground = d.glyphs.get("ground")
    if ground is not None:
        g = p[ground]
        dims = [0.05 * size] * 3
        dims[t] = 0.008 * size
        center = g.copy()
        center[t] -= dims[t] / 2
        plotter.add_mesh(pv.Cube(center=center, x_length=dims[0], y_length=dims[1],
                                 z_length=dims[2]), color="#6b6b6b")
    mass = d.glyphs.get("mass")
    if mass is not None:
        r = 0.03 * size
        plotter.add_mesh(pv.Sphere(radius=0.85 * r, center=p0[mass]), color=GHOST, opacity=0.6)
        ball = pv.Sphere(radius=r, center=p[mass], theta_resolution=24, phi_resolution=24)
        ball.point_data["|u|"] = np.full(ball.n_points, s[mass])
        plotter.add_mesh(ball, scalars="|u|", **kw)
    if lay.axial is not None and len(p0):
        low = p0[np.argmin(p0[:, t])].copy()
        low[lay.axial] += 0.04 * size
        if d.kind == "spring" and len(p0) == 2:  # beside the middle of a two-point spring
            low = p0.mean(axis=0)
            along = abs(p0[1] - p0[0])
            low[t if along[lay.axial] > along[t] else lay.axial] += \
                (-0.06 if along[lay.axial] > along[t] else 0.04) * size
        plotter.add_point_labels(low[None, :], [vtk_text(d.name)], font_size=11,
                                 text_color="#444444",
                                 shape=None, show_points=False, always_visible=True,
                                 justification_horizontal="left",
                                 justification_vertical="center")
    elif len(p0) > 1:  # a warped view: the name beside the far end (the mass or the ground)
        far = p0[-1] + 0.05 * size * np.array([0.0, 1.0, 0.0])  # to the right of it
        plotter.add_point_labels(far[None, :], [vtk_text(d.name)], font_size=12,
                                 text_color="#222222", shape=None, show_points=False,
                                 always_visible=True, justification_horizontal="left",
                                 justification_vertical="center")
    boundary = d.glyphs.get("boundary")
    if boundary is not None and boundary != mass:
        plotter.add_mesh(pv.Sphere(radius=0.014 * size, center=p[boundary]), color=INK)
