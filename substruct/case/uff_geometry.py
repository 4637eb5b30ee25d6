r"""The geometry of a test from a Universal File: channel positions and directions from the
nodes of datasets 15/2411 in the coordinate systems of 18/2420, the channels named by the
functions of 58.

A coordinate system is a rotation :math:`A` (its rows the unit axes in global coordinates) and
an origin :math:`o`: a point at local :math:`x_l` is at :math:`x = o + A^T x_l`.

* dataset 2420: records 5-7 are the rows of :math:`A`, record 8 is :math:`o`;
* dataset 18 (method of definition 1): the origin :math:`o'`, a point :math:`p` on +x and a
  point :math:`q` in the +xz plane, given in the reference system ``ref`` (0 global, or one
  defined before): :math:`e_x = (p - o')/\lvert p - o' \rvert`,
  :math:`e_y = (q - o') \times e_x / \lvert\cdot\rvert`, :math:`e_z = e_x \times e_y`
  (:math:`q - o'` has a positive component along :math:`e_z` and none along :math:`e_y`).

A node's coordinates are in its definition system, its direction codes in its displacement
system: the response of record 6 field 7 (or the reference, field 10) of a 58 at code
:math:`\pm k` (1..3) reads along :math:`\pm A_{disp}[k]` (a cartesian displacement system;
below for the others).  The receptances read from a UFF
file are signed to the positive axis (:mod:`substruct.case.frf_files`), so the channel
``<node>.<x|y|z>`` (the label ``<node>:<x|y|z>`` of the receptances read from the file, as a
name of the case) has the direction :math:`+A_{disp}[k]` at the node's global position; a
response node's channels are sensors, a reference node's impacts.

Lengths are in meters when the file has a units dataset 164: its records are read in SI
(:func:`substruct.case.uff_units.to_si`); the table then records the unit ``m`` and the
file's header (151).

Cylindrical and spherical systems (types 1 and 2) are read as :mod:`substruct.case.uff_frames`
says: a node's coordinates :math:`(r, \theta, z)` or :math:`(r, \theta, \varphi)` (degrees)
in its definition system, the codes 1-3 along the unit vectors of those coordinates at the node
in its displacement system; an 18 given in such a reference system has its three points in
that system's coordinates.

Honoured: system types 0, 1, 2, 18 with method 1, translations (codes 1-3).  Refused in one
line: another system type, other methods, a system defined twice or not orthonormal (2420, to
1e-6) or degenerate (18: the three points on a line), a node in a system the file does not
define, a node on the axis of a cylindrical or spherical displacement system it is not defined
in (no radial direction), a function at a node without coordinates, a rotation or scalar
code, a channel that is both a response and a reference.
"""

from __future__ import annotations

import os
from dataclasses import replace
from pathlib import Path

import numpy as np

from substruct.case.channels import ChannelTable, parse_channels
from substruct.case.uff_frames import (SYSTEM_TYPES, UffFrame, angles_of, frame_axes,
                                      local_to_cartesian)
from substruct.case.uff_records import UffFile, UffSystem, read_uff_records

__all__ = ["uff_coordinate_systems", "node_positions", "channels_from_uff"]

_AXES = ("x", "y", "z")


def _from_18(s: UffSystem, known: dict[int, UffFrame]) -> UffFrame:
    if s.method != 1:
        raise ValueError(f"{s.where}: method of definition {s.method} is not supported (1: "
                         "origin, a point on +x, a point in the +xz plane)")
    if s.ref not in known:
        raise ValueError(f"{s.where}: reference coordinate system {s.ref} is not defined "
                         "before it")
    ref = known[s.ref]
    o, p, q = (ref.o + ref.A.T @ local_to_cartesian(ref.kind, np.asarray(v, dtype=float))
               for v in s.matrix)
    ex, xz = p - o, q - o
    scale = max(float(np.linalg.norm(ex)), float(np.linalg.norm(xz)), 1e-300)
    ey = np.cross(xz, ex)
    if np.linalg.norm(ex) <= 1e-9 * scale or np.linalg.norm(ey) <= 1e-9 * scale ** 2:
        raise ValueError(f"{s.where}: the origin, the +x point and the +xz point are on one "
                         "line: no coordinate system")
    ex, ey = ex / np.linalg.norm(ex), ey / np.linalg.norm(ey)
    return UffFrame(np.array([ex, ey, np.cross(ex, ey)]), o, s.kind)


