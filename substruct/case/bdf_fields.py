r"""Nastran bulk data files split into cards of fields: free, small and large field.

A bulk data file is read as Nastran reads it:

* **Sections.** Lines before ``CEND`` are executive control, lines between ``CEND`` and
  ``BEGIN BULK`` case control, lines after ``BEGIN BULK`` bulk data up to ``ENDDATA``.  A file
  without ``BEGIN BULK`` is bulk data only.  A card after ``ENDDATA`` is refused (it would not
  be read), another ``ENDDATA`` is not (it is harmless), and text beyond column 80 of a bulk
  data line is refused.
* **Comments** start with ``$``; blank lines are skipped; tabs are expanded to 8 columns.
* **Small field:** columns 1-8 hold the card name (field 1), columns 9-72 eight fields of 8
  (fields 2-9), columns 73-80 the continuation marker (field 10, not read).
* **Large field:** a name ending in ``*`` (``GRID*``) starts a card whose lines hold four
  fields of 16 columns; a line starting with ``*`` continues it, the two lines making the
  eight fields of one small-field line.
* **Free field:** a line holding a comma is split at commas: the name, then eight fields
  (four for a large-field name), then an optional continuation marker; more is refused.
* **Continuations** are the lines that start with a blank, ``+``, ``*`` or ``,``.  They
  continue the card above them in the order they are written (continuation markers are not
  matched).

A card is a :class:`RawCard`: its name and a flat list of its fields, ``fields[0]`` being
field 2 of its first line and ``fields[8 k + j]`` field ``j + 2`` of continuation ``k``.
:class:`BdfField` reads typed values out of it (integers, reals with Nastran's rules) and
raises :class:`BdfError`, one line naming the file, the line, the card, its id and the field.

The file is checked before it is read (a regular file of at most :data:`MAX_BDF_FILE` bytes),
so that a huge file is refused from its size; the count of every card is bounded by the file
size, so the arrays built from them are too.
"""

from __future__ import annotations

import os
import re
import stat
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from substruct.case.errors import MISSING, CaseError
from substruct.case.numbers import coefficient_problem, number_problem

__all__ = ["MAX_BDF_FILE", "BdfError", "RawCard", "BdfText", "read_bdf_text", "split_bdf",
           "nastran_real", "nastran_int"]

#: Largest bulk data file read, in bytes (about a million cards; the text parser reads some
#: 10 MB/s, and the largest model accepted has MAX_MATRIX_SIZE coordinates).
MAX_BDF_FILE = 64_000_000

_INT = re.compile(r"^[+-]?\d+$")
_REAL = re.compile(r"^([+-]?(?:\d+\.\d*|\.\d+))(?:[ED]([+-]?\d+)|([+-]\d+))?$")


class BdfError(CaseError):
    """A problem with a bulk data file, one line: ``<file>: line <n>: <CARD> <id>: <field>:
    <problem>, got <value>``."""

    def __init__(self, source: str, problem: str, value: Any = MISSING, line: int = 0,
                 card: str = "", ident: Any = None, name: str = ""):
        where = []
        if line:
            where.append(f"line {line}")
        if card:
            shown = str(ident) if ident is not None else ""
            shown = shown if len(shown) <= 16 else shown[:13] + "..."  # a field holds 16
            where.append(card if ident is None else f"{card} {shown}")
        if name:
            where.append(name)
        super().__init__(source, ": ".join(where), problem, value)


#: The largest integer a field holds (Nastran's 32-bit integers); ids and counts beyond it
#: are refused before they reach an array.
MAX_NASTRAN_INT = 2_147_483_647


def nastran_int(text: str) -> int | None:
    """The integer of a field (``None`` if it is not one, or if it lies outside Nastran's
    32-bit range, ``|i| <= MAX_NASTRAN_INT``)."""
    if len(text) > 12 or not _INT.match(text):
        return None
    value = int(text)
    return value if abs(value) <= MAX_NASTRAN_INT else None


def nastran_real(text: str) -> float | None:
    """The real number of a field, with Nastran's rules: a decimal point is required, the
    exponent is written ``E``, ``D`` or a bare sign (``7.85-9``, ``2.1+11``); ``None`` if the
    field is not a real."""
    m = _REAL.match(text.upper())
    if m is None:
        return None
    exp = m.group(2) or m.group(3)
    return float(m.group(1) + (f"e{exp}" if exp else ""))


