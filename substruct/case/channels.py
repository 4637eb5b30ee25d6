r"""The geometry of a test: sensor and impact channels with positions and directions.

A channel table is a plain CSV file (a header row, then one channel a row) or a YAML file
(``channels:`` a list of mappings), with the columns

==========  ==================================================================
``name``    the channel's name, unique in the table (letters, digits, ``_ . -``)
``node``    the test-geometry node it sits on (a name or a number; several channels
            may share a node: the three axes of a triaxial sensor)
``x y z``   its position (any length unit, the same for the whole table)
``dx dy dz`` its direction: the sense of a positive response (sensor) or force (impact);
            normalised on reading
``kind``    ``sensor`` or ``impact``
==========  ==================================================================

.. code-block:: text

    name,node,x,y,z,dx,dy,dz,kind
    S1x,101,0.03,0.02,0.0,1,0,0,sensor
    H1,201,0.04,-0.03,0.01,0,0,-1,impact

Every check names the row and the column: a column missing or unknown, a value missing or not
a finite number, a name repeated, a direction of zero length, two channels of the same kind
at the same place in the same direction (one would be a copy of the other), more than
:data:`MAX_CHANNELS` rows, a line that is not a CSV row (a field beyond the csv module's
limit of 131072 characters).  Errors are :class:`~substruct.case.errors.CaseError`:
``<file>: line 4.dx: <problem>, got <value>`` (CSV) or ``<file>: channels.2.dx: ...`` (YAML).
"""

from __future__ import annotations

import csv
import io
import os
import re
import stat
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from substruct.case.errors import CaseError
from substruct.case.fields import MAX_NAME_LENGTH, NAME_PATTERN
from substruct.case.yaml_io import load_yaml

__all__ = ["Channel", "ChannelTable", "COLUMNS", "CHANNEL_KINDS", "MAX_CHANNELS", "MAX_CHANNEL_FILE",
           "parse_channels", "read_channel_table", "check_channel_file", "write_channels"]

#: The columns of a channel table, in the order written.
COLUMNS = ("name", "node", "x", "y", "z", "dx", "dy", "dz", "kind")
#: The kinds of channel.
CHANNEL_KINDS = ("sensor", "impact")
#: Most channels in one table.
MAX_CHANNELS = 100_000
#: Largest channel file read, in bytes.
MAX_CHANNEL_FILE = 50_000_000
#: Two channels are at the same place if closer than this fraction of the table's extent
#: (the largest distance between two channels), in the same direction if their unit vectors
#: differ by less than this.
SAME_PLACE = 1e-9


@dataclass(frozen=True)
class Channel:
    """One sensor or impact channel.

    Attributes:
        name: unique in its table.
        node: the test-geometry node (text).
        position: ``(x, y, z)``.
        direction: unit vector ``(dx, dy, dz)``.
        kind: ``"sensor"`` or ``"impact"``.
    """

    name: str
    node: str
    position: tuple[float, float, float]
    direction: tuple[float, float, float]
    kind: str


@dataclass(frozen=True)
class ChannelTable:
    """The channels of a test, in file order; ``units`` the length unit of the positions
    when the file states it (``"m"``: a Universal File with a units dataset 164, converted),
    ``header`` the names and dates of a Universal File's header (151), as ``(key, text)``."""

    channels: tuple[Channel, ...]
    source: str = "<channels>"
    units: str = ""
    header: tuple[tuple[str, str], ...] = ()

    def of_kind(self, kind: str) -> list[Channel]:
        """The channels of one kind, in file order."""
        return [c for c in self.channels if c.kind == kind]

    def get(self, name: str) -> Channel:
        """The channel called ``name``.

        Raises:
            KeyError: no such channel (the message lists up to ten known names).
        """
        for c in self.channels:
            if c.name == name:
                return c
        known = ", ".join(c.name for c in self.channels[:10])
        raise KeyError(f"{self.source}: no channel {name!r} (it has {known}"
                       f"{', ...' if len(self.channels) > 10 else ''})")

    def positions(self, names: Sequence[str]) -> np.ndarray:
        """``(n, 3)`` positions of the named channels."""
        return np.array([self.get(n).position for n in names], dtype=float).reshape(-1, 3)

    def directions(self, names: Sequence[str]) -> np.ndarray:
        """``(n, 3)`` unit directions of the named channels."""
        return np.array([self.get(n).direction for n in names], dtype=float).reshape(-1, 3)


