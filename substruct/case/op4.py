r"""Reading Nastran OUTPUT4 (``.op4``) matrix files: text and binary, dense and sparse, real
and complex, every matrix of a file by name.

A file holds matrices one after the other.  Each has a header (columns, rows, form, type,
name) and then its non-zero columns, in increasing order, each as a column number, a first row
and a count of words, closed by a column ``cols + 1``:

* **text** (``1P,3E23.16`` format): fixed-width integer lines ``%8d%8d%8d`` and lines of
  fixed-width numbers (``D`` exponents accepted); ``|I16`` after the format widens the header
  integers to 16 characters;
* **binary**: Fortran unformatted records (a 4-byte length before and after each record),
  either byte order, with 4-byte or 8-byte integers (header record of 24 or 48 bytes);
* **dense** columns (first row > 0) hold the numbers from their first to their last non-zero;
  **sparse** columns (first row 0) hold strings of consecutive non-zeros, each headed by one
  word ``IS = (L + 1) * 65536 + row`` (non-BIGMAT) or two words ``L + 1, row`` (BIGMAT, the
  header's rows negative or 65536 and more), ``L`` its count of words;
* type 1 real single, 2 real double, 3 complex single, 4 complex double (a complex number is
  two numbers, real then imaginary); a double counts two words in text sparse strings and in
  4-byte binary files, one word in 8-byte files (where singles are stored as doubles too);
* text numbers are read as float64 whatever the type: a text file holds the digits written,
  and they are kept (a type 1 or 3 code then says how the writing program held the matrix,
  not what the text carries).  Binary singles are the float32 bytes of the file;
* the closing column ``cols + 1`` holds one number, read and not kept; in text its count is
  written as words (2 for a double) by some writers, as one number by others: both are read.

A file may write a name more than once (nas2cam writes ``SE_START`` once per superelement):
it is read through; only a name asked for, or any name when all matrices are taken, that
occurs more than once is refused, naming its occurrences.

Forms 1 (square), 2 (rectangular), 4, 5 (triangular) and 6 (symmetric) are stored in full and
read as they are; a form whose storage is not the full matrix (3 diagonal, 8 identity, 9
pseudo-identity) is refused, as is any other code.

Nothing is allocated before its size is checked: rows and columns at most
:data:`~substruct.case.fields.MAX_MATRIX_SIZE`, a dense matrix's ``rows x cols`` numbers and
every sparse column's entries against the memory allowed (``limit``,
:data:`~substruct.case.fields.MEMORY_LIMIT` by default, the same on every machine), each
record's length against the bytes left in the file.  Truncated files, record markers that
disagree, record lengths that are not what their words declare, rows out of range and columns
out of order are refused in one line naming the file, the matrix and the problem.
"""

from __future__ import annotations

import os
import struct
from pathlib import Path
from typing import BinaryIO, Callable, Iterator, Sequence

import numpy as np

from substruct.case.fields import MEMORY_LIMIT
from substruct.case.op4_matrix import (
    BIGMAT_ROWS,
    FORMS,
    MAX_OP4_LINE,
    MatrixBuilder,
    Op4Error,
    Op4Matrix,
    ReadBudget,
    column_strings,
)
from substruct.case.op4_text import read_text

__all__ = ["Op4Error", "Op4Matrix", "read_op4", "op4_names", "BIGMAT_ROWS", "FORMS",
           "MAX_OP4_LINE"]


def _binary_kind(head: bytes) -> tuple[str, int] | None:
    """``(byte order, integer bytes)`` of a binary file from its first record marker."""
    for order in ("<", ">"):
        (n,) = struct.unpack(order + "i", head[:4])
        if n in (24, 48):
            return order, 4 if n == 24 else 8
    return None


class _Records:
    """The Fortran records of a binary file, each length checked against what is left."""

    def __init__(self, fp: BinaryIO, size: int, order: str, file: str) -> None:
        self.fp, self.size, self.order, self.file = fp, size, order, file

    def next(self, where: str) -> bytes | None:
        """The next record's body, ``None`` at the end of the file."""
        pos = self.fp.tell()
        mark = self.fp.read(4)
        if not mark:
            return None
        if len(mark) < 4:
            raise Op4Error(f"{where}: truncated: {len(mark)} byte(s) where a record starts")
        (n,) = struct.unpack(self.order + "i", mark)
        left = self.size - pos - 8
        if n < 0 or n > left:
            raise Op4Error(f"{where}: truncated or wrong record length: a record of {n} "
                           f"bytes at byte {pos}, but {max(left, 0)} are left")
        body = self.fp.read(n)
        (end,) = struct.unpack(self.order + "i", self.fp.read(4))
        if end != n:
            raise Op4Error(f"{where}: wrong record length: the record at byte {pos} starts "
                           f"with {n} and ends with {end}")
        return body