@dataclass
class RawCard:
    """One card: ``name`` (upper case, without ``*``), its ``fields`` (flat, see the module
    docstring, stripped and upper case) and the ``line`` it starts on."""

    name: str
    fields: list[str]
    line: int
    source: str = ""

    @property
    def ident(self) -> str:
        """Field 2 (the id of most cards), for messages."""
        return self.fields[0] if self.fields else ""

    def error(self, problem: str, value: Any = MISSING, name: str = "") -> BdfError:
        """A :class:`BdfError` at this card (``name``: the field's name)."""
        return BdfError(self.source, problem, value, self.line, self.name, self.ident or None,
                        name)

    def text(self, i: int) -> str:
        """Field ``i`` as text ('' if blank or past the end)."""
        return self.fields[i] if i < len(self.fields) else ""

    def integer(self, i: int, name: str, default: int | None = None) -> int:
        """Integer field ``i``; ``default`` if blank (an error if blank without default)."""
        t = self.text(i)
        if not t:
            if default is None:
                raise self.error("a required integer field is blank", name=name)
            return default
        v = nastran_int(t)
        if v is None:
            raise self.error(f"must be an integer of at most {MAX_NASTRAN_INT} in size", t,
                             name)
        return v

    def real(self, i: int, name: str, default: float | None = None,
             coefficient: bool = False) -> float:
        """Real field ``i`` (a decimal point required); ``default`` if blank.

        The value is a number of the case (:func:`~substruct.case.numbers.number_problem`:
        finite, 0 or within ``1e-30 .. 1e30`` in magnitude), or with ``coefficient`` a
        constraint coefficient (an MPC's, finite at any magnitude: its row is equilibrated).
        """
        t = self.text(i)
        if not t:
            if default is None:
                raise self.error("a required real field is blank", name=name)
            return default
        v = nastran_real(t)
        if v is None:
            raise self.error("must be a real number with a decimal point (Nastran's rule)",
                             t, name)
        if v != v or v in (float("inf"), float("-inf")):
            raise self.error("must be finite", t, name)
        problem = coefficient_problem(v) if coefficient else number_problem(v)
        if problem is not None:
            raise self.error(problem, t, name)
        return v

    def no_damping(self, i: int, name: str) -> None:
        """Refuse a structural damping coefficient ``GE`` other than blank or 0: normal modes
        and the undamped responses of a substructure do not use it (its damping comes from
        the case file's ``analysis``)."""
        if self.real(i, name, 0.0) != 0.0:
            raise self.error(f"{name} (structural damping) is not supported: normal modes and "
                             "the undamped responses of a substructure do not use it (damp "
                             "in the case file's analysis)", self.text(i), name)

    def blank_after(self, i: int, what: str) -> None:
        """Refuse any non-blank field from ``i`` on (fields that would not be read)."""
        for k in range(i, len(self.fields)):
            if self.fields[k]:
                raise self.error(f"field {k % 8 + 2} of line {k // 8 + 1} is not read "
                                 f"({what})", self.fields[k], f"field {k + 2}")


@dataclass
class BdfText:
    """A bulk data file split: executive and case control lines ``(line, text)`` and the
    bulk data cards."""

    source: str
    executive: list[tuple[int, str]] = field(default_factory=list)
    case_control: list[tuple[int, str]] = field(default_factory=list)
    cards: list[RawCard] = field(default_factory=list)


def read_bdf_text(path: Path, source: str) -> str:
    """The text of a bulk data file: a regular file of at most :data:`MAX_BDF_FILE` bytes,
    checked before it is read; ASCII/Latin-1 (each byte one character).

    Raises:
        BdfError: no such file, not a regular file, too large, unreadable.
    """
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0)
    try:
        fd = os.open(path, flags)
    except FileNotFoundError:
        raise BdfError(source, "no such bulk data file") from None
    except OSError as err:
        raise BdfError(source, f"cannot read bulk data file ({err.strerror or err})") from None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise BdfError(source, "not a regular file: a bulk data file is read from a "
                           "regular file")
        if info.st_size > MAX_BDF_FILE:
            raise BdfError(source, f"a bulk data file of {info.st_size} bytes, more than the "
                           f"{MAX_BDF_FILE} read")
        chunks, size = [], 0
        while size <= MAX_BDF_FILE:
            chunk = os.read(fd, MAX_BDF_FILE + 1 - size)
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
        if size > MAX_BDF_FILE:
            raise BdfError(source, "a bulk data file that grew while it was read")
    except OSError as err:
        raise BdfError(source, f"cannot read bulk data file ({err.strerror or err})") from None
    finally:
        os.close(fd)
    data = b"".join(chunks)
    if b"\0" in data:
        raise BdfError(source, "a binary file, not bulk data (it holds NUL bytes)")
    return data.decode("latin-1")