def _number(source: str, where: str, value: Any) -> float:
    if isinstance(value, bool) or value is None or (isinstance(value, str) and not value.strip()):
        raise CaseError(source, where, "a number is needed", value)
    try:
        x = float(value)
    except (TypeError, ValueError, OverflowError):
        raise CaseError(source, where, "not a number", value) from None
    if not np.isfinite(x):
        raise CaseError(source, where, "not a finite number", value)
    return x


def _text(source: str, where: str, value: Any, pattern: bool) -> str:
    if value is None or isinstance(value, (bool, list, dict)):
        raise CaseError(source, where, "a name is needed", value)
    text = str(value).strip()
    if not text:
        raise CaseError(source, where, "a name is needed", value)
    if len(text) > MAX_NAME_LENGTH or (pattern and not re.match(NAME_PATTERN, text)):
        raise CaseError(source, where, f"a name of at most {MAX_NAME_LENGTH} letters, digits, "
                        f"'_', '.' or '-'", value)
    return text


def parse_channels(rows: Sequence[Mapping[str, Any]], source: str,
                   where: Sequence[str] | None = None) -> ChannelTable:
    r"""Channels from rows of ``{column: value}``, checked (module docstring).

    Args:
        rows: one mapping per channel.
        source: the file, for messages.
        where: the field path of each row (default ``channels.<i>``).

    The direction is normalised, :math:`e = d / \lVert d \rVert`.

    Raises:
        CaseError: the first problem, naming the row and column.
    """
    if len(rows) > MAX_CHANNELS:
        raise CaseError(source, "channels", f"at most {MAX_CHANNELS} channels", len(rows))
    if not rows:
        raise CaseError(source, "channels", "no channel given")
    paths = list(where) if where is not None else [f"channels.{i}" for i in range(len(rows))]
    out: list[Channel] = []
    seen: dict[str, str] = {}
    for row, at in zip(rows, paths):
        if not isinstance(row, Mapping):
            raise CaseError(source, at, "a channel is a mapping of " + ", ".join(COLUMNS), row)
        for key in row:
            if key not in COLUMNS:
                raise CaseError(source, f"{at}.{key}", "unknown column (the columns are "
                                f"{', '.join(COLUMNS)})")
        for key in COLUMNS:
            if key not in row:
                raise CaseError(source, f"{at}.{key}", "missing")
        name = _text(source, f"{at}.name", row["name"], True)
        if name in seen:
            raise CaseError(source, f"{at}.name", f"repeated (first at {seen[name]})", name)
        seen[name] = at
        node = _text(source, f"{at}.node", row["node"], True)
        pos = tuple(_number(source, f"{at}.{k}", row[k]) for k in ("x", "y", "z"))
        d = np.array([_number(source, f"{at}.{k}", row[k]) for k in ("dx", "dy", "dz")])
        big = float(np.abs(d).max())
        if not big > 0:
            raise CaseError(source, f"{at}.dx", "the direction (dx, dy, dz) has zero length",
                            d.tolist())
        e = (d / big) / np.linalg.norm(d / big)  # scaled first: no overflow or underflow
        kind = row["kind"]
        if not isinstance(kind, str) or kind.strip().lower() not in CHANNEL_KINDS:
            raise CaseError(source, f"{at}.kind", f"one of {', '.join(CHANNEL_KINDS)}", kind)
        out.append(Channel(name, node, (pos[0], pos[1], pos[2]),
                           (float(e[0]), float(e[1]), float(e[2])), kind.strip().lower()))
    _check_copies(out, paths, source)
    return ChannelTable(tuple(out), source)


