r"""GRID ``CD``: the coordinates of a grid along its displacement coordinate system's
directions at the grid (:meth:`~substruct.case.bdf_coords.CoordSystem.frame`).

With ``F_g`` (3 x 3, columns the directions in basic) for each grid (the identity for
``CD = 0``), a grid's six basic coordinates are :math:`u_{basic} = \mathrm{diag}(F_g, F_g)\,
u_{CD}`, and for the whole model :math:`u_{basic} = T\, u_{CD}` with ``T`` block diagonal
(orthogonal).  Elements and masses are assembled in basic and transformed,

.. math::  K_{CD} = T^T K_{basic} T, \qquad M_{CD} = T^T M_{basic} T,

so every reference to a component of a grid (SPC, SPC1, GRID PS, MPC, CELAS, points of a
case) is in its ``CD`` system, as in Nastran.
"""

from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np
import scipy.sparse as sp

__all__ = ["grid_frames6", "grid_transform"]


def grid_frames6(frames: Mapping[int, np.ndarray], g: int) -> np.ndarray:
    """``diag(F_g, F_g)`` (6 x 6) of grid ``g`` (the identity without a frame)."""
    out = np.eye(6)
    if g in frames:
        out[:3, :3] = out[3:, 3:] = frames[g]
    return out


def grid_transform(ids: Sequence[int], frames: Mapping[int, np.ndarray]) -> sp.csr_array:
    """``T`` (``6 n x 6 n``, grids in the order of ``ids``): :math:`u_{basic} = T u_{CD}`."""
    n = len(ids)
    blocks = np.zeros((2 * n, 3, 3))
    blocks[:] = np.eye(3)
    for k, g in enumerate(ids):
        if g in frames:
            blocks[2 * k] = blocks[2 * k + 1] = frames[g]
    rows = (3 * np.arange(2 * n)[:, None, None] + np.arange(3)[None, :, None]).repeat(3, 2)
    cols = (3 * np.arange(2 * n)[:, None, None] + np.arange(3)[None, None, :]).repeat(3, 1)
    T = sp.csr_array((blocks.ravel(), (rows.ravel(), cols.ravel())), shape=(6 * n, 6 * n))
    T.eliminate_zeros()
    return T
