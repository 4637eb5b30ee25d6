r"""The header (dataset 151) and the units (dataset 164) of a Universal File, and the factors
that turn the file's lengths and functions into SI.

Dataset 151 (header), seven records of text: 1 model file name, 2 model file description,
3 program which created the database, 4 date and time the database was created (``10A1,10A1``,
then three ``I10``: two database versions and the file type), 5 date and time it was last
saved, 6 program which wrote the universal file, 7 date and time the file was written.  Its
names and dates are kept (:class:`UffHeader`); nothing is computed from them.

Dataset 164 (units): record 1 ``FORMAT(I10,20A1,I10)``: field 1 the units code (1 SI: meter,
newton; 2 BG: foot, pound force; 3 MG: meter, kilogram force; 4 BA: foot, poundal; 5 MM: mm,
milli newton; 6 CM: cm, centi newton; 7 IN: inch, pound force; 8 GM: mm, kilogram force; 9 US:
user defined; 10 MN: mm, newton), field 2 a description, field 3 the temperature mode (1
absolute, 2 relative); record 2 ``FORMAT(3D25.17)``, four factors "for converting universal
file units to SI: divide by the factor": length, force, temperature, temperature offset.  A
blank temperature mode (as LMS Test.Lab writes it) is read as not given; any other text but 1
or 2 is refused.  A
length :math:`x` of the file is :math:`x / f_L` m.  The factors of a named system (any code
but 9) must be its own to :data:`UNIT_RTOL` and are then replaced by its own exactly (files
print them rounded); code 9 takes the file's, positive and finite.

A function's value has the dimension :math:`L^{l} F^{f}` that the specific data type of its
record (58 records 8-10 field 1) and the direction give (58 Addendum A: displacement,
velocity, acceleration :math:`L` at a translation and 1 at a rotation; excitation force
:math:`F` at a translation and :math:`L F` (a moment) at a rotation; frequency 1), so a
receptance read as :math:`H` is :math:`H f_L^{-l_n + l_d} f_F^{-f_n + f_d}` in SI
(:func:`function_to_si`).  The temperature and its offset scale no quantity that substruct
reads; they are kept but not used.

A file's records are turned into SI as they are read (:func:`to_si`, called by
:func:`substruct.case.uff_records.read_uff_records`): node coordinates, the origins of 2420
(record 8) and the three points of 18 divided by :math:`f_L` (in a cylindrical or spherical
system only the coordinates that are lengths, :math:`r, z` or :math:`r`; the angles are
degrees, :func:`substruct.case.uff_frames.length_components`), each 58 function's ordinate
multiplied by :func:`function_to_si` of its data types and directions.  In a file whose
factors are not 1, a 58 of a data type outside the table (8, 11, 12, 13, 18) is refused: its
units are not known.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

from substruct.case.uff_frames import length_components

if TYPE_CHECKING:  # the records import this module: their types for the checker only
    from substruct.case.uff_records import Uff58, UffNode, UffSystem

__all__ = ["UffHeader", "UffUnits", "UNIT_SYSTEMS", "UNIT_RTOL", "parse_151", "parse_164",
           "unit_exponents", "length_to_si", "function_to_si", "to_si"]

_LBF = 4.4482216152605  # N (0.45359237 kg x 9.80665 m/s^2)
_KGF = 9.80665  # N
_POUNDAL = 0.138254954376  # N (0.45359237 kg x 0.3048 m/s^2)

#: The unit systems of 164 record 1 field 1: name, length factor, force factor (``None``: any,
#: user defined).
UNIT_SYSTEMS: dict[int, tuple[str, float | None, float | None]] = {
    1: ("SI: meter (newton)", 1.0, 1.0),
    2: ("BG: foot (pound f)", 1 / 0.3048, 1 / _LBF),
    3: ("MG: meter (kilogram f)", 1.0, 1 / _KGF),
    4: ("BA: foot (poundal)", 1 / 0.3048, 1 / _POUNDAL),
    5: ("MM: mm (milli newton)", 1000.0, 1000.0),
    6: ("CM: cm (centi newton)", 100.0, 100.0),
    7: ("IN: inch (pound f)", 1 / 0.0254, 1 / _LBF),
    8: ("GM: mm (kilogram f)", 1000.0, 1 / _KGF),
    9: ("US: user defined", None, None),
    10: ("MN: mm (newton)", 1000.0, 1.0),
}
#: The factors of a named unit system (codes other than 9) may differ from its own by this
#: much (relative: files print few digits) before the file is refused as contradicting
#: itself; within it, the code's own factors are used.
UNIT_RTOL = 1e-4

#: Units exponents (length, force) of the specific data types read, at a translation and at a
#: rotation (58 Addendum A); time is always seconds.
_EXPONENTS = {8: ((1, 0), (0, 0)), 11: ((1, 0), (0, 0)), 12: ((1, 0), (0, 0)),
              13: ((0, 1), (1, 1)), 18: ((0, 0), (0, 0))}


@dataclass(frozen=True)
class UffHeader:
    """Dataset 151: the names and dates it records, as text (module docstring)."""

    model_name: str
    description: str
    database_program: str
    database_created: str
    database_saved: str
    program: str
    file_written: str
    where: str

    def attributes(self) -> dict[str, str]:
        """The header as ``{name: text}`` (the attributes stored with a channel table)."""
        return {"model_name": self.model_name, "description": self.description,
                "database_program": self.database_program,
                "database_created": self.database_created,
                "database_saved": self.database_saved, "program": self.program,
                "file_written": self.file_written}


@dataclass(frozen=True)
class UffUnits:
    """Dataset 164 (module docstring): the code, its description, the temperature mode and
    the four factors (file units per SI unit)."""

    code: int
    description: str
    temperature_mode: int | None  # None: left blank (not used by substruct)
    length: float
    force: float
    temperature: float
    temperature_offset: float
    where: str

    @property
    def is_si(self) -> bool:
        """Length and force factors of exactly 1: nothing to convert."""
        return self.length == 1.0 and self.force == 1.0


def parse_151(rows: list[str], where: str) -> UffHeader:
    """The header of the seven records ``rows`` (the lines between the dataset's number and
    its closing ``-1``).

    Raises:
        ValueError: not seven records.
    """
    if len(rows) != 7:
        raise ValueError(f"{where}: {len(rows)} records, a header (151) has 7")

    def when(text: str) -> str:
        return " ".join(f"{text[:10].strip()} {text[10:20].strip()}".split())

    return UffHeader(rows[0].strip(), rows[1].strip(), rows[2].strip(), when(rows[3]),
                     when(rows[4]), rows[5].strip(), when(rows[6]), where)


def parse_164(rows: list[str], where: str) -> UffUnits:
    """The units of the records ``rows`` (module docstring), every field checked.

    Raises:
        ValueError: a units code not 1..10, a temperature mode not blank, 1 or 2, not four
            factors, a factor that is not a positive finite number, or the factors of a named unit
            system (codes other than 9) off its own by more than :data:`UNIT_RTOL` (within
            it, the length and force factors kept are the system's own).
    """
    if len(rows) < 2:
        raise ValueError(f"{where}: {len(rows)} record(s), units (164) have 2")
    head = rows[0]
    try:
        code = int(head[:10])
    except ValueError:
        raise ValueError(f"{where}: record 1 field 1, units code {head[:10].strip()!r}: not "
                         "an integer") from None
    if code not in UNIT_SYSTEMS:
        raise ValueError(f"{where}: record 1 field 1, units code {code}: not one of 1..10 ("
                         + ", ".join(f"{k} {v[0]}" for k, v in UNIT_SYSTEMS.items()) + ")")
    mode: int | None = None  # blank: not given (LMS Test.Lab); substruct does not use it
    if head[30:40].strip():
        try:
            mode = int(head[30:40])
        except ValueError:
            raise ValueError(f"{where}: record 1 field 3, temperature mode "
                             f"{head[30:40].strip()!r}: not an integer") from None
        if mode not in (1, 2):
            raise ValueError(f"{where}: record 1 field 3, temperature mode {mode}: not 1 "
                             "(absolute) or 2 (relative)")
    words = " ".join(rows[1:]).split()
    if len(words) != 4:
        raise ValueError(f"{where}: record 2 holds {len(words)} numbers, the four factors "
                         "(length, force, temperature, temperature offset) are needed")
    names = ("length", "force", "temperature", "temperature offset")
    factors = []
    for k, (w, name) in enumerate(zip(words, names)):
        try:
            v = float(w.replace("D", "E").replace("d", "e"))
        except ValueError:
            raise ValueError(f"{where}: record 2 field {k + 1} ({name} factor) {w!r}: not a "
                             "number") from None
        if not math.isfinite(v) or (k < 3 and not v > 0):
            raise ValueError(f"{where}: record 2 field {k + 1}, {name} factor {w}: not a "
                             f"{'positive ' if k < 3 else ''}finite number")
        factors.append(v)
    name, fl, ff = UNIT_SYSTEMS[code]
    for k, (given, own) in enumerate(zip(factors[:2], (fl, ff))):
        if own is not None and abs(given - own) > UNIT_RTOL * own:
            raise ValueError(f"{where}: record 2 field {k + 1}, {names[k]} factor {given:.10g}"
                             f" is not that of units code {code} ({name}: {own:.10g}); the "
                             "file contradicts itself")
        if own is not None:  # the code's own factor, not the file's rounded print of it
            factors[k] = own
    return UffUnits(code, head[10:30].strip(), mode, factors[0], factors[1], factors[2],
                    factors[3], where)


def unit_exponents(data_type: int, direction: int) -> tuple[int, int]:
    """``(length, force)`` exponents of a specific data type at a direction code (1-3
    translations, 4-6 rotations; 58 Addendum A).

    Raises:
        KeyError: a data type not in the table of those read (8, 11, 12, 13, 18).
    """
    return _EXPONENTS[data_type][1 if abs(direction) > 3 else 0]


def length_to_si(units: UffUnits | None) -> float:
    """The factor that turns a length of the file into meters: :math:`1 / f_L` (1 with no
    dataset 164)."""
    return 1.0 if units is None else 1.0 / units.length


def function_to_si(units: UffUnits | None, numerator: int, rsp_dir: int, denominator: int,
                   ref_dir: int) -> float:
    r"""The factor that turns a function of the file (ordinate ``numerator`` at the response
    direction over ``denominator`` at the reference direction) into SI:
    :math:`f_L^{l_d - l_n} f_F^{f_d - f_n}` (1 with no dataset 164)."""
    if units is None:
        return 1.0
    ln, fn = unit_exponents(numerator, rsp_dir)
    ld, fd = unit_exponents(denominator, ref_dir)
    return units.length ** (ld - ln) * units.force ** (fd - fn)


def to_si(units: UffUnits | None, functions: list[Uff58], nodes: dict[int, UffNode],
          systems: list[UffSystem]) -> tuple[list[Uff58], dict[int, UffNode], list[UffSystem]]:
    """The records in SI (module docstring): each ordinate times :func:`function_to_si`,
    node coordinates, 2420 origins and the points of 18 times :func:`length_to_si`;
    unchanged without a 164 or when its factors are 1.

    Raises:
        ValueError: a function of a data type whose units are not known, in a file that is
            not SI.
    """
    if units is None or units.is_si:
        return functions, nodes, systems
    funcs = []
    for f in functions:
        try:
            k = function_to_si(units, f.numerator, f.rsp_dir, f.denominator, f.ref_dir)
        except KeyError:
            raise ValueError(f"{f.where}: records 9-10 field 1, ordinate data type "
                             f"{f.numerator} over {f.denominator}: its units are not known, "
                             f"so it cannot be converted from units code {units.code} "
                             f"({units.where.split(': ', 1)[-1]}) to SI") from None
        funcs.append(replace(f, y=f.y * k))
    s = length_to_si(units)
    kinds: dict[int, int] = {}
    for c in systems:
        kinds.setdefault(c.label, c.kind)

    def scaled_point(row: tuple[float, ...], cs: int) -> tuple[float, ...]:
        keep = length_components(kinds.get(cs, 0))
        return tuple(v * s if i in keep else v for i, v in enumerate(row))

    table = {}
    for k, n in nodes.items():
        x = scaled_point(n.xyz, n.def_cs)
        table[k] = replace(n, xyz=(x[0], x[1], x[2]))
    scaled = [replace(c, matrix=tuple(
        scaled_point(row, c.ref) if c.dataset == 18 else
        tuple(v * s for v in row) if r == 3 else row for r, row in enumerate(c.matrix)))
        for c in systems]
    return funcs, table, scaled
