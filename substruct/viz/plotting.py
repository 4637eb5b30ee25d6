"""Pictures of a result: mode shapes (pyvista, off-screen) and receptances (matplotlib).

Both work on a machine without a display and write their PNG atomically (temporary file in
the target directory, then rename).

**Mode shapes.** Each mode is drawn from the result's drawings, displaced by the real part of
the phase-aligned shape and scaled so that the largest displacement is 15 % of the model size.
Rods carry *axial* displacement, which is invisible when drawn along the rod.  When the model
is made of line drawings only, all moving along one axis, and the longest of them lies along
it, the picture switches to the *axial view*: the displacement ``u`` is drawn transversely, so
a rod becomes the curve ``(x, u(x))`` over its undeformed axis (grey), attachments hang below
it as springs with their masses raised or lowered by their own displacement, and the rest
positions of the masses are shown as grey ghosts.  Solids and shells are warped by their
displacement vector over their grey undeformed edges.  Colour is ``|u| / max |u|`` of the mode
throughout.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from substruct.builder.drawing import Drawing
from substruct.io.export import CombinedMesh, combined_mesh
from substruct.io.hdf5 import atomic_path
from substruct.run.result import ModeResult, Result

__all__ = ["plot_modes", "plot_frf", "SCALE_FRACTION"]

#: The largest displayed displacement as a fraction of the model size.
SCALE_FRACTION = 0.15
#: Shortest displayed spring of an attachment in the axial view, as a fraction of model size.
MIN_SPRING = 0.2

_CMAP = "viridis"
_INK = "#222222"
_GHOST = "#b8b8b8"


# ----------------------------------------------------------------------------- geometry


def _is_line_type(cell_type: str) -> bool:
    return cell_type == "vertex" or cell_type.startswith("line")


def _is_1d(d: Drawing) -> bool:
    return all(_is_line_type(t) for t, _ in d.cells)


def _components(d: Drawing) -> set[int]:
    """Displacement components (0, 1, 2) the drawing can have."""
    rows = np.unique(d.interp.tocoo().row) if d.interp.nnz else np.zeros(0, int)
    return set((rows % 3).tolist())


def _is_spring(d: Drawing) -> bool:
    """A discrete attachment (mass on a spring) rather than a continuum."""
    return _is_1d(d) and ("mass" in d.glyphs or d.kind in ("fixed-free", "free-free")
                          or "spring" in d.kind)


@dataclass
class _Layout:
    """How the model is drawn: axial view (axis ``e`` drawn along ``t``) or vector warp."""

    mesh: CombinedMesh
    drawings: list[Drawing]
    points: np.ndarray        # display positions of the undeformed points
    size: float
    axial: int | None         # axis of the axial displacement, or None (vector warp)
    transverse: int           # axis the axial displacement is drawn along


def _layout(drawings: list[Drawing]) -> _Layout:
    mesh = combined_mesh(drawings)
    pts = mesh.points.copy()
    extent = np.ptp(pts, axis=0) if len(pts) else np.zeros(3)
    size = float(np.max(extent)) or 1.0
    axial, transverse = None, 1
    lines = [d for d in drawings if _is_1d(d) and d.interp.nnz]
    comps = set().union(*(_components(d) for d in lines)) if lines else set()
    if len(comps) == 1 and all(_is_1d(d) for d in drawings):
        e = comps.pop()
        longest = max(lines, key=lambda d: np.ptp(np.asarray(d.points), axis=0).max())
        span = np.ptp(np.asarray(longest.points), axis=0)
        if span.max() > 0 and span[e] >= 0.9 * span.max():
            axial, transverse = e, (1 if e != 1 else 0)
            axis_t = float(np.median(np.asarray(longest.points)[:, transverse]))
            _stretch_springs(drawings, mesh, pts, transverse, axis_t, size)
    return _Layout(mesh, drawings, pts, size, axial, transverse)


def _stretch_springs(drawings, mesh, pts, t, axis_t, size):
    """In the axial view, give short attachment springs a readable length (schematic only).
    A ``spring`` between two points is left as placed: its ends are where it is connected."""
    for i, d in enumerate(drawings):
        if not _is_spring(d) or d.kind == "spring":
            continue
        sl = slice(mesh.point_offsets[i], mesh.point_offsets[i + 1])
        p = pts[sl]
        anchor = int(np.argmin(abs(p[:, t] - axis_t)))
        offset = p[:, t] - p[anchor, t]
        reach = float(np.max(abs(offset)))
        if 0 < reach < MIN_SPRING * size:
            p[:, t] = p[anchor, t] + offset * (MIN_SPRING * size / reach)


def _aligned(disp: np.ndarray) -> np.ndarray:
    """Real displacement of a complex mode, rotated to its most real phase, largest entry > 0."""
    flat = disp.ravel()
    if not np.iscomplexobj(flat):
        real = flat.astype(float)
    else:
        theta = 0.5 * np.angle(np.sum(flat * flat))
        real = (flat * np.exp(-1j * theta)).real
    if real.size and real[np.argmax(abs(real))] < 0:
        real = -real
    return real.reshape(disp.shape)


def _deformed(lay: _Layout, shape: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Display positions and normalised magnitude ``|u| / max |u|`` for one mode."""
    u = _aligned(lay.mesh.displacement(shape))
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


