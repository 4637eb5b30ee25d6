"""Numbers read from a case: one validation for every reader, before any conversion.

Every number that enters a case (a YAML field, a ``--set`` value, a constant or the value of an
expression, an inline matrix entry, the entries of a matrix file, the coordinates of a mesh)
is checked here:

* it is finite (no ``.nan``, ``.inf``, ``1e999``);
* its magnitude lies within :data:`MIN_MAGNITUDE` .. :data:`MAX_MAGNITUDE` (``1e-30 .. 1e30``),
  or it is exactly zero.  No engineering quantity in any consistent unit system comes near
  either bound (``E = 2e11`` Pa, ``rho = 7.85e-9`` t/mm^3, ``omega = 1e9`` rad/s), while products
  of a handful of such numbers and their squares (stiffness x length^3 / mass, omega^2 x mass,
  norms) stay far inside float64 (``1e308``), so nothing computed later overflows to ``inf``
  or underflows to a subnormal that makes a matrix singular;
* an integer written with more than :data:`MAX_DIGITS` digits is refused by its number of
  digits, without ever being converted: YAML integer literals that long are read as
  :class:`BigNumber` (never as Python integers, whose conversion to ``float`` raises
  ``OverflowError`` and whose conversion to text fails beyond 4300 digits), and expression and
  point texts are scanned for such digit runs before they are parsed.

Counts (elements, modes, divisions, frequencies) are integers within their own limits
(:mod:`substruct.case.fields`); damping ratios lie within ``0 .. MAX_DAMPING_RATIO``.
"""

from __future__ import annotations

import math
import re
from typing import Any, Iterator

import numpy as np

__all__ = [
    "MAX_MAGNITUDE", "MIN_MAGNITUDE", "MAX_DIGITS", "MAX_DAMPING_RATIO", "RANGE",
    "BigNumber", "number_problem", "coefficient_problem", "array_problem", "digits_problem",
    "find_problem", "is_coefficient", "entry_problem",
]

#: Largest magnitude of any number in a case.
MAX_MAGNITUDE = 1e30
#: Smallest magnitude of a nonzero number in a case.
MIN_MAGNITUDE = 1e-30
#: Most digits of an integer literal (``10**30`` has 31).
MAX_DIGITS = 30
#: Largest modal damping ratio (critical damping is 1; 100 is far past anything physical).
MAX_DAMPING_RATIO = 100.0
#: The accepted range, as messages write it.
RANGE = "numbers are 0 or within 1e-30 .. 1e30 in magnitude"


class BigNumber:
    """An integer literal of more than :data:`MAX_DIGITS` digits, kept as its text.

    It is never converted to a number: the validation refuses it by name wherever it stands.
    """

    __slots__ = ("text",)

    def __init__(self, text: str):
        self.text = text

    @property
    def digits(self) -> int:
        """The number of digits written (signs, underscores and prefixes left out)."""
        body = self.text.strip().lstrip("+-").replace("_", "").lower()
        if body.startswith(("0x", "0o", "0b")):
            body = body[2:]
        return sum(c.isalnum() for c in body.lstrip("0")) or 1

    def __str__(self) -> str:
        t = self.text.strip()
        return t if len(t) <= 40 else f"{t[:24]}...{t[-8:]} ({self.digits} digits)"

    __repr__ = __str__

    def __eq__(self, other: object) -> bool:
        return isinstance(other, BigNumber) and other.text == self.text

    def __hash__(self) -> int:
        return hash(("BigNumber", self.text))


def _int_digits(n: int) -> int:
    """Decimal digits of ``|n|`` without converting it to text (exact below 10**4000)."""
    bits = abs(n).bit_length()
    if bits <= 12000:
        return len(str(abs(n)))
    return int(bits * math.log10(2)) + 1


def number_problem(value: Any) -> str | None:
    """What is wrong with a number read from a case, or ``None`` if it is usable.

    ``value`` is a ``bool`` (refused: not a number), an ``int``, a ``float`` (or numpy
    scalar) or a :class:`BigNumber`; anything else is not judged here (``None``).
    """
    if isinstance(value, (bool, np.bool_)):
        return "must be a number, not true/false"
    if isinstance(value, BigNumber):
        return f"out of range: an integer of {value.digits} digits ({RANGE})"
    if isinstance(value, (int, np.integer)):
        n = int(value)
        if abs(n) > 10 ** MAX_DIGITS:
            return f"out of range: an integer of {_int_digits(n)} digits ({RANGE})"
        x = float(n)
    elif isinstance(value, (float, np.floating)):
        x = float(value)
    else:
        return None
    if not math.isfinite(x):
        return "must be a finite number"
    if abs(x) > MAX_MAGNITUDE:
        return f"out of range: too large ({RANGE})"
    if x != 0 and abs(x) < MIN_MAGNITUDE:
        return f"out of range: too small ({RANGE})"
    return None


def coefficient_problem(value: Any) -> str | None:
    """What is wrong with a constraint coefficient (``terms``, ``rhs``, ``rhs_force``), or
    ``None``: finite and not a big integer, at any magnitude.

    A constraint row means the same whatever its scale (``1e-300 q1 = 0`` is ``q1 = 0``): every
    analysis equilibrates the rows ``D A q = D b + D R F`` before it decides on rank or
    consistency (:mod:`substruct.linalg.scaling`), so the range of :func:`number_problem`,
    which keeps physical quantities and their products finite, does not apply here.
    """
    problem = number_problem(value)
    if problem is None or not problem.startswith("out of range: too"):
        return problem
    return None