def _check_copies(channels: list[Channel], paths: list[str], source: str) -> None:
    """Two channels of one kind at the same place in the same direction: refused."""
    xyz = np.array([c.position for c in channels])
    extent = float(np.ptp(xyz, axis=0).max()) if len(channels) > 1 else 0.0
    e = np.array([c.direction for c in channels])
    kinds = np.array([c.kind for c in channels])
    from scipy.spatial import cKDTree  # imported where used (start-up time)
    for i, j in sorted(cKDTree(xyz).query_pairs(SAME_PLACE * extent)):
        if kinds[i] == kinds[j] and np.abs(e[i] - e[j]).max() < SAME_PLACE:
            c = channels[j]
            raise CaseError(source, paths[j], f"{c.kind} {c.name!r} is at the place and in the "
                            f"direction of {channels[i].name!r} ({paths[i]}): a duplicate",
                            list(c.position))


def check_channel_file(path: Path) -> None:
    """Refuse a channel file that cannot be read, is not a regular file or is larger than
    :data:`MAX_CHANNEL_FILE` bytes (:class:`CaseError`, before anything is read)."""
    try:
        info = os.stat(path)
    except OSError as err:
        raise CaseError(path.name, "", f"cannot read the channel file: {err.strerror}") \
            from None
    if not stat.S_ISREG(info.st_mode):
        raise CaseError(path.name, "", "the channel file is not a regular file")
    if info.st_size > MAX_CHANNEL_FILE:
        raise CaseError(path.name, "", f"more than {MAX_CHANNEL_FILE} bytes", info.st_size)


def read_channel_table(path: str | os.PathLike) -> ChannelTable:
    """A channel table from a ``.csv`` or a ``.yaml``/``.yml`` file (module docstring); a
    Universal File is read by :func:`substruct.case.channel_files.read_channels`.

    Raises:
        CaseError: an unreadable file, an unknown suffix, or a problem with a row.
    """
    p = Path(path)
    check_channel_file(p)
    source = p.name
    try:
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise CaseError(source, "", "the channel file is not UTF-8 text") from None
    suffix = p.suffix.lower()
    if suffix in (".yaml", ".yml"):
        data = load_yaml(text, source)
        if not isinstance(data, Mapping) or set(data) != {"channels"} or \
                not isinstance(data["channels"], list):
            raise CaseError(source, "", "a YAML channel file is a mapping with one key, "
                            "channels: a list of channels")
        return parse_channels(data["channels"], source)
    if suffix != ".csv":
        raise CaseError(source, "", "a channel file is .csv, .yaml, .yml, .uff or .unv",
                        p.suffix)
    reader = csv.reader(io.StringIO(text))
    try:  # a field beyond csv's limit (131072 characters) is a csv.Error
        lines = [(reader.line_num, r) for r in reader if any(c.strip() for c in r)]
    except csv.Error as err:
        raise CaseError(source, f"line {reader.line_num}", f"not a CSV row ({err})") from None
    if not lines:
        raise CaseError(source, "", "no header row (" + ",".join(COLUMNS) + ")")
    header = [h.strip() for h in lines[0][1]]
    for h in header:
        if h not in COLUMNS:
            raise CaseError(source, "line 1", f"unknown column (the columns are "
                            f"{', '.join(COLUMNS)})", h)
    if len(set(header)) != len(header):
        raise CaseError(source, "line 1", "a column is repeated", ",".join(header))
    if len(lines) - 1 > MAX_CHANNELS:
        raise CaseError(source, "", f"at most {MAX_CHANNELS} channels", len(lines) - 1)
    rows, where = [], []
    for num, cells in lines[1:]:
        if len(cells) != len(header):
            raise CaseError(source, f"line {num}", f"{len(header)} values expected",
                            len(cells))
        rows.append(dict(zip(header, (c.strip() for c in cells))))
        where.append(f"line {num}")
    return parse_channels(rows, source, where)


def write_channels(table: ChannelTable, path: str | os.PathLike) -> None:
    """Write a channel table as CSV (the columns of :data:`COLUMNS`, positions and directions
    with 17 significant digits: read back exactly)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(COLUMNS)
    for c in table.channels:
        w.writerow([c.name, c.node, *(repr(float(v)) for v in c.position),
                    *(repr(float(v)) for v in c.direction), c.kind])
    Path(path).write_text(buf.getvalue(), encoding="utf-8")