# ----------------------------------------------------------------------------- mode plots


def _font() -> str | None:
    try:
        from matplotlib import font_manager

        return font_manager.findfont("DejaVu Sans", fallback_to_default=True)
    except Exception:  # pragma: no cover - matplotlib always ships DejaVu
        return None


def _vtk_text(text: str) -> str:
    """VTK's text renderer splits on '|' (table columns) and parses '$...$' as math."""
    return text.replace("|", "\u00a6").replace("$", "\uff04")


def _grid(k: int) -> tuple[int, int]:
    """Rows and columns of subplots for ``k`` modes (at most 4 columns)."""
    table = {1: (1, 1), 2: (1, 2), 3: (1, 3), 4: (2, 2), 5: (2, 3), 6: (2, 3), 9: (3, 3)}
    if k in table:
        return table[k]
    return math.ceil(k / 4), 4


def _mode_title(mr: ModeResult, j: int) -> str:
    w = float(mr.omega[j])
    z = float(mr.damping_ratio[j])
    z = 0.0 if abs(z) < 1e-9 else z  # round-off of an undamped mode
    return (f"mode {j + 1}:  \u03c9 = {w:.4g} rad/s ({w / (2 * np.pi):.4g} Hz),  "
            f"\u03b6 = {z:.2g}")


