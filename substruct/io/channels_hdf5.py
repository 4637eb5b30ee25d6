r"""The ``/channels/`` group of a results file: the geometry of the test of a virtual-point
case (:mod:`substruct.case.channel_geometry`), one numbered group per part,
``/channels/<i>/``, attributes ``part``, ``source`` (the channel file's name), ``units`` (the
length unit when the file stated it, ``"m"`` for a Universal File with a units dataset 164,
else empty), and the datasets

==================  ===============================================================
``names``           the channels' names (strings)
``nodes``           their test-geometry nodes (strings)
``kinds``           ``sensor`` or ``impact``
``positions``       ``n x 3``, global
``directions``      ``n x 3``, global unit vectors
``points``          the virtual points' names
``point_positions`` ``n_points x 3``
==================  ===============================================================

and, for a table read from a Universal File with a header (151), the subgroup ``header``
with its names and dates as string attributes.  Read back through
:func:`~substruct.case.channels.parse_channels`: every check of a channel table holds.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import h5py
import numpy as np

if TYPE_CHECKING:  # the case layer (pydantic) only when a result has channels
    from substruct.case.channel_geometry import PartChannels

__all__ = ["write_channel_geometry", "read_channel_geometry"]

_STR = h5py.string_dtype("utf-8")
#: The keys of a header (151) kept with a table.
_HEADER_KEYS = ("model_name", "description", "database_program", "database_created",
                "database_saved", "program", "file_written")


def _strings(g: h5py.Group, key: str, values: list[str]) -> None:
    g.create_dataset(key, data=np.array(values, dtype=object), dtype=_STR,
                     shape=(len(values),))


def write_channel_geometry(group: h5py.Group, parts: dict[str, PartChannels]) -> None:
    """Write each part's channels and virtual points (module docstring) under ``group``."""
    for i, (part, pc) in enumerate(parts.items()):
        g = group.create_group(str(i), track_order=True)
        t = pc.table
        g.attrs["part"], g.attrs["source"], g.attrs["units"] = str(part), t.source, t.units
        _strings(g, "names", [c.name for c in t.channels])
        _strings(g, "nodes", [c.node for c in t.channels])
        _strings(g, "kinds", [c.kind for c in t.channels])
        for key, attr in (("positions", "position"), ("directions", "direction")):
            g.create_dataset(key, data=np.array([getattr(c, attr) for c in t.channels],
                                                dtype=float).reshape(-1, 3))
        _strings(g, "points", list(pc.points))
        g.create_dataset("point_positions", data=np.asarray(pc.point_xyz, dtype=float))
        if t.header:
            h = g.create_group("header")
            for key, text in t.header:
                h.attrs[key] = str(text)


def _text(g: h5py.Group, key: str) -> str:
    v = g.attrs.get(key)
    if not isinstance(v, (str, bytes)):
        raise ValueError(f"{g.name} has no text attribute {key}")
    return v.decode("utf-8", "replace") if isinstance(v, bytes) else v


def read_channel_geometry(rd: Any, groups: list[h5py.Group]) -> dict[str, PartChannels]:
    """The geometry written by :func:`write_channel_geometry` in the numbered ``groups`` (in
    order), checked: one row per channel, finite positions, directions of unit length (to
    1e-12), every check of :func:`~substruct.case.channels.parse_channels`, a part named
    once.  ``rd`` is the result reader (its ``array`` and ``strings`` check each dataset's
    rank, kind and size before reading).

    Raises:
        ValueError: one line naming the group and what is wrong.
    """
    from substruct.case.channel_geometry import PartChannels
    from substruct.case.channels import Channel, ChannelTable, parse_channels
    from substruct.case.errors import CaseError

    out: dict[str, PartChannels] = {}
    for g in groups:
        part = _text(g, "part")
        if part in out:
            raise ValueError(f"{g.name}: part {part!r} twice in /channels")
        names = rd.strings(g, "names")
        n = len(names)
        nodes, kinds = rd.strings(g, "nodes", n), rd.strings(g, "kinds", n)
        xyz = rd.array(g, "positions", "f", 2, (n, 3), finite=True)
        e = rd.array(g, "directions", "f", 2, (n, 3), finite=True)
        if n and np.abs(np.linalg.norm(e, axis=1) - 1).max() > 1e-12:
            raise ValueError(f"{g.name}/directions holds a direction that is not of unit "
                             "length")
        points = rd.strings(g, "points")
        p_xyz = rd.array(g, "point_positions", "f", 2, (len(points), 3), finite=True)
        rows = [dict(name=names[i], node=nodes[i], x=xyz[i, 0], y=xyz[i, 1], z=xyz[i, 2],
                     dx=e[i, 0], dy=e[i, 1], dz=e[i, 2], kind=kinds[i]) for i in range(n)]
        try:
            table = parse_channels(rows, _text(g, "source"))
        except CaseError as err:
            raise ValueError(f"{g.name}: {' '.join(str(err).split())}") from None
        header: tuple[tuple[str, str], ...] = ()
        if "header" in g:
            h = rd.node(g, "header", h5py.Group)
            header = tuple((k, _text(h, k)) for k in _HEADER_KEYS if k in h.attrs)
        exact = tuple(Channel(c.name, c.node, c.position, (float(e[i, 0]), float(e[i, 1]),
                                                           float(e[i, 2])), c.kind)
                      for i, c in enumerate(table.channels))  # as stored, not renormalised
        table = ChannelTable(exact, table.source, _text(g, "units"), header)
        out[part] = PartChannels(table, tuple(points), p_xyz)
    return out
