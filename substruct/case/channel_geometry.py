"""The geometry of a virtual-point case as a result keeps it: for every ``type: frf`` part
with ``virtual_points:``, the channel table the run used (names, nodes, positions, unit
directions, kinds; the length unit and the header of a Universal File, when the table came
from one) and the virtual points (names, positions), in the part's own coordinates.

Positions and directions are global: the coordinate systems of a Universal File (18, 2420)
are resolved when the table is read (:mod:`substruct.case.uff_geometry`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from substruct.case.channels import ChannelTable

__all__ = ["PartChannels", "case_channels"]


@dataclass(frozen=True)
class PartChannels:
    """The channels and virtual points of one part.

    Attributes:
        table: the channel table (its ``source``, ``units`` and ``header`` kept).
        points: the virtual points' names, in the case's order.
        point_xyz: ``(n_points, 3)`` their positions, in the table's length unit.
    """

    table: ChannelTable
    points: tuple[str, ...]
    point_xyz: np.ndarray


def case_channels(case: Any) -> dict[str, PartChannels]:
    """Part name -> :class:`PartChannels` for every substructure of ``case`` (a validated
    case) with ``virtual_points:``, in the case's order."""
    out: dict[str, PartChannels] = {}
    for s in case.substructures:
        vps = getattr(s, "virtual_points", None)
        if vps is None:
            continue
        out[s.name] = PartChannels(
            vps.table(), tuple(p.name for p in vps.points),
            np.asarray([p.position for p in vps.points], dtype=float).reshape(-1, 3))
    return out