def _zigzag(a: np.ndarray, b: np.ndarray, plane_normal: np.ndarray, width: float,
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


def _polyline(pv, pts: np.ndarray):
    n = len(pts)
    return pv.PolyData(pts, lines=np.concatenate([[n], np.arange(n)]))


def _segments(cells) -> np.ndarray:
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


def _line_mesh(pv, pts: np.ndarray, cells, scalars=None):
    conn = _segments(cells)
    if not len(conn):
        return None
    lines = np.hstack([np.full((len(conn), 1), 2), conn]).ravel()
    poly = pv.PolyData(pts, lines=lines)
    if scalars is not None:
        poly.point_data["|u|"] = scalars
    return poly.strip(join=True)


def _draw_mode(pv, plotter, lay: _Layout, pos: np.ndarray, mag: np.ndarray) -> None:
    size = lay.size
    m = lay.mesh
    kw = dict(cmap=_CMAP, clim=(0.0, 1.0), show_scalar_bar=False)
    for i, d in enumerate(lay.drawings):
        sl = slice(m.point_offsets[i], m.point_offsets[i + 1])
        p0, p, s = lay.points[sl], pos[sl], mag[sl]
        if not _is_1d(d):
            grid = pv.from_meshio(_meshio_mesh(p0, d.cells))
            plotter.add_mesh(grid.extract_all_edges(), color=_GHOST, line_width=1, opacity=0.6)
            warped = grid.copy()
            warped.points = p
            warped.point_data["|u|"] = s
            plotter.add_mesh(warped, scalars="|u|", show_edges=True, edge_color="#404040",
                             line_width=0.5, smooth_shading=False, **kw)
            continue
        if _is_spring(d):
            _draw_spring(pv, plotter, d, p0, p, s, lay, kw)
            continue
        ghost = _line_mesh(pv, p0, d.cells)
        if ghost is not None:
            plotter.add_mesh(ghost.tube(radius=0.0035 * size, n_sides=12), color=_GHOST)
            curve = _line_mesh(pv, p, d.cells, s)
            plotter.add_mesh(curve.tube(radius=0.008 * size, n_sides=16), scalars="|u|", **kw)
        nodes = [np.ravel(c) for t, c in d.cells if t == "vertex"]
        if nodes:
            dots = pv.PolyData(p[np.unique(np.concatenate(nodes))])
            dots.point_data["|u|"] = s[np.unique(np.concatenate(nodes))]
            plotter.add_mesh(dots.glyph(geom=pv.Sphere(radius=0.02 * size), scale=False,
                                        orient=False), scalars="|u|", **kw)
        for name, node in d.glyphs.items():
            plotter.add_mesh(pv.Sphere(radius=0.014 * size, center=p[node]), color=_INK)
        if lay.axial is not None:
            _draw_supports(pv, plotter, d, p0, lay)


def _fixed(d: Drawing, node: int) -> bool:
    """Whether drawing node ``node`` cannot move (its interpolation rows are zero)."""
    rows = _row_values(d.interp, 3 * node, 3 * node + 3)
    return rows.size == 0 or not np.any(rows)


def _row_values(matrix, start: int, stop: int) -> np.ndarray:
    m = matrix.tocsr() if hasattr(matrix, "tocsr") else matrix
    return np.asarray(m.data[m.indptr[start]:m.indptr[stop]])


def _draw_supports(pv, plotter, d: Drawing, p0: np.ndarray, lay: _Layout) -> None:
    """A wall at each end of a line drawing that is held fixed."""
    a, t, size = lay.axial, lay.transverse, lay.size
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


def _draw_spring(pv, plotter, d: Drawing, p0, p, s, lay: _Layout, kw) -> None:
    size = lay.size
    t = lay.transverse if lay.axial is not None else 1
    for a, b in _segments(d.cells):
        zig = _zigzag(p[a], p[b], _view_normal(lay), 0.016 * size)
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
        plotter.add_mesh(pv.Sphere(radius=0.85 * r, center=p0[mass]), color=_GHOST, opacity=0.6)
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
        plotter.add_point_labels(low[None, :], [_vtk_text(d.name)], font_size=11,
                                 text_color="#444444",
                                 shape=None, show_points=False, always_visible=True,
                                 justification_horizontal="left",
                                 justification_vertical="center")
    boundary = d.glyphs.get("boundary")
    if boundary is not None and boundary != mass:
        plotter.add_mesh(pv.Sphere(radius=0.014 * size, center=p[boundary]), color=_INK)


def _view_normal(lay: _Layout) -> np.ndarray:
    """Direction the camera looks along (the axial view is planar)."""
    n = np.zeros(3)
    if lay.axial is None:
        return np.array([1.0, 1.0, 1.0]) / np.sqrt(3.0)
    n[({0, 1, 2} - {lay.axial, lay.transverse}).pop()] = 1.0
    return n


def _meshio_mesh(points, cells):
    import meshio

    return meshio.Mesh(points, [(t, np.asarray(c)) for t, c in cells])


def _bounds(all_pos: list[np.ndarray], lay: _Layout) -> list[float]:
    stacked = np.vstack([lay.points, *all_pos])
    lo, hi = stacked.min(axis=0), stacked.max(axis=0)
    pad = 0.06 * lay.size
    return [v for a, b in zip(lo - pad, hi + pad) for v in (a, b)]


def _mode_result(result: Result, variant: str | None) -> tuple[ModeResult, str]:
    if variant is not None:
        if variant not in result.variants:
            known = ", ".join(repr(v) for v in result.variants) or "none"
            raise ValueError(f"no variant {variant!r} in this result (variants: {known})")
        return result.variants[variant], f" \u2014 {variant}"
    if result.modes is None:
        raise ValueError(f"result {result.case_name!r} holds no modes to plot")
    return result.modes, ""


def _quiet_headless_vtk() -> None:
    """Without a display VTK tries X first and logs 'bad X server connection' before falling
    back to an off-screen context; that warning is noise for a headless run."""
    if os.name == "posix" and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        try:
            from vtkmodules.vtkCommonCore import vtkLogger

            vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_ERROR)
        except Exception:  # pragma: no cover - logging only
            pass


