r"""The header datasets of a Universal File: 151 (model header) and 164 (units), and the
conversion of the file's numbers to SI.

* **151**: records 1-3 are the model name, its description and the program that created the
  database (kept, :class:`UffHeader`); the dates and versions of records 4-8 are not used.
  A second 151 in one file is refused.
* **164**: record 1 ``I10,20A1,I10`` the units code, its description and the temperature mode;
  record 2 ``3D25.17`` the factors that convert the file's length, force and temperature to SI
  (*divide* a file value by its factor: millimetres have a length factor of 1000); record 3
  the temperature offset.  Codes 1-8 and 10 are the specification's systems (1 SI, 2 BG
  foot/pound-force, 3 MG metre/kilogram-force, 4 BA foot/poundal, 5 MM millimetre/
  millinewton, 6 CM centimetre/centinewton, 7 IN inch/pound-force, 8 GM millimetre/
  kilogram-force, 10 MN millimetre/newton): their factors must be those of the code (to
  1e-4, files print few digits); code 9 (user defined) takes the file's factors, which must be
  positive and finite.  Any other code is refused, and so are two 164 datasets that differ.
  Nothing the program reads is a temperature, so the temperature factor and offset are read
  (they must be numbers) and not used.

Converted to SI (:func:`length_factor`, :func:`ordinate_factor`): node coordinates and the
origins and defining points of coordinate systems (lengths: divided by the length factor
:math:`L`); the ordinates of 58 functions of displacement, velocity or acceleration (spec
data types 8, 11, 12) over force (13): length over force, multiplied by :math:`F / L` (time is
the second in every system).  A 58 of another ordinate in a file that is not SI is refused: its
units are not known.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # the records import this module: their types for the checker only
    from substruct.case.uff_records import Uff58, UffNode, UffSystem

__all__ = ["UffHeader", "UffUnits", "UNIT_SYSTEMS", "parse_151", "parse_164",
           "ordinate_factor", "to_si"]

#: code -> (name, length factor, force factor) of the specification's unit systems.
UNIT_SYSTEMS: dict[int, tuple[str, float, float]] = {
    1: ("SI (metre, newton)", 1.0, 1.0),
    2: ("BG (foot, pound-force)", 3.28083989501312, 0.224808943099711),
    3: ("MG (metre, kilogram-force)", 1.0, 0.101971621297793),
    4: ("BA (foot, poundal)", 3.28083989501312, 7.23301385120989),
    5: ("MM (millimetre, millinewton)", 1000.0, 1000.0),
    6: ("CM (centimetre, centinewton)", 100.0, 100.0),
    7: ("IN (inch, pound-force)", 39.3700787401575, 0.224808943099711),
    8: ("GM (millimetre, kilogram-force)", 1000.0, 0.101971621297793),
    10: ("MN (millimetre, newton)", 1000.0, 1.0),
}
#: How far a file's factors may be from those of its code.
FACTOR_RTOL = 1e-4
#: Ordinates over force (13) that are converted: displacement, velocity, acceleration.
LENGTH_ORDINATES = (8, 11, 12)


@dataclass(frozen=True)
class UffHeader:
    """Records 1-3 of a dataset 151."""

    model: str
    description: str
    program: str


@dataclass(frozen=True)
class UffUnits:
    """A dataset 164: the code, its description and the length and force factors (file
    units per SI unit)."""

    code: int
    description: str
    length: float
    force: float
    where: str

    @property
    def is_si(self) -> bool:
        """Factors of exactly 1: nothing to convert."""
        return self.length == 1.0 and self.force == 1.0


def parse_151(rows: list[str], where: str) -> UffHeader:
    """Records 1-3 of a 151 dataset (its lines up to the closing ``-1``).

    Raises:
        ValueError: fewer than three records.
    """
    if len(rows) < 3:
        raise ValueError(f"{where}: a model header (151) has at least 3 records, got "
                         f"{len(rows)}")
    return UffHeader(rows[0].strip(), rows[1].strip(), rows[2].strip())


def _number(text: str, what: str) -> float:
    raw = text.strip()
    try:
        return float(raw.replace("D", "E").replace("d", "e"))
    except ValueError:
        raise ValueError(f"{what}: {raw!r} is not a number") from None


def parse_164(rows: list[str], where: str) -> UffUnits:
    """A 164 dataset (its lines up to the closing ``-1``), checked (module docstring).

    Raises:
        ValueError: one line naming the dataset, the record and the value: a code the program
            cannot honour, factors that are not those of the code or not positive, records
            missing or not numbers.
    """
    if len(rows) < 3:
        raise ValueError(f"{where}: a units dataset (164) has 3 records, got {len(rows)}")
    raw = rows[0][:10].strip()
    try:
        code = int(raw)
    except ValueError:
        raise ValueError(f"{where}: record 1 field 1 (units code): {raw!r} is not an "
                         "integer") from None
    factors = [_number(rows[1][25 * i:25 * i + 25], f"{where}: record 2 field {i + 1}")
               for i in range(3)]
    _number(rows[2][:25], f"{where}: record 3 field 1 (temperature offset)")
    length, force = factors[0], factors[1]
    if code not in UNIT_SYSTEMS and code != 9:
        raise ValueError(f"{where}: record 1 field 1: units code {code} is not one of the "
                         "specification's systems (1-10)")
    for what, value in (("length", length), ("force", force)):
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"{where}: record 2: the {what} factor must be positive and "
                             f"finite, not {value!r}")
    if code in UNIT_SYSTEMS:
        name, want_l, want_f = UNIT_SYSTEMS[code]
        for what, value, want in (("length", length, want_l), ("force", force, want_f)):
            if abs(value - want) > FACTOR_RTOL * want:
                raise ValueError(f"{where}: record 2: the {what} factor of units code {code} "
                                 f"({name}) is {want!r}, not {value!r}")
        length, force = want_l, want_f
    return UffUnits(code, rows[0][10:30].strip(), length, force, where)


def ordinate_factor(units: UffUnits, numerator: int, denominator: int, where: str) -> float:
    """The factor that converts a 58 function's ordinate to SI (module docstring).

    Raises:
        ValueError: an ordinate other than length, velocity or acceleration over force in a
            file that is not SI.
    """
    if units.is_si:
        return 1.0
    if numerator not in LENGTH_ORDINATES or denominator != 13:
        raise ValueError(f"{where}: records 9-10: an ordinate of data type {numerator} over "
                         f"{denominator} cannot be converted from units code {units.code} "
                         f"({units.where.split(': ', 1)[-1]}) to SI")
    return units.force / units.length


def to_si(units: UffUnits, functions: list[Uff58], nodes: dict[int, UffNode],
          systems: list[UffSystem]) -> tuple[list[Uff58], dict[int, UffNode], list[UffSystem]]:
    """The records in SI (module docstring): ordinates times :func:`ordinate_factor`, node
    coordinates, 2420 origins (record 8) and the three defining points of 18 divided by the
    length factor; unchanged when the file is SI.

    Raises:
        ValueError: as :func:`ordinate_factor`.
    """
    if units.is_si:
        return functions, nodes, systems
    L = units.length
    funcs = [replace(f, y=f.y * ordinate_factor(units, f.numerator, f.denominator, f.where))
             for f in functions]
    table = {k: replace(n, xyz=(n.xyz[0] / L, n.xyz[1] / L, n.xyz[2] / L))
             for k, n in nodes.items()}
    scaled = [replace(s, matrix=tuple(tuple(v / L for v in row) if s.dataset == 18 or r == 3
                                      else row for r, row in enumerate(s.matrix)))
              for s in systems]
    return funcs, table, scaled
