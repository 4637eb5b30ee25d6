"""The drawing of one substructure as plain data (points, cells, interpolation from the
stacked coordinates), stored in results and drawn by :mod:`substruct.viz`."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

__all__ = ["Drawing"]


@dataclass
class Drawing:
    """How to draw one substructure from the stacked coordinate vector ``u``.

    ``(interp @ u).reshape(-1, 3)`` are the displacements of ``points``; ``cells`` are
    meshio-style ``(cell_type, connectivity)`` pairs; ``glyphs`` name points worth marking.
    """

    name: str
    kind: str
    points: np.ndarray
    cells: list[tuple[str, np.ndarray]]
    interp: sp.csr_array
    glyphs: dict[str, int] = field(default_factory=dict)
    #: ``(rotations @ u).reshape(-1, 3)`` are the rotations of ``points`` (``None``: no
    #: rotations, as on solids).
    rotations: sp.csr_array | None = None
