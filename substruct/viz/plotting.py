"""Pictures of a result: mode shapes (pyvista, off-screen) and receptances (matplotlib).

Both work on a machine without a display and write their PNG atomically (temporary file in
the target directory, then rename).  This module is the front door; the work is done in

* :mod:`substruct.viz.layout`: axial view or vector warp, the displayed displacement of a mode
  (the largest is :data:`SCALE_FRACTION` of the model size), phase alignment;
* :mod:`substruct.viz.mode_drawing`: one mode drawn in a pyvista view (continua warped over
  their grey undeformed edges, rods as tubes, springs, masses, walls);
* :mod:`substruct.viz.mode_picture`: the grid of modes in one PNG (:func:`plot_modes`);
* :mod:`substruct.viz.frf_picture`: receptance magnitude and phase (:func:`plot_frf`).

:func:`plot_modes` and :func:`plot_frf` write a PNG and return its path (the command line);
:func:`modes_figure` and :func:`frf_figure` return a matplotlib figure, for a notebook to show
and change, and write the PNG too when given a path.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

from substruct.io.hdf5 import atomic_path
from substruct.run.result import Result
from substruct.viz.frf_picture import MAX_FRF_CURVES, draw_frf, plot_frf
from substruct.viz.layout import SCALE_FRACTION
from substruct.viz.mode_picture import plot_modes, render_modes, save_png

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["plot_modes", "plot_frf", "modes_figure", "frf_figure", "SCALE_FRACTION"]


def frf_figure(result: Result, png_path: str | os.PathLike | None = None, *,
               max_curves: int = MAX_FRF_CURVES, magnitude: str | None = None) -> Figure:
    """The receptance figure of :func:`plot_frf`, returned; written to ``png_path`` as well
    when one is given.  ``magnitude``: ``"log"`` or ``"db"``; ``None`` takes the case's
    ``analysis.frf.magnitude`` (:func:`substruct.viz.frf_picture.draw_frf`).

    Raises:
        ValueError: the result holds no FRF.
    """
    fig = draw_frf(result, max_curves=max_curves, magnitude=magnitude)
    if png_path is not None:
        with atomic_path(Path(png_path), suffix=".png.part") as tmp:
            fig.savefig(tmp, format="png")
    return fig


def modes_figure(result: Result, png_path: str | os.PathLike | None = None, n_modes: int = 6,
                 variant: str | None = None) -> Figure:
    """The mode picture of :func:`plot_modes` in a matplotlib figure, returned; the PNG is
    written to ``png_path`` as well when one is given (the rendered image, pixel for pixel).

    Raises:
        ValueError: no modes, no drawings, unknown variant, or ``n_modes < 1``.
    """
    from matplotlib.figure import Figure

    image = render_modes(result, n_modes, variant)
    if png_path is not None:
        save_png(image, png_path)
    height, width = image.shape[:2]
    fig = Figure(figsize=(width / 100, height / 100), dpi=100)
    ax = fig.add_axes((0, 0, 1, 1))
    ax.imshow(image)
    ax.set_axis_off()
    return fig
