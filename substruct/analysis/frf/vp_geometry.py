r"""The geometry of a test as a result keeps it: the channels of a part's table (names,
kinds, positions, unit directions) and its virtual points (names, positions), so that a
coupled or virtual-point result can be drawn or exported (UFF) without the case's files.

A sensor at :math:`r` with direction :math:`e` reads :math:`e \cdot u(r)`; an impact at
:math:`r` along :math:`e` applies the force :math:`f e` there (:mod:`substruct.case.channels`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from substruct.case.channels import ChannelTable

__all__ = ["ChannelGeometry", "channel_geometry", "check_geometry"]

#: How far from unit length a stored direction may be (it was normalised when read).
UNIT_TOL = 1e-12


@dataclass(frozen=True)
class ChannelGeometry:
    """The channels and virtual points of one part.

    Attributes:
        names, kinds: one per channel (``"sensor"`` or ``"impact"``).
        positions, directions: ``(n, 3)``; directions of unit length.
        point_names: the virtual points.
        point_positions: ``(m, 3)``.
    """

    names: list[str]
    kinds: list[str]
    positions: np.ndarray
    directions: np.ndarray
    point_names: list[str]
    point_positions: np.ndarray

    def __post_init__(self) -> None:
        check_geometry(self.names, self.kinds, self.positions, self.directions,
                       self.point_names, self.point_positions)

    def channel(self, name: str) -> tuple[np.ndarray, np.ndarray, str]:
        """``(position, direction, kind)`` of a channel by name."""
        i = self.names.index(name)
        return self.positions[i], self.directions[i], self.kinds[i]

    def point(self, name: str) -> np.ndarray:
        """The position of a virtual point by name."""
        return self.point_positions[self.point_names.index(name)]


def check_geometry(names: Sequence[str], kinds: Sequence[str], positions: np.ndarray,
                   directions: np.ndarray, point_names: Sequence[str],
                   point_positions: np.ndarray) -> None:
    """Refuse a geometry whose parts disagree in size, repeat a name, hold values that are
    not finite, a kind other than sensor or impact, or a direction not of unit length.

    Raises:
        ValueError: as above, naming the first offender.
    """
    n, m = len(names), len(point_names)
    for what, arr, rows in (("positions", positions, n), ("directions", directions, n),
                            ("point positions", point_positions, m)):
        if np.shape(arr) != (rows, 3):
            raise ValueError(f"channel geometry: {what} of shape {list(np.shape(arr))}, "
                             f"expected [{rows}, 3]")
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"channel geometry: {what} hold values that are not finite")
    if len(kinds) != n:
        raise ValueError(f"channel geometry: {len(kinds)} kinds for {n} channels")
    for group in (names, point_names):
        if len(set(group)) != len(group):
            raise ValueError("channel geometry: a name is repeated")
    for name, kind in zip(names, kinds):
        if kind not in ("sensor", "impact"):
            raise ValueError(f"channel geometry: channel {name!r} is of kind {kind!r}, not "
                             "sensor or impact")
    length = np.linalg.norm(directions, axis=1) if n else np.zeros(0)
    if n and np.abs(length - 1).max() > UNIT_TOL:
        i = int(np.argmax(np.abs(length - 1)))
        raise ValueError(f"channel geometry: the direction of {names[i]!r} has length "
                         f"{length[i]!r}, not 1")


def channel_geometry(table: ChannelTable, points: Sequence[tuple[str, Sequence[float]]]
                     ) -> ChannelGeometry:
    """The geometry of every channel of ``table`` (in its order) and of the virtual points
    ``(name, position)``."""
    chans = list(table.channels)
    pos = np.array([c.position for c in chans], dtype=float).reshape(-1, 3)
    dirs = np.array([c.direction for c in chans], dtype=float).reshape(-1, 3)
    return ChannelGeometry([c.name for c in chans], [c.kind for c in chans], pos, dirs,
                           [p for p, _ in points],
                           np.array([list(x) for _, x in points], dtype=float).reshape(-1, 3))
