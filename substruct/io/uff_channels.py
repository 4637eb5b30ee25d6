r"""The test geometry of a virtual-point result in a Universal File: a header (151: the case
name, written by substruct), the units (164), the nodes (2411) of its virtual points and
channels and their coordinate systems (2420), so that the 58 functions of :func:`substruct.io.uff.export_uff` carry real node numbers and direction
codes.

* a virtual-point coordinate ``<part>@vp:<point>:<c>`` (``c`` one of ``ux uy uz rx ry rz``)
  is the node of ``(part, point)``, at the point's position, in the global system (0), with
  the direction code 1..6 of ``c``;
* a channel that passes through, ``<part>@ch:<name>``, is a node of its own at the channel's
  position (coordinates in the global system), whose displacement system is a 2420 system
  of the same label with the rows :math:`A = [e;\ e_2;\ e_3]`: :math:`e` the channel's
  direction, :math:`e_2` the unit part of the global axis least aligned with :math:`e`
  orthogonal to it, :math:`e_3 = e \times e_2` (right-handed); the direction code is 1 (+x
  of that system, which is :math:`e` to the last bit); the system's origin (record 8) is the
  channel's position;
* anything else (an extra interface mode ``vp:<point>:e<k>``, a coordinate of a
  finite-element part) keeps the node of :func:`substruct.io.uff.frf_nodes`, at ``(k, 0, 0)``.

Coordinates are written ``%25.16e`` (17 significant digits: the doubles themselves), so the
positions and directions read back (:mod:`substruct.case.uff_geometry`) are the result's
exactly.  The 164 dataset says SI (code 1, factors 1): substruct converts no units, so the
file's numbers are those of the case and its channel tables, SI when they are (a table read
from a Universal File with a 164 is in meters).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import numpy as np

from substruct.case.channel_geometry import PartChannels

__all__ = ["ChannelNodes", "channel_nodes", "channel_frame", "geometry_sets", "VP_CODES"]

#: Direction codes of the virtual-point components.
VP_CODES = {"ux": 1, "uy": 2, "uz": 3, "rx": 4, "ry": 5, "rz": 6}


@dataclass
class ChannelNodes:
    """The nodes of the points of a result with channels.

    Attributes:
        where: point name -> ``(node, direction code)``.
        xyz: node -> global position (every node ``1 .. n``).
        disp_cs: node -> the label of its displacement system (0 global).
        systems: label -> ``(A, origin)`` of the 2420 systems written.
    """

    where: dict[str, tuple[int, int]] = field(default_factory=dict)
    xyz: dict[int, np.ndarray] = field(default_factory=dict)
    disp_cs: dict[int, int] = field(default_factory=dict)
    systems: dict[int, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)


def channel_frame(e: Sequence[float]) -> np.ndarray:
    r"""The rows :math:`[e;\ e_2;\ e_3]` of a right-handed orthonormal system whose first
    axis is the unit vector ``e`` itself (module docstring)."""
    u = np.asarray(e, dtype=float)
    a = np.zeros(3)
    a[int(np.argmin(np.abs(u)))] = 1.0
    e2 = a - (a @ u) * u
    e2 /= np.linalg.norm(e2)
    return np.array([u, e2, np.cross(u, e2)])


def _split(name: str, channels: Mapping[str, PartChannels]
           ) -> tuple[str, str, str] | None:
    """``(part, kind, rest)`` of a virtual-point or channel point of a part with channels."""
    part, at, local = name.partition("@")
    if not at or part not in channels:
        return None
    kind, _, rest = local.partition(":")
    pc = channels[part]
    if kind == "vp":
        point, _, comp = rest.rpartition(":")
        if point in pc.points and comp in VP_CODES:
            return part, "vp", rest
    elif kind == "ch" and any(c.name == rest for c in pc.table.channels):
        return part, "ch", rest
    return None


def channel_nodes(points: Sequence[str], coordinates: Sequence[str],
                  channels: Mapping[str, PartChannels]) -> ChannelNodes:
    """Node and direction of every point (module docstring): the others first by
    :func:`substruct.io.uff.frf_nodes` (nodes ``1 .. m``, at ``(k, 0, 0)``), then one node per
    virtual point and per channel, numbered after them in the order of ``points``."""
    from substruct.io.uff import frf_nodes

    mine = [p for p in points if _split(p, channels) is not None]
    others, last = frf_nodes([p for p in points if p not in set(mine)], coordinates)
    out = ChannelNodes(dict(others))
    for k in range(1, last + 1):
        out.xyz[k], out.disp_cs[k] = np.array([float(k), 0.0, 0.0]), 0
    owners: dict[tuple[str, str], int] = {}
    for p in mine:
        if p in out.where:
            continue
        got = _split(p, channels)
        assert got is not None
        part, kind, rest = got
        pc = channels[part]
        if kind == "vp":
            point, _, comp = rest.rpartition(":")
            key = (part, f"vp:{point}")
            if key not in owners:
                last += 1
                owners[key] = last
                xyz = pc.point_xyz[pc.points.index(point)]
                out.xyz[last], out.disp_cs[last] = np.array(xyz, dtype=float), 0
            out.where[p] = (owners[key], VP_CODES[comp])
        else:
            c = pc.table.get(rest)
            last += 1
            pos = np.array(c.position, dtype=float)
            out.xyz[last], out.disp_cs[last] = pos, last
            out.systems[last] = (channel_frame(c.direction), pos)
            out.where[p] = (last, 1)
    return out


def geometry_sets(nodes: ChannelNodes, name: str) -> list[dict[str, Any]]:
    """The 151 (the case ``name``), 164 (SI), 2411 (every node) and 2420 (the channels'
    systems, if any) datasets of ``nodes``, as ``pyuff`` writes them."""
    import pyuff

    labels = np.array(sorted(nodes.xyz), dtype=int)
    xyz = np.array([nodes.xyz[k] for k in labels], dtype=float).reshape(-1, 3)
    sets = [pyuff.prepare_151(model_name=name[:80], description="substruct test geometry "
                              "and receptances", db_app="substruct", program="substruct"),
            pyuff.prepare_164(units_code=1, units_description="SI: meter (newton)",
                              temp_mode=1, length=1.0, force=1.0, temp=1.0,
                              temp_offset=0.0),
            pyuff.prepare_2411(node_nums=labels, def_cs=np.zeros(len(labels), dtype=int),
                               disp_cs=np.array([nodes.disp_cs[k] for k in labels], dtype=int),
                               color=np.ones(len(labels), dtype=int), x=xyz[:, 0],
                               y=xyz[:, 1], z=xyz[:, 2])]
    if nodes.systems:
        cs = sorted(nodes.systems)
        sets.append(pyuff.prepare_2420(
            Part_UID=1, Part_Name=f"substruct {name}"[:80], CS_sys_labels=cs,
            CS_types=[0] * len(cs), CS_colors=[8] * len(cs),
            CS_names=[f"channel node {k}" for k in cs],
            CS_matrices=[np.vstack([nodes.systems[k][0], nodes.systems[k][1]]) for k in cs]))
    return sets
