r"""The geometry of a test from a Universal File: channel positions and directions from the
nodes of datasets 15/2411 in the coordinate systems of 18/2420, the channels named by the
functions of 58.

A coordinate system is a rotation :math:`A` (its rows the unit axes in global coordinates) and
an origin :math:`o`: a point at local :math:`x_l` is at :math:`x = o + A^T x_l`.

* dataset 2420: records 5-7 are the rows of :math:`A`, record 8 is :math:`o`;
* dataset 18 (method of definition 1): the origin :math:`o'`, a point :math:`p` on +x and a
  point :math:`q` in the +xz plane, given in the reference system ``ref`` (0 global, or one
  defined before): :math:`e_x = (p - o')/\lvert p - o' \rvert`,
  :math:`e_y = e_z \times e_x`, :math:`e_z = e_x \times (q - o') / \lvert\cdot\rvert`.

A node's coordinates are in its definition system, its direction codes in its displacement
system: the response of record 6 field 7 (or the reference, field 10) of a 58 at code
:math:`\pm k` (1..3) reads along :math:`\pm A_{disp}[k]`.  The receptances read from a UFF
file are signed to the positive axis (:mod:`substruct.case.frf_files`), so the channel
``<node>.<x|y|z>`` (the label ``<node>:<x|y|z>`` of the receptances read from the file, as a
name of the case) has the direction :math:`+A_{disp}[k]` at the node's global position; a
response node's channels are sensors, a reference node's impacts.

Lengths are in meters when the file has a units dataset 164: its records are read in SI
(:func:`substruct.case.uff_units.to_si`); the table then records the unit ``m`` and the
file's header (151).

Honoured: cartesian systems (type 0), 18 with method 1, translations (codes 1-3).  Refused in
one line: cylindrical and spherical systems, other methods, a system defined twice or not
orthonormal (2420, to 1e-6) or degenerate (18: the three points on a line), a node in a system
the file does not define, a function at a node without coordinates, a rotation or scalar code,
a channel that is both a response and a reference.
"""

from __future__ import annotations

import os
from dataclasses import replace
from pathlib import Path

import numpy as np

from substruct.case.channels import ChannelTable, parse_channels
from substruct.case.uff_records import UffFile, UffSystem, read_uff_records

__all__ = ["uff_coordinate_systems", "node_positions", "channels_from_uff"]

_AXES = ("x", "y", "z")


def _from_18(s: UffSystem, known: dict[int, tuple[np.ndarray, np.ndarray]]
             ) -> tuple[np.ndarray, np.ndarray]:
    if s.method != 1:
        raise ValueError(f"{s.where}: method of definition {s.method} is not supported (1: "
                         "origin, a point on +x, a point in the +xz plane)")
    if s.ref not in known:
        raise ValueError(f"{s.where}: reference coordinate system {s.ref} is not defined "
                         "before it")
    A_ref, o_ref = known[s.ref]
    o, p, q = (o_ref + A_ref.T @ np.asarray(v, dtype=float) for v in s.matrix)
    ex, xz = p - o, q - o
    scale = max(float(np.linalg.norm(ex)), float(np.linalg.norm(xz)), 1e-300)
    ez = np.cross(ex, xz)
    if np.linalg.norm(ex) <= 1e-9 * scale or np.linalg.norm(ez) <= 1e-9 * scale ** 2:
        raise ValueError(f"{s.where}: the origin, the +x point and the +xz point are on one "
                         "line: no coordinate system")
    ex, ez = ex / np.linalg.norm(ex), ez / np.linalg.norm(ez)
    return np.array([ex, np.cross(ez, ex), ez]), o


def uff_coordinate_systems(uff: UffFile) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """Every coordinate system of the file, label -> ``(A, o)`` (module docstring), with the
    global system 0.

    Raises:
        ValueError: a system that is not cartesian, defined twice, not orthonormal or
            degenerate, or an 18 of another method or reference.
    """
    out: dict[int, tuple[np.ndarray, np.ndarray]] = {0: (np.eye(3), np.zeros(3))}
    for s in uff.systems:
        if s.kind != 0:
            kind = {1: "cylindrical", 2: "spherical"}.get(s.kind, f"of type {s.kind}")
            raise ValueError(f"{s.where}: coordinate system {s.label} is {kind}; only "
                             "cartesian systems (type 0) are supported")
        if s.label in out:
            raise ValueError(f"{s.where}: coordinate system {s.label} is defined twice")
        if s.dataset == 2420:
            A = np.array(s.matrix[:3], dtype=float)
            if not np.all(np.isfinite(s.matrix)) or \
                    np.abs(A @ A.T - np.eye(3)).max() > 1e-6 or np.linalg.det(A) < 0:
                raise ValueError(f"{s.where}: the axes of coordinate system {s.label} "
                                 "(records 5-7) are not a right-handed orthonormal triad")
            out[s.label] = (A, np.array(s.matrix[3], dtype=float))
        else:
            out[s.label] = _from_18(s, out)
    return out


def node_positions(uff: UffFile, systems: dict[int, tuple[np.ndarray, np.ndarray]]
                   ) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """Every node with coordinates: label -> ``(global position, A of its displacement
    system)``.

    Raises:
        ValueError: a node in a coordinate system the file does not define, or coordinates
            that are not finite.
    """
    out = {}
    for label, node in uff.node_table.items():
        for cs, what in ((node.def_cs, "definition"), (node.disp_cs, "displacement")):
            if cs not in systems:
                raise ValueError(f"node {label}: its {what} coordinate system {cs} is not "
                                 "defined in the file (datasets 18/2420)")
        if not np.all(np.isfinite(node.xyz)):
            raise ValueError(f"node {label}: coordinates that are not finite "
                             f"{[float(v) for v in node.xyz]}")
        A, o = systems[node.def_cs]
        out[label] = (o + A.T @ np.asarray(node.xyz, dtype=float), systems[node.disp_cs][0])
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
    except ValueError as err:  # a system's message names the file already, a node's not
        text = str(err)
        raise ValueError(text if text.startswith(p.name) else f"{p.name}: {text}") from None
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