def _read_binary(fp: BinaryIO, size: int, file: str, order: str, isz: int,
                 wanted: Callable[[str], bool], budget: ReadBudget) -> Iterator[Op4Matrix]:
    recs = _Records(fp, size, order, file)
    ichar = "i" if isz == 4 else "q"
    while True:
        head = recs.next(f"{file}: matrix header")
        if head is None:
            return
        if len(head) != 6 * isz:
            raise Op4Error(f"{file}: wrong record length: a matrix header of {len(head)} "
                           f"bytes, {6 * isz} expected with {isz}-byte integers")
        cols, rows, form, mtype = struct.unpack(order + 4 * ichar, head[:4 * isz])
        name = head[4 * isz:].decode("latin-1").replace("\x00", " ").replace(" ", "")
        m = MatrixBuilder(file, (cols, rows, form, mtype, name), wanted(name), budget)
        single = mtype in (1, 3) and isz == 4
        wper = 1 if single or isz == 8 else 2
        num = np.dtype(order + ("f4" if single else "f8"))
        while True:
            body = recs.next(m.where)
            if body is None:
                raise Op4Error(f"{m.where}: truncated: the file ends after column {m.last} "
                               f"of {m.cols}")
            if len(body) < 3 * isz:
                raise Op4Error(f"{m.where}: wrong record length: a column record of "
                               f"{len(body)} bytes")
            icol, irow, nwords = struct.unpack(order + 3 * ichar, body[:3 * isz])
            if not m.begin(icol, irow):
                break
            if len(body) != (3 + nwords) * isz:
                raise Op4Error(f"{m.where}: wrong record length: column {icol} declares "
                               f"{nwords} words ({(3 + nwords) * isz} bytes) in a record of "
                               f"{len(body)} bytes")
            data = memoryview(body)[3 * isz:]

            def words(at: int, n: int, data: memoryview = data) -> np.ndarray:
                return np.frombuffer(data, num, n, at * isz).astype(np.float64)

            if irow > 0:
                if nwords % wper:
                    raise Op4Error(f"{m.where}: column {icol} has {nwords} words, not whole "
                                   f"numbers of {wper} words")
                count = nwords // wper
                m.numbers(count, f"column {icol}")
                m.put(icol, irow, words(0, count), f"column {icol}")
            else:
                def ints(at: int, k: int, data: memoryview = data) -> list[int]:
                    return list(struct.unpack_from(order + k * ichar, data, at * isz))
                column_strings(m, icol, words, ints, nwords, wper)
        yield m.done()


def _open(path: str | os.PathLike) -> tuple[Path, int, BinaryIO]:
    p = Path(path)
    try:
        if not p.is_file():
            raise Op4Error(f"{p.name}: not a regular file")
        size = p.stat().st_size
        fp = open(p, "rb", buffering=1 << 16)
    except OSError as err:
        raise Op4Error(f"{p.name}: cannot be opened ({err.strerror})") from None
    return p, size, fp


def _matrices(path: str | os.PathLike, wanted: Callable[[str], bool],
              limit: float | None) -> Iterator[Op4Matrix]:
    p, size, fp = _open(path)
    file = p.name
    budget = ReadBudget(file, MEMORY_LIMIT if limit is None else limit)
    with fp:
        head = fp.read(4)
        fp.seek(0)
        if len(head) < 4:
            raise Op4Error(f"{file}: not an OP4 file: {size} byte(s)")
        kind = _binary_kind(head)
        if kind is not None:
            yield from _read_binary(fp, size, file, kind[0], kind[1], wanted, budget)
        elif all(32 <= b < 127 for b in head):
            yield from read_text(fp, file, wanted, budget)
        else:
            raise Op4Error(f"{file}: not an OP4 file: it starts neither with a text header "
                           f"nor with a binary record of 24 or 48 bytes")


def read_op4(path: str | os.PathLike, names: Sequence[str] | None = None,
             limit: float | None = None) -> dict[str, Op4Matrix]:
    """The matrices of an OP4 file, by name as written (all of them, or ``names``, matched
    without regard to case; the others are read through and checked but not kept).

    Args:
        path: the file (text or binary, detected from its first bytes).
        names: the matrices wanted; each must be in the file, once (all of them must be
            written once when ``names`` is ``None``).
        limit: bytes allowed for the matrices kept (:data:`MEMORY_LIMIT` if ``None``).

    Raises:
        Op4Error: one line naming the file, the matrix and the problem (see the module).
    """
    want = None if names is None else {n.upper() for n in names}
    out: dict[str, Op4Matrix] = {}
    seen: dict[str, str] = {}
    where: dict[str, list[int]] = {}  # the 1-based positions of each name in the file
    count = 0

    def wanted(name: str) -> bool:
        """Keep the first occurrence of a name asked for (a repeat is refused below)."""
        nonlocal count
        count += 1
        where.setdefault(name.upper(), []).append(count)
        return (want is None or name.upper() in want) and len(where[name.upper()]) == 1

    for m in _matrices(path, wanted, limit):
        key = m.name.upper()
        if key not in seen:
            seen[key] = m.name
            if want is None or key in want:
                out[m.name] = m
    asked = list(where) if want is None else [n for n in where if n in want]
    for key in asked:
        if len(where[key]) > 1:
            places = where[key]
            raise Op4Error(f"{Path(path).name}: matrix {seen[key]!r} is written "
                           f"{len(places)} times (matrices {_and(places)} of the file): "
                           f"which one is meant is ambiguous")
    missing = [n for n in (names or []) if n.upper() not in seen]
    if missing:
        raise Op4Error(f"{Path(path).name}: no matrix {missing[0]!r} (it has "
                       f"{', '.join(dict.fromkeys(seen.values())) or 'none'})")
    return out


def _and(numbers: Sequence[int]) -> str:
    """``1, 4 and 9``."""
    text = [str(n) for n in numbers]
    return ", ".join(text[:-1]) + " and " + text[-1] if len(text) > 1 else text[0]


def op4_names(path: str | os.PathLike) -> list[str]:
    """The names of the matrices of an OP4 file, in order (the file is read through and
    checked, nothing is kept)."""
    return [m.name for m in _matrices(path, lambda n: False, None)]