def plot_modes(result: Result, png_path: str | os.PathLike, n_modes: int = 6,
               variant: str | None = None, *, window_size: tuple[int, int] | None = None
               ) -> Path:
    """Draw the first ``n_modes`` mode shapes in one PNG (a grid of views); return its path.

    Args:
        result: a result with modes and drawings.
        png_path: the PNG to write (parent directories are created).
        n_modes: how many modes, from the lowest (fewer if the result has fewer).
        variant: draw ``result.variants[variant]`` instead of ``result.modes``.
        window_size: ``(width, height)`` in pixels; default 1600 wide, rows as tall as the
            content needs (planar views) or 440 pixels (3-D views), plus a 100-pixel header.

    Raises:
        ValueError: no modes, no drawings, unknown variant, or ``n_modes < 1``.
    """
    import pyvista as pv

    mr, suffix = _mode_result(result, variant)
    if int(n_modes) < 1:
        raise ValueError(f"n_modes must be >= 1, got {n_modes!r}")
    k = min(int(n_modes), mr.shapes.shape[1])
    if k == 0:
        raise ValueError(f"result {result.case_name!r} holds no modes to plot")
    drawings = list(result.model.drawings)
    if not drawings:
        raise ValueError("the model has no drawings (nothing to draw)")
    lay = _layout(drawings)
    if lay.mesh.interp.shape[1] != mr.shapes.shape[0]:
        raise ValueError(f"drawings expect {lay.mesh.interp.shape[1]} coordinates, the mode "
                         f"shapes have {mr.shapes.shape[0]}")
    frames = [_deformed(lay, mr.shapes[:, j]) for j in range(k)]
    bounds = _bounds([f[0] for f in frames], lay)

    _quiet_headless_vtk()
    rows, cols = _grid(k)
    header = 100
    if window_size is None:
        width = 1600
        span = np.ptp(np.reshape(bounds, (3, 2)), axis=1)
        if lay.axial is not None:  # planar picture: rows as tall as the content needs
            aspect = span[lay.transverse] / max(span[lay.axial], 1e-300)
            row = int(np.clip(width / cols * aspect * 1.05 + 60, 260, 520))
        else:
            row = 440
        window_size = (width, header + row * rows)
    width, height = window_size
    row = (height - header) / rows
    font = _font()
    text_kw = {"font_file": font} if font else {}
    plotter = pv.Plotter(off_screen=True, shape=(rows + 1, cols),
                         row_weights=[header / row] + [1] * rows, groups=[(0, np.s_[:])],
                         border=False, window_size=[width, height], lighting="light kit")
    try:
        plotter.set_background("white")
        plotter.subplot(0, 0)
        how = ("axial displacement drawn transversely over the undeformed axis (grey)"
               if lay.axial is not None else "warped over the undeformed mesh (grey)")
        plotter.add_text(_vtk_text(f"{result.case_name}{suffix}: mode shapes ({mr.method})"),
                         position=(0.012, 0.58), viewport=True, font_size=13, color=_INK,
                         **text_kw)
        plotter.add_text(f"{how};\nlargest displacement drawn as {SCALE_FRACTION:.0%} of the "
                         f"model size; colour: displacement magnitude over the mode's largest",
                         position=(0.012, 0.08), viewport=True, font_size=8,
                         color="#555555", **text_kw)
        for j, (pos, mag) in enumerate(frames):
            plotter.subplot(1 + j // cols, j % cols)
            _draw_mode(pv, plotter, lay, pos, mag)
            label = plotter.add_text(_mode_title(mr, j), position=(0.5, 0.89), viewport=True,
                                     font_size=9, color=_INK, **text_kw)
            label.prop.justification_horizontal = "center"
            _camera(plotter, lay, bounds)
        plotter.subplot(0, 0)
        bar = pv.PolyData(np.zeros((2, 3)))
        bar.point_data["|u| / max |u|"] = [0.0, 1.0]
        actor = plotter.add_mesh(bar, scalars="|u| / max |u|", cmap=_CMAP, clim=(0, 1),
                                 show_scalar_bar=False, opacity=0.0)
        plotter.add_scalar_bar("normalised displacement", mapper=actor.mapper,
                               vertical=False, position_x=0.8, position_y=0.08, width=0.18,
                               height=0.55,
                               color=_INK, n_labels=3, fmt="%.1f", title_font_size=14,
                               label_font_size=12)
        image = plotter.screenshot(return_img=True)
    finally:
        plotter.close()
    return _save_png(image, png_path)


def _camera(plotter, lay: _Layout, bounds: list[float], title_room: float = 0.14) -> None:
    """Frame ``bounds`` in the current subplot, leaving ``title_room`` of its height on top."""
    if lay.axial is None:
        planar = len(lay.points) and np.ptp(lay.points[:, 2]) <= 1e-9 * lay.size
        if planar:  # a 2D model seen from above, in its own plane
            plotter.view_xy()
            plotter.enable_parallel_projection()
        else:
            plotter.view_isometric()
        plotter.reset_camera(bounds=bounds)
        plotter.camera.zoom(0.95)
        plotter.add_axes(line_width=2, color=_INK, viewport=(0.0, 0.0, 0.16, 0.24))
        return
    x0, y0, x1, y1 = plotter.renderer.GetViewport()
    width, height = plotter.window_size
    aspect = (x1 - x0) * width / ((y1 - y0) * height)
    normal = _view_normal(lay)
    box = np.reshape(bounds, (3, 2))
    center = box.mean(axis=1)
    half = 0.5 * np.ptp(box, axis=1)
    scale = 1.02 * max(half[lay.transverse] / (1 - title_room), half[lay.axial] / aspect)
    center[lay.transverse] += title_room * scale
    up = np.zeros(3)
    up[lay.transverse] = 1.0
    cam = plotter.camera
    cam.focal_point = center
    cam.position = center + normal * 4 * lay.size
    cam.up = up
    plotter.enable_parallel_projection()
    cam.parallel_scale = scale
    plotter.reset_camera_clipping_range()


def _save_png(image: np.ndarray, png_path: str | os.PathLike) -> Path:
    from matplotlib import image as mpimg

    path = Path(png_path)
    with atomic_path(path, suffix=".png.part") as tmp:
        mpimg.imsave(tmp, np.ascontiguousarray(image), format="png")
    return path


# ----------------------------------------------------------------------------- FRF plots


def plot_frf(result: Result, png_path: str | os.PathLike, *, max_curves: int = 9) -> Path:
    """Receptance magnitude (log) and phase against ``omega``, one curve per output/input pair.

    At most ``max_curves`` pairs are drawn (the first ones, outputs varying slowest); natural
    frequencies of ``result.modes`` inside the range are marked.  A single-frequency grid is
    drawn as matrices of ``|H|`` and phase with the values written in.  Return the PNG path.

    Raises:
        ValueError: the result holds no FRF.
    """
    from matplotlib.figure import Figure

    frf = result.frf
    if frf is None:
        raise ValueError(f"result {result.case_name!r} holds no FRF to plot")
    H = np.asarray(frf.H)
    omega = np.asarray(frf.omega, dtype=float)
    if H.ndim != 3 or H.shape[0] != omega.size or omega.size == 0:
        raise ValueError(f"FRF array has shape {H.shape}, expected ({omega.size}, n_out, n_in)")
    fig = Figure(figsize=(11, 7.5), dpi=110, layout="constrained")
    title = f"{result.case_name}: receptance H ({frf.method})"
    notes = [f"{m}: {v:.1e}" for m, v in frf.agreement.items()]
    sub = ("agreement " + ", ".join(notes) + "; " if notes else "") + \
        f"constraint residual {frf.constraint_residual:.1e}"
    if omega.size == 1:
        _frf_matrix(fig, frf, H[0], omega[0])
    else:
        _frf_curves(fig, result, frf, H, omega, max_curves)
    fig.suptitle(f"{title}\n{sub}", fontsize=12)
    path = Path(png_path)
    with atomic_path(path, suffix=".png.part") as tmp:
        fig.savefig(tmp, format="png")
    return path


def _frf_curves(fig, result: Result, frf, H: np.ndarray, omega: np.ndarray,
                max_curves: int) -> None:
    pairs = [(i, j) for i in range(H.shape[1]) for j in range(H.shape[2])]
    shown = pairs[:max(1, int(max_curves))]
    ax_mag, ax_ph = fig.subplots(2, 1, sharex=True, height_ratios=[2, 1])
    colors = [f"C{c}" for c in range(10)]
    for c, (i, j) in enumerate(shown):
        h = H[:, i, j]
        mag = np.where(abs(h) > 0, abs(h), np.nan)
        label = f"{frf.outputs[i]} \u2190 {frf.inputs[j]}"
        ax_mag.plot(omega, mag, color=colors[c % 10], lw=1.4, label=label)
        phase = np.degrees(np.angle(h))
        phase[phase < -179.9999] = 180.0  # one side for real negative values (+-0 imaginary)
        ax_ph.plot(omega, phase, color=colors[c % 10], lw=1.2)
    if np.any(abs(H[:, [i for i, _ in shown], [j for _, j in shown]]) > 0):
        ax_mag.set_yscale("log")
    if omega.min() > 0 and omega.max() / omega.min() > 100:
        ax_mag.set_xscale("log")
    ax_mag.set_ylabel("|H|  (displacement / force)")
    ax_ph.set_ylabel("phase (deg)")
    ax_ph.set_xlabel("\u03c9 (rad/s)")
    ax_ph.set_ylim(-185, 185)
    ax_ph.set_yticks([-180, -90, 0, 90, 180])
    for ax in (ax_mag, ax_ph):
        ax.grid(True, which="major", alpha=0.35)
        ax.grid(True, which="minor", alpha=0.12)
        ax.set_xlim(omega.min(), omega.max())
    if result.modes is not None:
        w = np.asarray(result.modes.omega, dtype=float)
        inside = w[(w >= omega.min()) & (w <= omega.max())]
        for c, wn in enumerate(inside):
            for ax in (ax_mag, ax_ph):
                ax.axvline(wn, color="0.55", lw=0.8, ls=":",
                           label="natural frequencies" if (c == 0 and ax is ax_mag) else None)
    secondary = ax_mag.secondary_xaxis("top", functions=(lambda w: w / (2 * np.pi),
                                                         lambda f: f * 2 * np.pi))
    secondary.set_xlabel("frequency (Hz)")
    more = len(pairs) - len(shown)
    ax_mag.legend(fontsize=8.5, loc="best", ncols=1 if len(shown) < 5 else 2,
                  title=f"output \u2190 input (+{more} pairs not shown)" if more else
                  "output \u2190 input", title_fontsize=8.5)


def _frf_matrix(fig, frf, H: np.ndarray, w: float) -> None:
    from matplotlib.colors import LogNorm

    ax_mag, ax_ph = fig.subplots(1, 2)
    mag = abs(H)
    positive = mag[mag > 0]
    norm = LogNorm(positive.min(), positive.max()) if positive.size and \
        positive.max() > positive.min() else None
    im = ax_mag.imshow(np.where(mag > 0, mag, np.nan), cmap="viridis", norm=norm,
                       aspect="auto")
    fig.colorbar(im, ax=ax_mag, shrink=0.8, label="|H|")
    ph = ax_ph.imshow(np.degrees(np.angle(H)), cmap="twilight_shifted", vmin=-180, vmax=180,
                      aspect="auto")
    fig.colorbar(ph, ax=ax_ph, shrink=0.8, label="phase (deg)", ticks=[-180, -90, 0, 90, 180])
    big = H.size <= 64
    phase = np.degrees(np.angle(H)) + 0.0  # + 0.0: no "-0.0"
    phase[abs(phase) < 0.05] = 0.0
    for ax, values, fmt in ((ax_mag, mag, "{:.4g}"), (ax_ph, phase, "{:.1f}\u00b0")):
        ax.set_xticks(range(H.shape[1]), frf.inputs, rotation=30, ha="right")
        ax.set_yticks(range(H.shape[0]), frf.outputs)
        ax.set_xlabel("input (unit force at)")
        ax.set_ylabel("output (displacement at)")
        if big:
            for (i, j), v in np.ndenumerate(values):
                ax.text(j, i, fmt.format(v), ha="center", va="center", fontsize=9,
                        color="white", fontweight="bold",
                        bbox=dict(boxstyle="round,pad=0.2", fc="black", alpha=0.35, lw=0))
    ax_mag.set_title(f"|H| at \u03c9 = {w:.5g} rad/s ({w / (2 * np.pi):.4g} Hz)")
    ax_ph.set_title("phase")