def uff_coordinate_systems(uff: UffFile) -> dict[int, UffFrame]:
    """Every coordinate system of the file, label -> ``UffFrame(A, o, kind)`` (module
    docstring), with the global system 0.

    Raises:
        ValueError: a system of a type not 0, 1 or 2, defined twice, not orthonormal or
            degenerate, or an 18 of another method or reference.
    """
    out: dict[int, UffFrame] = {0: UffFrame(np.eye(3), np.zeros(3), 0)}
    for s in uff.systems:
        if s.kind not in SYSTEM_TYPES:
            field = "record 3 field 2" if s.dataset == 2420 else "record 1 field 2"
            raise ValueError(f"{s.where}: {field}, coordinate system {s.label} of type "
                             f"{s.kind}: not 0 (cartesian), 1 (cylindrical) or 2 (spherical)")
        if s.label in out:
            raise ValueError(f"{s.where}: coordinate system {s.label} is defined twice")
        if s.dataset == 2420:
            A = np.array(s.matrix[:3], dtype=float)
            if not np.all(np.isfinite(s.matrix)) or \
                    np.abs(A @ A.T - np.eye(3)).max() > 1e-6 or np.linalg.det(A) < 0:
                raise ValueError(f"{s.where}: the axes of coordinate system {s.label} "
                                 "(records 5-7) are not a right-handed orthonormal triad")
            out[s.label] = UffFrame(A, np.array(s.matrix[3], dtype=float), s.kind)
        else:
            out[s.label] = _from_18(s, out)
    return out


def node_positions(uff: UffFile, systems: dict[int, UffFrame]
                   ) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """Every node with coordinates: label -> ``(global position, axes)``, the rows of
    ``axes`` the global unit vectors of its direction codes 1, 2, 3 (its displacement
    system's axes, or its cylindrical or spherical unit vectors at the node).

    Raises:
        ValueError: a node in a coordinate system the file does not define, coordinates
            that are not finite, or a node on the axis of a cylindrical or spherical
            displacement system that it is not defined in.
    """
    out = {}
    for label, node in uff.node_table.items():
        for cs, what, at in ((node.def_cs, "definition", 2), (node.disp_cs, "displacement", 3)):
            if cs not in systems:
                raise ValueError(f"node {label}: record 1 field {at}, {what} coordinate "
                                 f"system {cs}: not defined in the file (datasets 18/2420)")
        if not np.all(np.isfinite(node.xyz)):
            raise ValueError(f"node {label}: coordinates that are not finite "
                             f"{[float(v) for v in node.xyz]}")
        own, disp = systems[node.def_cs], systems[node.disp_cs]
        c = np.asarray(node.xyz, dtype=float)
        pos = own.o + own.A.T @ local_to_cartesian(own.kind, c)
        angles: tuple[float, float] | None = (0.0, 0.0)
        if disp.kind and node.def_cs == node.disp_cs:
            angles = (float(np.deg2rad(c[1])), float(np.deg2rad(c[2])))
        elif disp.kind:
            angles = angles_of(disp.kind, disp.A @ (pos - disp.o))
        if angles is None:
            raise ValueError(f"node {label}: it lies on the axis of its "
                             f"{SYSTEM_TYPES[disp.kind]} displacement coordinate system "
                             f"{node.disp_cs}, where its directions are not defined (at "
                             f"{[float(v) for v in pos]})")
        out[label] = (pos, frame_axes(disp, angles))
    return out


def channels_from_uff(path: str | os.PathLike) -> ChannelTable:
    """The channel table of a Universal File (module docstring): one channel per response
    and per reference ``<node>.<x|y|z>`` of its 58 functions, in the order met.

    Raises:
        ValueError: one line naming the file and the dataset (module docstring), or a
            problem of the table itself (:func:`~substruct.case.channels.parse_channels`).
    """
    p = Path(path)
    uff = read_uff_records(p)
    try:
        where = node_positions(uff, uff_coordinate_systems(uff))
    except ValueError as err:  # a system's message names the file (its dataset), a node's not
        text = str(err)
        raise ValueError(text if text.startswith(f"{p.name}: ") else f"{p.name}: {text}"
                         ) from None
    if not uff.functions:
        raise ValueError(f"{p.name} holds no UFF 58 function to name the channels")
    kinds: dict[str, str] = {}
    rows = []
    for f in uff.functions:
        for node, code, kind, rec in ((f.rsp_node, f.rsp_dir, "sensor", "6 and 7 (response)"),
                                      (f.ref_node, f.ref_dir, "impact", "9 and 10 (reference)")):
            if not 1 <= abs(code) <= 3:
                raise ValueError(f"{f.where}: record 6 fields {rec}: direction {code} at node "
                                 f"{node} is not a translation (+-1..3): not a channel")
            if node not in where:
                raise ValueError(f"{f.where}: record 6 fields {rec}: node {node} has no "
                                 "coordinates in the file's datasets 15/2411")
            name = f"{node}.{_AXES[abs(code) - 1]}"
            if kinds.get(name, kind) != kind:
                raise ValueError(f"{f.where}: channel {name} is both a response and a "
                                 "reference: a channel table gives a channel one kind")
            if name in kinds:
                continue
            kinds[name] = kind
            pos, A = where[node]
            d = A[abs(code) - 1]
            rows.append(dict(name=name, node=str(node), x=pos[0], y=pos[1], z=pos[2],
                             dx=d[0], dy=d[1], dz=d[2], kind=kind))
    table = parse_channels(rows, p.name)
    header = () if uff.header is None else tuple(uff.header.attributes().items())
    return replace(table, units="" if uff.units is None else "m", header=header)