def is_coefficient(loc: tuple) -> bool:
    """Whether a location of raw case data holds a constraint coefficient
    (``constraints[i].terms.*``, ``constraints[i].rhs``, ``constraints[i].rhs_force.*``)."""
    return (len(loc) >= 3 and loc[0] == "constraints" and
            loc[2] in ("terms", "rhs", "rhs_force"))


def array_problem(values: Any) -> str | None:
    """What is wrong with an array of numbers (a matrix file, mesh coordinates), or ``None``.

    Every entry must be finite and at most :data:`MAX_MAGNITUDE` in magnitude, and the largest
    at least :data:`MIN_MAGNITUDE` unless all are zero; small entries beside large ones are
    rounding noise and are accepted.
    """
    a = np.asarray(values)
    if a.size == 0:
        return None
    if a.dtype.kind not in "biuf":
        return f"holds {a.dtype} entries, not real numbers"
    a = a.astype(float, copy=False)
    with np.errstate(all="ignore"):
        if not np.all(np.isfinite(a)):
            return "has entries that are not finite numbers"
        top = float(np.abs(a).max())
    if top > MAX_MAGNITUDE:
        return f"has an entry of magnitude {top:.3g}, out of range ({RANGE})"
    if 0 < top < MIN_MAGNITUDE:
        return f"its largest entry is of magnitude {top:.3g}, out of range ({RANGE})"
    return None


def entry_problem(values: Any) -> tuple[tuple[int, ...], float, str] | None:
    """The first entry of a real array that is not finite or beyond :data:`MAX_MAGNITUDE`, or
    its largest entry if that is below :data:`MIN_MAGNITUDE` but not zero (the rule of
    :func:`array_problem`: small entries beside large ones are rounding noise, as in a matrix
    written by another program), located: ``(index, value, problem)``, or ``None``.

    For the entries of Nastran matrices (OP4), whose refusal names the entry.
    """
    a = np.asarray(values, dtype=float)
    with np.errstate(all="ignore"):
        size = np.abs(a)
        bad = ~(size <= MAX_MAGNITUDE)
    if not bad.any():
        if not a.size or not 0 < size.max() < MIN_MAGNITUDE:
            return None
        bad = size == size.max()
    index = tuple(int(i) for i in np.unravel_index(int(np.argmax(bad)), a.shape))
    value = float(a[index])
    problem = number_problem(value)
    assert problem is not None
    return index, value, problem


#: A run of digits that starts a number in an expression (not the fraction after a point, not
#: a part of a name or an exponent).
_DIGIT_RUN = re.compile(r"(?<![\w.])\d[\d_]*")
#: Any run of digits in a point but a fraction (``rod@120``, ``beam@n12:z``, ``P@q3``).
_POINT_DIGITS = re.compile(r"(?<![.\d_])\d[\d_]*")


def digits_problem(text: str, point: bool = False) -> str | None:
    """An integer of more than :data:`MAX_DIGITS` digits written in ``text`` (an expression,
    or with ``point`` the place of a point, where node numbers follow a letter), found before
    the text is parsed; ``None`` if there is none."""
    for m in (_POINT_DIGITS if point else _DIGIT_RUN).finditer(text):
        digits = m.group().replace("_", "").lstrip("0")
        if len(digits) > MAX_DIGITS:
            shown = m.group() if len(m.group()) <= 24 else f"{m.group()[:16]}..."
            return f"out of range: the number {shown} has {len(digits)} digits ({RANGE})"
    return None


def _walk(node: Any, loc: tuple, seen: set[int]) -> Iterator[tuple[tuple, Any, bool]]:
    """``(loc, value, is_key)`` of every scalar and mapping key below ``node``; containers
    shared through YAML aliases are walked once."""
    if isinstance(node, (dict, list)):
        if id(node) in seen:
            return
        seen.add(id(node))
        if isinstance(node, dict):
            for key, value in node.items():
                yield loc, key, True
                yield from _walk(value, loc + (key,), seen)
        else:
            for i, value in enumerate(node):
                yield from _walk(value, loc + (i,), seen)
    else:
        yield loc, node, False


def find_problem(data: Any) -> tuple[tuple, Any, str, bool] | None:
    """The first number of raw case data (parsed YAML) that :func:`number_problem` refuses.

    Booleans are left to the schema (a flag is ``true``/``false``); numbers written as text are
    checked where they are read (expressions, points, fields that accept text).

    Returns:
        ``(loc, value, problem, is_key)``: the location (keys and 0-based indices; for a key,
        the location of its mapping), the value, what is wrong, and whether the value is a
        mapping key; or ``None``.
    """
    for loc, value, is_key in _walk(data, (), set()):
        if isinstance(value, bool):
            continue
        problem = (coefficient_problem(value) if not is_key and is_coefficient(loc)
                   else number_problem(value))
        if problem is not None:
            return loc, value, problem, is_key
    return None
