r"""Universal File export of a test's geometry with its receptances: a virtual-point or coupled
result whose parts carry their channel geometry (``/virtual_points/<i>/geometry``) is written
as

* **151** model header (the case name, ``substruct``) and **164** units (code 1, SI: factors 1;
  the positions are written in the channel tables' length unit, taken as metres);
* **2420** one cartesian coordinate system per channel, its x axis the channel's direction
  (records 5-7 the rows of :math:`A`: :math:`e`, then :math:`e \times a / |\cdot|` and
  :math:`e \times (e \times a) / |\cdot|` with :math:`a` the global axis least aligned with
  :math:`e`, a right-handed orthonormal triad; record 8 the origin, zero);
* **2411** one node per channel (at its position, displacement system its own) and one per
  virtual point (at its position, the global system), ``1P3D25.16``: 17 significant digits,
  so the positions and directions read back to the last bit;
* **58** (binary, :func:`substruct.io.uff.uff58_bytes`) one function per output/input pair:
  a channel ``<part>@ch:<name>`` at its node, direction ``+1`` (its system's x axis, the
  channel's direction); a virtual-point coordinate ``<part>@vp:<point>:<ux..rz>`` at the
  point's node, directions 1-6 in the global system.

Read back by :mod:`substruct.case.uff_geometry` (positions and directions) and
:mod:`substruct.case.uff_records` (the functions), the channels land where the result's
geometry puts them, exactly.  Refused: an output or input that is neither a channel nor a
virtual-point coordinate of a part with a geometry (its place is not known).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from substruct.io.hdf5 import atomic_path
from substruct.io.uff import uff58_bytes, uff58_sets, uff_path
from substruct.run.result import Result

__all__ = ["has_channel_geometry", "channel_axes", "channel_uff_text", "export_channels_uff"]

_DELIM = "    -1\n"
_VP_CODES = {"ux": 1, "uy": 2, "uz": 3, "rx": 4, "ry": 5, "rz": 6}


def has_channel_geometry(result: Result) -> bool:
    """Whether every part of the result's virtual points carries its channel geometry."""
    vps = result.virtual_points or {}
    return bool(vps) and all(v.geometry is not None for v in vps.values())


def channel_axes(e: np.ndarray) -> np.ndarray:
    r"""A right-handed orthonormal triad (rows) whose first row is the unit vector ``e``
    exactly (module docstring)."""
    e = np.asarray(e, dtype=float)
    a = np.zeros(3)
    a[int(np.argmin(np.abs(e)))] = 1.0
    y = np.cross(e, a)
    y /= np.linalg.norm(y)
    z = np.cross(e, y)
    z /= np.linalg.norm(z)
    return np.array([e, y, z])


def _d25(values: np.ndarray) -> str:
    return "".join(f"{float(v):25.16E}" for v in values) + "\n"


def channel_uff_text(result: Result) -> tuple[str, dict[str, tuple[int, int]]]:
    """The 151, 164, 2420 and 2411 datasets of the result's geometry (module docstring), and
    the ``(node, direction)`` of every channel and virtual-point coordinate by its point
    name (``<part>@ch:<name>``, ``<part>@vp:<point>:<ux..rz>``)."""
    head = (f"{_DELIM}   151\n{result.case_name[:80]}\nsubstruct test geometry and "
            f"receptances\nsubstruct\n\n\n\nsubstruct\n\n{_DELIM}"
            f"{_DELIM}   164\n{1:10d}{'SI - mks (Newton)':<20}{2:10d}\n"
            f"{1.0:25.17E}{1.0:25.17E}{1.0:25.17E}\n{273.15:25.17E}\n{_DELIM}")
    systems: list[str] = []
    nodes: list[str] = []
    where: dict[str, tuple[int, int]] = {}
    label = 0
    for part, ind in (result.virtual_points or {}).items():
        geo = ind.geometry
        if geo is None:
            continue
        for name, pos, d in zip(geo.names, geo.positions, geo.directions):
            label += 1
            A = channel_axes(d)
            systems.append(f"{label:10d}{0:10d}{8:10d}\n{part}@ch:{name}"[:80] + "\n"
                           + "".join(_d25(row) for row in A) + _d25(np.zeros(3)))
            nodes.append(f"{label:10d}{0:10d}{label:10d}{8:10d}\n" + _d25(pos))
            where[f"{part}@ch:{name}"] = (label, 1)
        for name, pos in zip(geo.point_names, geo.point_positions):
            label += 1
            nodes.append(f"{label:10d}{0:10d}{0:10d}{8:10d}\n" + _d25(pos))
            for comp, code in _VP_CODES.items():
                where[f"{part}@vp:{name}:{comp}"] = (label, code)
    text = head
    if systems:
        text += f"{_DELIM}  2420\n{1:10d}\nsubstruct channels\n" + "".join(systems) + _DELIM
    text += f"{_DELIM}  2411\n" + "".join(nodes) + _DELIM
    return text, where


def export_channels_uff(result: Result, out: str | os.PathLike, force: bool = False) -> Path:
    """Write the result's geometry and receptances as one UFF file (module docstring;
    :func:`~substruct.io.uff.uff_path`), atomically; return its path.

    Raises:
        FileExistsError: the file exists and ``force`` is not set.
        ValueError: no receptances, or an output or input without a place.
    """
    path = uff_path(result, out)
    if path.exists() and not force:
        raise FileExistsError(f"{path} exists; use --force to overwrite it")
    frf = result.frf
    if frf is None:
        raise ValueError(f"{result.case_name}: no receptances to export with the channels")
    text, where = channel_uff_text(result)
    for point in [*frf.outputs, *frf.inputs]:
        if point not in where:
            raise ValueError(f"UFF export with channels: {point!r} is neither a channel nor a "
                             "virtual-point coordinate of a part with a stored geometry")
    sets: list[dict[str, Any]] = uff58_sets(frf.omega, frf.H, frf.outputs, frf.inputs,
                                            frf.quantity, where)
    with atomic_path(path, suffix=".uff") as tmp:
        with open(tmp, "wb") as fh:
            fh.write(text.encode("ascii", "replace"))
            for s in sets:
                fh.write(uff58_bytes(s))
    return path
