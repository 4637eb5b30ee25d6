"""An animated GIF of a transient response: the structure deformed by the fields the run
stored every ``field_every`` steps (``/transient/snapshots``), one frame per stored instant (at
most :data:`MAX_FRAMES`, evenly spaced, the first and the last kept).

The drawing is that of the mode pictures (:mod:`substruct.viz.mode_drawing`, pyvista off
screen): solids warped over their grey undeformed edges, rods as tubes (their axial
displacement drawn transversely in the axial view, :mod:`substruct.viz.layout`), attachments as
springs.  One scale serves every frame, so the motion is seen as it is: the largest displacement
over the whole run is drawn as :data:`~substruct.viz.layout.SCALE_FRACTION` of the model size,
and the colour is ``|u|`` over that largest value.  The camera is fixed.  pyvista and PIL are
imported only by :func:`write_transient_gif`.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from substruct.io.hdf5 import atomic_path
from substruct.run.result import Result
from substruct.viz.layout import SCALE_FRACTION, Layout, drawing_layout, view_normal
from substruct.viz.mode_drawing import INK, draw_mode, vtk_text

__all__ = ["MAX_FRAMES", "frame_indices", "frame_positions", "write_transient_gif"]

#: The most frames of an animation.
MAX_FRAMES = 120
#: Frames per second of the GIF.
FPS = 12


def frame_indices(n: int, max_frames: int = MAX_FRAMES) -> list[int]:
    """The stored fields drawn: all ``n`` if at most ``max_frames``, else ``max_frames``
    evenly spaced from the first to the last."""
    if n <= max_frames:
        return list(range(n))
    return sorted({int(round(i)) for i in np.linspace(0, n - 1, max_frames)})


def frame_positions(lay: Layout, fields: np.ndarray) -> tuple[list[np.ndarray],
                                                              list[np.ndarray], float]:
    r"""Display positions and colours ``|u| / max_k |u_k|`` of each field (rows of
    ``fields``, coordinates of the model), and the largest displacement :math:`\max_k |u_k|`:
    one scale, :math:`s = \text{SCALE\_FRACTION} \cdot \text{size} / \max_k |u_k|`, for all."""
    disp = [lay.mesh.displacement(q).real for q in fields]
    if lay.axial is not None:
        mags = [np.abs(u[:, lay.axial]) for u in disp]
    else:
        mags = [np.linalg.norm(u, axis=1) for u in disp]
    peak = max((float(m.max()) for m in mags if m.size), default=0.0)
    scale = SCALE_FRACTION * lay.size / peak if peak > 0 else 0.0
    positions = []
    for u in disp:
        pos = lay.points.copy()
        if lay.axial is not None:
            pos[:, lay.transverse] += scale * u[:, lay.axial]
        else:
            pos += scale * u
        positions.append(pos)
    return positions, [m / peak if peak > 0 else m for m in mags], peak


def _camera(plotter: Any, lay: Layout, bounds: np.ndarray) -> None:
    """The same view for every frame: in the plane of an axial view, else isometric."""
    center = bounds.mean(axis=1)
    half = 0.5 * np.ptp(bounds, axis=1)
    cam = plotter.camera
    if lay.axial is None:
        normal = view_normal(lay)
        cam.focal_point = center
        cam.position = center + normal * 4 * lay.size
        cam.up = (0.0, 0.0, 1.0)
        plotter.reset_camera(bounds=[float(v) for v in bounds.ravel()])
        return
    width, height = plotter.window_size
    up = np.zeros(3)
    up[lay.transverse] = 1.0
    cam.focal_point = center
    cam.position = center + view_normal(lay) * 4 * lay.size
    cam.up = up
    plotter.enable_parallel_projection()
    cam.parallel_scale = 1.15 * max(half[lay.transverse], half[lay.axial] * height / width)
    plotter.reset_camera_clipping_range()


def write_transient_gif(result: Result, gif_path: str | os.PathLike, *,
                        max_frames: int = MAX_FRAMES,
                        window_size: tuple[int, int] = (800, 480)) -> Path:
    """Draw the stored fields of ``result.transient`` as an animated GIF (module docstring),
    written atomically; return its path.

    Raises:
        ValueError: no transient response, no stored fields, no drawings, or drawings of
            another size than the fields.
    """
    import pyvista as pv
    from PIL import Image

    tr = result.transient
    if tr is None or not len(tr.snapshot_t):
        raise ValueError(f"result {result.case_name!r} holds no stored transient fields")
    lay = drawing_layout(result.model.drawings, tr.snapshots.shape[1], "stored fields")
    keep = frame_indices(len(tr.snapshot_t), max_frames)
    positions, mags, peak = frame_positions(lay, tr.snapshots[keep])
    stacked = np.vstack([lay.points, *positions])
    pad = 0.06 * lay.size
    bounds = np.column_stack([stacked.min(axis=0) - pad, stacked.max(axis=0) + pad])
    images = []
    plotter = pv.Plotter(off_screen=True, window_size=list(window_size), lighting="light kit")
    try:
        for k, pos, mag in zip(keep, positions, mags):
            plotter.clear()
            plotter.set_background("white")
            draw_mode(pv, plotter, lay, pos, mag)
            plotter.add_text(vtk_text(f"{result.case_name}: t = {tr.snapshot_t[k]:.6g}"),
                             position="upper_left", font_size=11, color=INK)
            plotter.add_text(f"largest displacement {peak:.3g} drawn as "
                             f"{SCALE_FRACTION:.0%} of the model size",
                             position="lower_left", font_size=8, color="#555555")
            _camera(plotter, lay, bounds)
            images.append(Image.fromarray(np.asarray(plotter.screenshot(return_img=True))))
    finally:
        plotter.close()
    frames = [im.convert("P", palette=Image.Palette.ADAPTIVE, colors=255) for im in images]
    path = Path(gif_path)
    with atomic_path(path, suffix=".gif.part") as tmp:
        frames[0].save(tmp, format="GIF", save_all=True, append_images=frames[1:],
                       duration=int(1000 / FPS), loop=0, optimize=False, disposal=1)
    return path
