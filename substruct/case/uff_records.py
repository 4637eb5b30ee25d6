r"""The records of a Universal File: the functions of dataset 58 (ASCII and binary ``58b``),
the nodes of datasets 15 and 2411, the coordinate systems of 18 and 2420, the header (151) and
the units (164, :mod:`substruct.case.uff_units`), read in one pass with every size checked
first.  A 164 must come before every dataset whose numbers it scales (58, 15, 2411, 18, 2420)
and at most once; a second 151 is refused too.  The records are returned in SI
(:func:`substruct.case.uff_units.to_si`).

The file is read line by line (no line longer than :data:`MAX_UFF_LINE` bytes), never whole.  A
58 dataset is parsed by the fixed columns of its specification (records 6-11:
``2(I5,I10),2(1X,10A1,I10,I4)``, ``3I10,3E13.5``, ``I10,3I5,2(1X,20A1)``); its data (record
12) only after the points it declares (record 7 field 2) are known to be at most
:data:`MAX_POINTS`, to fit in what is left of the file, and, with the points of the functions
before it, to fit in :data:`~substruct.case.fields.MEMORY_LIMIT`.  Record 12 must then hold
exactly the values declared (``ASCII``: the columns of the spec's case 1-8 formats; ``58b``:
the bytes of its values in the declared precision, as many as its id line declares, or the
count ``pyuff`` writes there, one value a point: ``num_pts * 8`` for doubles).  What the codes mean is checked by the caller
(:mod:`substruct.case.frf_files`).  The datasets that only draw the geometry or name the
model (:data:`DRAWING_DATASETS`: 82 trace lines, 2400, 2412 elements) are passed over; any
other (:data:`READ_DATASETS` are read; e.g. 1858, whose weighting and window codes would
qualify the functions) is refused: it would go unused.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from substruct.case.fields import MEMORY_LIMIT
from substruct.case.uff_lines import (MAX_UFF_LINE, UffLines, fixed_field, floats, ints,
                                     is_delimiter)
from substruct.case.uff_units import UffHeader, UffUnits, parse_151, parse_164, to_si

__all__ = ["Uff58", "UffNode", "UffSystem", "UffFile", "read_uff_records", "MAX_UFF_LINE",
           "MAX_POINTS", "READ_DATASETS", "DRAWING_DATASETS"]

#: Most points a function may declare (ten times the frequencies an analysis may have).
MAX_POINTS = 1_000_000


@dataclass(frozen=True)
class Uff58:
    """One dataset 58 as its records declare it (record numbers of the specification).

    Attributes:
        where: ``"dataset k (58, line l)"``: the k-th dataset of the file, starting at line l.
        func_type: record 6 field 1.
        load_case: record 6 field 4.
        rsp_node, rsp_dir, ref_node, ref_dir: record 6 fields 6, 7, 9, 10.
        ord_type: record 7 field 1 (2, 4: real; 5, 6: complex).
        num_pts: record 7 field 2.
        spacing: record 7 field 3 (0 uneven, 1 even).
        x_min, x_inc: record 7 fields 4, 5.
        abscissa, numerator, denominator: the specific data types of records 8, 9, 10.
        abscissa_units: record 8 field 6 (the axis units label).
        exponents: records 8, 9, 10 fields 2-4 (length, force, temperature units exponents;
            blank is 0).
        x: the abscissa, ``num_pts`` values.
        y: the ordinate, complex, ``num_pts`` values.
    """

    where: str
    func_type: int
    load_case: int
    rsp_node: int
    rsp_dir: int
    ref_node: int
    ref_dir: int
    ord_type: int
    num_pts: int
    spacing: int
    x_min: float
    x_inc: float
    abscissa: int
    abscissa_units: str
    numerator: int
    denominator: int
    x: np.ndarray
    y: np.ndarray
    exponents: tuple[tuple[int, ...], ...] = ()


@dataclass(frozen=True)
class UffNode:
    """A node of dataset 15 or 2411: its coordinates ``xyz`` in its definition coordinate
    system ``def_cs`` (15: record 1 field 2; 2411: the export system, record 1 field 2) and
    the system ``disp_cs`` its directions refer to (field 3)."""

    label: int
    def_cs: int
    disp_cs: int
    xyz: tuple[float, float, float]


@dataclass(frozen=True)
class UffSystem:
    """A coordinate system of dataset 2420 (``matrix``: records 5-8, the three axes then the
    origin, one row each) or 18 (``matrix``: the origin, a point on +x and a point in the
    +xz plane, one row each, in the system ``ref``; ``method`` of definition, record 1 field
    5); ``kind``: 0 cartesian, 1 cylindrical, 2 spherical; ``where``: the dataset."""

    label: int
    kind: int
    dataset: int
    ref: int
    method: int
    matrix: tuple[tuple[float, ...], ...]
    where: str


@dataclass(frozen=True)
class UffFile:
    """The functions (58) of a file, the node numbers its datasets 15 and 2411 define
    (``None`` if it has neither), those nodes, the coordinate systems of 18 and 2420, the
    header (151) and the units (164); lengths and functions in SI (:func:`to_si`)."""

    functions: list[Uff58]
    nodes: set[int] | None
    node_table: dict[int, UffNode] = field(default_factory=dict)
    systems: list[UffSystem] = field(default_factory=list)
    header: UffHeader | None = None
    units: UffUnits | None = None


def _header(lines: UffLines, where: str) -> list[str]:
    out: list[str] = []
    for _ in range(11):
        line = lines.next()
        if line is None or is_delimiter(line):
            raise ValueError(f"{where}: ends after {len(out)} of its 11 header records")
        out.append(line.decode("latin-1"))
    return out


#: Column widths of the data lines of record 12, by (ord_type, spacing): the spec's cases 1-8.
_WIDTHS = {(2, 1): [13] * 6, (2, 0): [13] * 6, (5, 1): [13] * 6, (5, 0): [13] * 6,
           (4, 1): [20] * 4, (6, 1): [20] * 4, (4, 0): [13, 20, 13, 20], (6, 0): [13, 20, 20]}


def _ascii_data(lines: UffLines, where: str, count: int, widths: list[int]) -> np.ndarray:
    values = np.empty(count, dtype=float)
    k = 0
    for line in lines.until_delimiter(f"{where}: record 12"):
        text = line.decode("latin-1")
        at = 0
        for w in widths:
            cell = text[at:at + w]
            at += w
            if not cell.strip():
                break
            if k == count:
                raise ValueError(f"{where}: record 12 holds more values than the "
                                 f"{count} that record 7 declares, at line {lines.number}")
            try:
                values[k] = float(cell.replace("D", "E").replace("d", "e"))
            except ValueError:
                raise ValueError(f"{where}: record 12 line {lines.number}: {cell.strip()!r} "
                                 "is not a number") from None
            k += 1
        if text[at:].strip():
            raise ValueError(f"{where}: record 12 line {lines.number} has more columns than "
                             f"its format ({len(widths)} values of widths {widths})")
    if k != count:
        raise ValueError(f"{where}: record 12 holds {k} values, record 7 declares {count}")
    return values


def _binary_data(lines: UffLines, where: str, count: int, single: bool, order: str
                 ) -> np.ndarray:
    need = count * (4 if single else 8)
    raw = lines.fh.read(need)
    if len(raw) != need:
        raise ValueError(f"{where}: record 12 holds {len(raw)} bytes, record 7 declares "
                         f"{need}")
    rest = lines.next()
    if rest is not None and rest == b"":  # a line break before the closing -1
        rest = lines.next()
    if rest is None or not is_delimiter(rest):
        raise ValueError(f"{where}: record 12 holds more data than the {need} bytes "
                         "declared (no closing -1 after them)")
    dtype = np.dtype(f"{order}{'f4' if single else 'f8'}")
    return np.frombuffer(raw, dtype=dtype).astype(float)


def _function(lines: UffLines, where: str, kind: str, budget: list[float]) -> Uff58:
    """Parse one 58 dataset after its type line ``kind`` (``"58"`` or ``"58b ..."``)."""
    binary = len(kind) > 6 and kind[6] in "bB"
    if binary:
        order = fixed_field(kind, 7, 13, int, f"{where}: id line field 3 (byte ordering)")
        fp = fixed_field(kind, 13, 19, int, f"{where}: id line field 4 (floating point format)")
        n_ascii = fixed_field(kind, 19, 31, int, f"{where}: id line field 5 (ASCII lines)")
        declared = int(fixed_field(kind, 31, 43, int, f"{where}: id line field 6 (bytes)"))
        if order not in (1, 2):
            raise ValueError(f"{where}: id line field 3, byte ordering {order}: not 1 (little "
                             "endian) or 2 (big endian)")
        if fp != 2:
            raise ValueError(f"{where}: id line field 4, floating point format {fp}: only 2 "
                             "(IEEE 754) is read")
        if n_ascii != 11:
            raise ValueError(f"{where}: id line field 5, {n_ascii} ASCII lines: dataset 58b "
                             "has 11")
    head = _header(lines, where)
    r6, r7 = head[5], head[6]
    rec6 = [(0, 5, "field 1 (function type)"), (20, 30, "field 4 (load case)"),
            (41, 51, "field 6 (response node)"), (51, 55, "field 7 (response direction)"),
            (66, 76, "field 9 (reference node)"), (76, 80, "field 10 (reference direction)")]
    f6 = [int(fixed_field(r6, a, b, int, f"{where}: record 6 {what}")) for a, b, what in rec6]
    ord_type = int(fixed_field(r7, 0, 10, int, f"{where}: record 7 field 1 (ordinate data type)"))
    num_pts = int(fixed_field(r7, 10, 20, int, f"{where}: record 7 field 2 (number of points)"))
    spacing = int(fixed_field(r7, 20, 30, int, f"{where}: record 7 field 3 (abscissa spacing)"))
    x_min = float(fixed_field(r7, 30, 43, float, f"{where}: record 7 field 4 (abscissa minimum)"))
    x_inc = float(fixed_field(r7, 43, 56, float, f"{where}: record 7 field 5 (abscissa increment)"))
    types = [int(fixed_field(head[k], 0, 10, int, f"{where}: record {k + 1} field 1 (specific "
                        "data type)")) for k in (7, 8, 9)]
    units = head[7][47:67].strip()
    exps = tuple(tuple(0 if not head[k][a:a + 5].strip() else int(fixed_field(
        head[k], a, a + 5, int, f"{where}: record {k + 1} field {a // 5} (units exponent)"))
        for a in (10, 15, 20)) for k in (7, 8, 9))
    if ord_type not in (2, 4, 5, 6):
        raise ValueError(f"{where}: record 7 field 1, ordinate data type {ord_type}: not 2, 4 "
                         "(real) or 5, 6 (complex)")
    if spacing not in (0, 1):
        raise ValueError(f"{where}: record 7 field 3, abscissa spacing {spacing}: not 0 "
                         "(uneven) or 1 (even)")
    if not 1 <= num_pts <= MAX_POINTS:
        raise ValueError(f"{where}: record 7 field 2 declares {num_pts} points; 1 to "
                         f"{MAX_POINTS} are read")
    complex_ = ord_type in (5, 6)
    per = (2 if complex_ else 1) + (1 if spacing == 0 else 0)
    count = num_pts * per
    single = ord_type in (2, 5)
    least = count * (4 if single else 8) if binary else count * min(_WIDTHS[(ord_type, spacing)])
    if least > lines.left():
        raise ValueError(f"{where}: record 7 declares {num_pts} points ({least} bytes or "
                         f"more) but {lines.left()} bytes of the file are left")
    budget[0] += 8.0 * count + 32.0 * num_pts
    if budget[0] > MEMORY_LIMIT:
        raise ValueError(f"{where}: the points declared so far would need more than "
                         f"{MEMORY_LIMIT / 1e9:g} GB of memory")
    if binary:
        size = 4 if single else 8
        if declared not in (count * size, num_pts * size):
            raise ValueError(f"{where}: id line field 6 declares {declared} bytes of data, "
                             f"record 7 {count * size} ({num_pts} points, {count} values of "
                             f"{size} bytes)")
        values = _binary_data(lines, where, count, single, "<" if order == 1 else ">")
    else:
        values = _ascii_data(lines, where, count, _WIDTHS[(ord_type, spacing)])
    table = values.reshape(num_pts, per)
    if spacing == 0:
        x, data = table[:, 0].copy(), table[:, 1:]
    else:
        x, data = x_min + x_inc * np.arange(num_pts), table
    y = data[:, 0] + 1j * data[:, 1] if complex_ else data[:, 0].astype(complex)
    return Uff58(where, f6[0], f6[1], f6[2], f6[3], f6[4], f6[5], ord_type, num_pts, spacing,
                 x_min, x_inc, types[0], units, types[1], types[2], x, y,
                 exps)


def _nodes(lines: UffLines, kind: int, into: set[int], table: dict[int, UffNode],
           where: str) -> None:
    """The nodes of a 15 (``4I10,3E13.5``, one a line) or 2411 (``4I10`` then ``3D25.16``,
    two lines a node) dataset."""
    head: list[int] = []
    count = 0
    for k, raw in enumerate(lines.until_delimiter(f"{where}:")):
        count = k + 1
        line = raw.decode("latin-1")
        what = f"{where}: line {lines.number}"
        if kind == 2411 and k % 2 == 1:
            xyz = floats(line, 3, 25, f"{what} (record 2)")
        else:
            head = ints(line, 3, f"{what} (record 1)")
            into.add(head[0])
            if kind == 2411 or not line[40:].strip():  # 15 without coordinates: a label
                continue
            xyz = floats(line[40:], 3, 13, f"{what} (coordinates)")
        if head[0] in table:
            raise ValueError(f"{what}: node {head[0]} is defined twice")
        table[head[0]] = UffNode(head[0], head[1], head[2], (xyz[0], xyz[1], xyz[2]))
    if kind == 2411 and count % 2:
        raise ValueError(f"{where}: node {head[0]} has no coordinates record")


def _systems(lines: UffLines, kind: int, into: list[UffSystem], where: str) -> None:
    """The coordinate systems of a 2420 (part records 1-2, then records 3-8 per system) or
    an 18 (records 1-4 per system) dataset."""
    rows = [raw.decode("latin-1") for raw in lines.until_delimiter(f"{where}:")]
    body, per = (rows[2:], 6) if kind == 2420 else (rows, 4)
    if (kind == 2420 and len(rows) < 2) or len(body) % per:
        raise ValueError(f"{where}: {len(rows)} lines do not make whole coordinate systems "
                         f"({per} records each)")
    for i in range(0, len(body), per):
        what = f"{where}: coordinate system {i // per + 1}"
        if kind == 2420:
            label, cs_type, _ = ints(body[i], 3, f"{what} (record 3)")
            matrix = tuple(floats(body[i + 2 + r], 3, 25, f"{what} (record {5 + r})")
                           for r in range(4))
            into.append(UffSystem(label, cs_type, 2420, 0, 0, matrix, what))
        else:
            label, cs_type, ref, _, method = ints(body[i], 5, f"{what} (record 1)")
            six = floats(body[i + 2], 6, 13, f"{what} (record 3)")
            xz = floats(body[i + 3], 3, 13, f"{what} (record 4)")
            into.append(UffSystem(label, cs_type, 18, ref, method,
                                  (six[:3], six[3:], xz), what))


def _rows(lines: UffLines, where: str) -> list[str]:
    return [raw.decode("latin-1") for raw in lines.until_delimiter(f"{where}:")]


#: The datasets a Universal File may hold.
READ_DATASETS = (15, 18, 58, 151, 164, 2411, 2420)
#: Datasets that only draw a test's geometry (82 trace lines, 2412 elements) or name its model
#: (2400): nothing in them changes a node, a system or a function, so they are passed over.
DRAWING_DATASETS = (82, 2400, 2412)


def read_uff_records(path: str | os.PathLike) -> UffFile:
    """The 58 functions and the 15/2411 node numbers of a Universal File (see the module).

    Raises:
        ValueError: one line naming the file, the dataset (its place and line), the record,
            the field and the value.
    """
    p = Path(path)
    size = p.stat().st_size
    functions: list[Uff58] = []
    nodes: set[int] | None = None
    table: dict[int, UffNode] = {}
    systems: list[UffSystem] = []
    header: UffHeader | None = None
    units: UffUnits | None = None
    first_data = ""
    budget = [0.0]
    with open(p, "rb") as fh:
        lines = UffLines(fh, p.name, size)
        k = 0
        while True:
            line = lines.next()
            if line is None:
                break
            if not line.strip():
                continue
            if not is_delimiter(line):
                raise ValueError(f"{p.name}: line {lines.number}: {line[:40]!r} where a "
                                 "dataset starts ('    -1')")
            start = lines.number
            kind_raw = lines.next()
            if kind_raw is None:
                break
            kind = kind_raw.decode("latin-1")
            k += 1
            try:
                number = int(kind[:6])
            except ValueError:
                raise ValueError(f"{p.name}: line {lines.number}: dataset number "
                                 f"{kind[:6].strip()!r} is not an integer") from None
            where = f"{p.name}: dataset {k} ({number}, line {start})"
            if number in (58, 15, 2411, 18, 2420) and not first_data:
                first_data = where.split(": ", 1)[1]
            if number == 164:
                if first_data:
                    raise ValueError(f"{where}: units after {first_data}, whose numbers they "
                                     "would scale: give the units (164) before the data")
                if units is not None:
                    raise ValueError(f"{where}: units given twice (first in "
                                     f"{units.where.split(': ', 1)[1]})")
                units = parse_164(_rows(lines, where), where)
            elif number == 151:
                if header is not None:
                    raise ValueError(f"{where}: a second header (151; first in "
                                     f"{header.where.split(': ', 1)[1]})")
                header = parse_151(_rows(lines, where), where)
            elif number == 58:
                functions.append(_function(lines, where, kind, budget))
            elif number in (15, 2411):
                nodes = set() if nodes is None else nodes
                _nodes(lines, number, nodes, table, where)
            elif number in (18, 2420):
                _systems(lines, number, systems, where)
            elif number in DRAWING_DATASETS:
                _rows(lines, where)
            else:
                raise ValueError(f"{where}: dataset {number} is not read (read: "
                                 f"{', '.join(map(str, READ_DATASETS))}); it would go unused")
    functions, table, systems = to_si(units, functions, table, systems)
    return UffFile(functions, nodes, table, systems, header, units)
