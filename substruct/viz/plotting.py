"""Pictures of a result: mode shapes (pyvista, off-screen) and receptances (matplotlib).

Both work on a machine without a display and write their PNG atomically (temporary file in
the target directory, then rename).  This module is the front door; the work is done in

* :mod:`substruct.viz.layout`: axial view or vector warp, the displayed displacement of a mode
  (the largest is :data:`SCALE_FRACTION` of the model size), phase alignment;
* :mod:`substruct.viz.mode_drawing`: one mode drawn in a pyvista view (continua warped over
  their grey undeformed edges, rods as tubes, springs, masses, walls);
* :mod:`substruct.viz.mode_picture`: the grid of modes in one PNG (:func:`plot_modes`);
* :mod:`substruct.viz.frf_picture`: receptance magnitude and phase (:func:`plot_frf`).
"""

from __future__ import annotations

from substruct.viz.frf_picture import plot_frf
from substruct.viz.layout import SCALE_FRACTION
from substruct.viz.mode_picture import plot_modes

__all__ = ["plot_modes", "plot_frf", "SCALE_FRACTION"]