def _line_fields(text: str, source: str, n: int) -> tuple[str, list[str], bool]:
    """``(field 1, data fields, large)`` of one line (4 data fields for large field)."""
    if "," in text:
        parts = [p.strip().upper() for p in text.split(",")]
        head = parts[0]
        large = head.endswith("*") or head.startswith("*")
        width = 4 if large else 8
        if len(parts) > width + 2:
            raise BdfError(source, f"a free-field line holds a name, {width} fields and a "
                           f"continuation marker, not {len(parts)} fields", line=n)
        data = parts[1:1 + width]
        return head, data + [""] * (width - len(data)), large
    head = text[:8].strip().upper()
    if head.endswith("*") or head.startswith("*"):
        return head, [text[8 + 16 * k: 24 + 16 * k].strip().upper() for k in range(4)], True
    return head, [text[8 + 8 * k: 16 + 8 * k].strip().upper() for k in range(8)], False


def _nothing_after(text: list[tuple[str, int, str]], lines: list[str], start: int) -> None:
    """Refuse a card after ``ENDDATA`` (it would not be read); comments, blank lines and
    another ``ENDDATA`` (which ends nothing more) are fine."""
    for k in range(start, len(lines)):
        rest = lines[k].split("$", 1)[0].strip()
        if rest and rest.upper().split()[0].split(",")[0] != "ENDDATA":
            raise BdfError(text[k][0], "a card after ENDDATA would not be read", rest,
                           line=text[k][1])


def split_bdf(text: str | list[tuple[str, int, str]], source: str) -> BdfText:
    """Split bulk data text, or lines ``(file name, line number, text)`` (a file and its
    includes, :mod:`substruct.case.bdf_include`), into control lines and cards (module
    docstring).

    Raises:
        BdfError: ``CEND`` without ``BEGIN BULK``, ``INCLUDE`` in text not read from a file,
            a continuation with no card above it, a free-field line with too many fields.
    """
    out = BdfText(source)
    if isinstance(text, str):
        text = [(source, k + 1, ln) for k, ln in
                enumerate(text.replace("\r\n", "\n").replace("\r", "\n").split("\n"))]
    lines = [ln for _, _, ln in text]
    upper = [ln.split("$", 1)[0].upper() for ln in lines]
    begin = next((k for k, u in enumerate(upper) if re.match(r"^\s*BEGIN\s+BULK\b", u)), None)
    start = 0
    if begin is not None:
        cend = next((k for k, u in enumerate(upper[:begin]) if u.strip() == "CEND"), None)
        head = 0 if cend is None else cend + 1
        out.executive = [(text[k][1], upper[k].strip()) for k in range(0, cend or 0)
                         if upper[k].strip()]
        out.case_control = [(text[k][1], upper[k].strip()) for k in range(head, begin)
                            if upper[k].strip()]
        start = begin + 1
    elif any(u.strip() == "CEND" for u in upper):
        raise BdfError(source, "executive and case control (CEND) without BEGIN BULK")
    current: RawCard | None = None
    for k in range(start, len(lines)):
        raw = lines[k].split("$", 1)[0].expandtabs(8).rstrip()
        if not raw.strip():
            continue
        src, n = text[k][0], text[k][1]
        if raw.strip().upper().split()[0].split(",")[0] == "ENDDATA":  # text after it: ignored
            _nothing_after(text, lines, k + 1)
            break
        if len(raw) > 80:
            raise BdfError(src, "a bulk data line holds 80 columns: the text beyond column 80 "
                           "would not be read", raw[80:].strip(), line=n)
        if raw.upper().startswith("INCLUDE"):
            raise BdfError(src, "INCLUDE is read from a file (substruct run MODEL.bdf, or "
                           "type: nastran): the included file is named relative to it",
                           raw.strip(), line=n)
        first, data, large = _line_fields(raw[:80], src, n)
        if raw[0] in " +*,":
            if current is None:
                raise BdfError(src, "a continuation line with no card above it",
                               raw.strip(), line=n)
            if not large:
                current.fields += [""] * (-len(current.fields) % 8)
            current.fields += data
            continue
        current = RawCard(first.rstrip("*"), list(data), n, src)
        out.cards.append(current)
    for card in out.cards:
        while card.fields and not card.fields[-1]:
            card.fields.pop()
    return out
