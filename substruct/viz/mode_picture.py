"""The mode-shape picture: the first modes of a result in one PNG, a grid of off-screen
pyvista views under a header (case, formulation, how the shapes are drawn, colour bar).

Each mode is laid out by :mod:`substruct.viz.layout` and drawn by
:mod:`substruct.viz.mode_drawing`; the PNG is written atomically (temporary file in the target
directory, then rename).
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from substruct.io.hdf5 import atomic_path
from substruct.run.result import Result
from substruct.viz.layout import (
    SCALE_FRACTION,
    Layout,
    deformed,
    drawing_layout,
    view_normal,
)
from substruct.viz.mode_drawing import CMAP, INK, draw_mode, vtk_text

if TYPE_CHECKING:
    from substruct.analysis.results import Modes

#: A mode shape more complex than this (:func:`complex_part`) says how it is drawn.
COMPLEX_NOTE = 1e-2

__all__ = ["plot_modes", "render_modes", "complex_part", "mapping_note", "COMPLEX_NOTE",
           "grid_shape", "mode_title", "modes_to_draw", "save_png"]

#: Height of the header row of a mode picture, in pixels.
HEADER = 100


def grid_shape(k: int) -> tuple[int, int]:
    """Rows and columns of subplots for ``k`` modes (at most 4 columns)."""
    table = {1: (1, 1), 2: (1, 2), 3: (1, 3), 4: (2, 2), 5: (2, 3), 6: (2, 3), 9: (3, 3)}
    if k in table:
        return table[k]
    return math.ceil(k / 4), 4


def mode_title(modes: Modes, j: int) -> str:
    """``mode j+1: omega = ... rad/s (... Hz), zeta = ...`` of mode ``j``."""
    w = float(modes.omega[j])
    z = float(modes.damping_ratio[j])
    z = 0.0 if abs(z) < 1e-9 else z  # round-off of an undamped mode
    return (f"mode {j + 1}:  \u03c9 = {w:.4g} rad/s ({w / (2 * np.pi):.4g} Hz),  "
            f"\u03b6 = {z:.2g}")


def complex_part(shape: np.ndarray) -> float:
    r"""How complex a mode shape is: the imaginary part left at its most real phase,

    .. math::  \frac{\lVert \operatorname{Im}(e^{-i\theta} u) \rVert}{\lVert u \rVert},
               \qquad \theta = \tfrac12 \arg \textstyle\sum_k u_k^2

    (0 for a real mode, at most 1/sqrt(2), reached by a travelling wave)."""
    u = np.asarray(shape, dtype=complex).ravel()
    norm = float(np.linalg.norm(u))
    if norm == 0:
        return 0.0
    theta = 0.5 * np.angle(np.sum(u * u))
    return float(np.linalg.norm((u * np.exp(-1j * theta)).imag) / norm)


def mapping_note(result: Result) -> str:
    """A caption for shapes of a rod with the paper-literal mapping (empty otherwise)."""
    import yaml

    try:
        case = yaml.safe_load(result.case_yaml) or {}
    except yaml.YAMLError:
        return ""
    subs = case.get("substructures") if isinstance(case, dict) else None
    literal = [s.get("name", "?") for s in subs or [] if isinstance(s, dict) and
               isinstance(s.get("discretization"), dict) and
               s["discretization"].get("mapping") == "paper-literal"]
    if not literal:
        return ""
    return (f"{', '.join(literal)}: paper-literal mapping, as Table 1 was computed: NOT\n"
            f"physical shapes (assumed-mode amplitudes drawn as displacements at x = jL/n)")


def modes_to_draw(result: Result, variant: str | None) -> tuple[Modes, str]:
    """The modes to draw (``result.modes`` or a variant's) and the title suffix.

    Raises:
        ValueError: an unknown variant, or a result without modes.
    """
    if variant is not None:
        if variant not in result.variants:
            known = ", ".join(repr(v) for v in result.variants) or "none"
            raise ValueError(f"no variant {variant!r} in this result (variants: {known})")
        return result.variants[variant], f" \u2014 {variant}"
    if result.modes is None:
        raise ValueError(f"result {result.case_name!r} holds no modes to plot")
    return result.modes, ""


def _font() -> str | None:
    try:
        from matplotlib import font_manager

        return str(font_manager.findfont("DejaVu Sans", fallback_to_default=True))
    except Exception:  # pragma: no cover - matplotlib always ships DejaVu
        return None


def _bounds(all_pos: list[np.ndarray], lay: Layout) -> list[float]:
    stacked = np.vstack([lay.points, *all_pos])
    lo, hi = stacked.min(axis=0), stacked.max(axis=0)
    pad = 0.06 * lay.size
    return [float(v) for a, b in zip(lo - pad, hi + pad) for v in (a, b)]


def _quiet_headless_vtk() -> None:
    """Without a display VTK tries X first and logs 'bad X server connection' before falling
    back to an off-screen context; that warning is noise for a headless run."""
    if os.name == "posix" and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        try:
            from vtkmodules.vtkCommonCore import vtkLogger

            vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_ERROR)
        except Exception:  # pragma: no cover - logging only
            pass


def _window(lay: Layout, bounds: list[float], rows: int, cols: int) -> tuple[int, int]:
    """Default picture size: 1600 wide, rows as tall as the content needs (planar views) or
    440 pixels (3-D views), plus the header."""
    width = 1600
    span = np.ptp(np.reshape(bounds, (3, 2)), axis=1)
    if lay.axial is not None:  # planar picture: rows as tall as the content needs
        aspect = span[lay.transverse] / max(span[lay.axial], 1e-300)
        row = int(np.clip(width / cols * aspect * 1.05 + 60, 260, 520))
    else:
        row = 440
    return width, HEADER + row * rows


def plot_modes(result: Result, png_path: str | os.PathLike, n_modes: int = 6,
               variant: str | None = None, *, window_size: tuple[int, int] | None = None
               ) -> Path:
    """Draw the first ``n_modes`` mode shapes in one PNG (a grid of views); return its path
    (the picture of :func:`render_modes`, same arguments)."""
    return save_png(render_modes(result, n_modes, variant, window_size=window_size), png_path)


def render_modes(result: Result, n_modes: int = 6, variant: str | None = None, *,
                 window_size: tuple[int, int] | None = None) -> np.ndarray:
    """The first ``n_modes`` mode shapes drawn in one image (a grid of views), as an RGB array.

    Args:
        result: a result with modes and drawings.
        n_modes: how many modes, from the lowest (fewer if the result has fewer).
        variant: draw ``result.variants[variant]`` instead of ``result.modes``.
        window_size: ``(width, height)`` in pixels; default 1600 wide, rows as tall as the
            content needs (planar views) or 440 pixels (3-D views), plus a 100-pixel header.

    Raises:
        ValueError: no modes, no drawings, unknown variant, or ``n_modes < 1``.
    """
    import pyvista as pv

    modes, suffix = modes_to_draw(result, variant)
    if int(n_modes) < 1:
        raise ValueError(f"n_modes must be >= 1, got {n_modes!r}")
    k = min(int(n_modes), modes.shapes.shape[1])
    if k == 0:
        raise ValueError(f"result {result.case_name!r} holds no modes to plot")
    lay = drawing_layout(result.model.drawings, modes.shapes.shape[0], "mode shapes")
    frames = [deformed(lay, modes.shapes[:, j]) for j in range(k)]
    bounds = _bounds([f[0] for f in frames], lay)

    _quiet_headless_vtk()
    rows, cols = grid_shape(k)
    width, height = window_size or _window(lay, bounds, rows, cols)
    row = (height - HEADER) / rows
    font = _font()
    text_kw = {"font_file": font} if font else {}
    plotter = pv.Plotter(off_screen=True, shape=(rows + 1, cols),
                         row_weights=[HEADER / row] + [1] * rows, groups=[(0, np.s_[:])],
                         border=False, window_size=[width, height], lighting="light kit")
    try:
        plotter.set_background("white")
        plotter.subplot(0, 0)
        how = ("axial displacement drawn transversely over the undeformed axis (grey)"
               if lay.axial is not None else "warped over the undeformed mesh (grey)")
        plotter.add_text(vtk_text(f"{result.case_name}{suffix}: mode shapes ({modes.method})"),
                         position=(0.012, 0.58), viewport=True, font_size=13, color=INK,
                         **text_kw)
        plotter.add_text(f"{how};\nlargest displacement drawn as {SCALE_FRACTION:.0%} of the "
                         f"model size; a damped mode at its most real phase (marked if its "
                         f"shape is complex)",
                         position=(0.012, 0.08), viewport=True, font_size=8,
                         color="#555555", **text_kw)
        note = mapping_note(result)
        if note:
            plotter.add_text(vtk_text(note), position=(0.47, 0.42), viewport=True,
                             font_size=9, color="#a01010", **text_kw)
        for j, (pos, mag) in enumerate(frames):
            plotter.subplot(1 + j // cols, j % cols)
            draw_mode(pv, plotter, lay, pos, mag)
            label = plotter.add_text(mode_title(modes, j), position=(0.5, 0.89), viewport=True,
                                     font_size=9, color=INK, **text_kw)
            label.prop.justification_horizontal = "center"
            if complex_part(modes.shapes[:, j]) > COMPLEX_NOTE:
                extra = plotter.add_text("complex (damped) shape: drawn at its most real phase, "
                                         "Re(exp(-i\u03b8) u)", position=(0.5, 0.80),
                                         viewport=True, font_size=7, color="#a01010",
                                         **text_kw)
                extra.prop.justification_horizontal = "center"
            _camera(plotter, lay, bounds)
        plotter.subplot(0, 0)
        bar = pv.PolyData(np.zeros((2, 3)))
        bar.point_data["|u| / max |u|"] = [0.0, 1.0]
        actor = plotter.add_mesh(bar, scalars="|u| / max |u|", cmap=CMAP, clim=(0, 1),
                                 show_scalar_bar=False, opacity=0.0)
        # the title as its own text above the bar, the tick labels under it: nothing overlaps
        plotter.add_scalar_bar(" ", mapper=actor.mapper, vertical=False, position_x=0.8,
                               position_y=0.30, width=0.18, height=0.22, color=INK,
                               n_labels=0, title_font_size=1)
        bar_title = plotter.add_text("colour: displacement / mode's largest",
                                     position=(0.98, 0.62), viewport=True, font_size=9,
                                     color=INK, **text_kw)
        bar_title.prop.justification_horizontal = "right"
        for x, tick in ((0.8, "0"), (0.973, "1")):
            plotter.add_text(tick, position=(x, 0.06), viewport=True, font_size=9,
                             color=INK, **text_kw)
        image = plotter.screenshot(return_img=True)
    finally:
        plotter.close()
    return np.asarray(image)


def _camera(plotter: Any, lay: Layout, bounds: list[float], title_room: float = 0.14) -> None:
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
        plotter.add_axes(line_width=2, color=INK, viewport=(0.0, 0.0, 0.16, 0.24))
        return
    x0, y0, x1, y1 = plotter.renderer.GetViewport()
    width, height = plotter.window_size
    aspect = (x1 - x0) * width / ((y1 - y0) * height)
    normal = view_normal(lay)
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


def save_png(image: np.ndarray, png_path: str | os.PathLike) -> Path:
    """Write an RGB(A) image as a PNG, atomically; return its path."""
    from matplotlib import image as mpimg

    path = Path(png_path)
    with atomic_path(path, suffix=".png.part") as tmp:
        mpimg.imsave(tmp, np.ascontiguousarray(image), format="png")
    return path
