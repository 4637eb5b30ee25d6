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
  4-byte binary files, one word in 8-byte files (where singles are stored as doubles too).

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
import re
import struct
from dataclasses import dataclass
from pathlib import Path
from typing import Any, BinaryIO, Callable, Iterator, Sequence

import numpy as np
import scipy.sparse as sp

from substruct.case.fields import MAX_MATRIX_SIZE, MEMORY_LIMIT, gigabytes

__all__ = ["Op4Error", "Op4Matrix", "read_op4", "op4_names", "BIGMAT_ROWS", "FORMS",
           "MAX_OP4_LINE"]

#: Rows from which a sparse matrix uses the BIGMAT strings (Nastran's rule).
BIGMAT_ROWS = 65536
#: Forms read (stored as full columns); 3, 8 and 9 are stored otherwise and refused.
FORMS = {1: "square", 2: "rectangular", 4: "lower triangular", 5: "upper triangular",
         6: "symmetric"}
#: Longest line of a text file (characters).
MAX_OP4_LINE = 1024
#: Bytes held per stored entry of a sparse matrix while it is read (row index, value, copies).
_SPARSE_ENTRY = 40
_NAME = re.compile(r"^[A-Za-z0-9_.-]{1,16}$")
_FORMAT = re.compile(r"^(?:1P,)?(\d{1,2})[ED](\d{1,2})(?:\.(\d{1,2}))?$")


class Op4Error(ValueError):
    """An OP4 file that cannot be read: one line naming the file, the matrix, the problem."""


@dataclass(frozen=True)
class Op4Matrix:
    """One matrix of an OP4 file.

    Attributes:
        name: its name as written (blanks removed); looked up without regard to case.
        rows, cols: its size.
        form: the Nastran form code (:data:`FORMS`).
        type: 1 real single, 2 real double, 3 complex single, 4 complex double.
        storage: ``"dense"``, ``"sparse"`` (non-BIGMAT strings) or ``"bigmat"``.
        data: an ``ndarray`` (dense storage) or a ``csc_array`` (sparse storage), float64 or
            complex128.
    """

    name: str
    rows: int
    cols: int
    form: int
    type: int
    storage: str
    data: Any

    @property
    def is_complex(self) -> bool:
        """Whether the type is complex (3 or 4)."""
        return self.type in (3, 4)

    def dense(self) -> np.ndarray:
        """The matrix as an ``ndarray``."""
        return self.data.toarray() if sp.issparse(self.data) else np.asarray(self.data)


class _Budget:
    """Bytes allowed for what is read, spent before each allocation."""

    def __init__(self, where: str, limit: float) -> None:
        self.where, self.limit, self.used = where, limit, 0.0

    def spend(self, nbytes: float, what: str) -> None:
        if self.used + nbytes > self.limit:
            raise Op4Error(f"{self.where}: {what} would need about "
                           f"{gigabytes(self.used + nbytes)} of memory, more than the "
                           f"{gigabytes(self.limit)} allowed")
        self.used += nbytes


class _Matrix:
    """A matrix being read: its header checked, its columns put in place."""

    def __init__(self, file: str, header: tuple[int, int, int, int, str], keep: bool,
                 budget: _Budget) -> None:
        cols, rows, form, mtype, name = header
        self.where = f"{file}: matrix {name!r}"
        self.name, self.form, self.type = name, form, mtype
        if not _NAME.match(name):
            raise Op4Error(f"{file}: a matrix name is letters, digits, '_', '.' or '-' "
                           f"(at most 16), got {name!r}")
        if mtype not in (1, 2, 3, 4):
            raise Op4Error(f"{self.where}: type {mtype} is not 1-4 (real/complex, "
                           f"single/double)")
        if form not in FORMS:
            raise Op4Error(f"{self.where}: form {form} is not read (forms "
                           f"{', '.join(f'{k} {v}' for k, v in FORMS.items())} are)")
        self.bigmat = rows < 0 or rows >= BIGMAT_ROWS
        self.rows, self.cols = abs(rows), cols
        for what, n in (("rows", self.rows), ("columns", cols)):
            if not 1 <= n <= MAX_MATRIX_SIZE:
                raise Op4Error(f"{self.where}: {n} {what} declared; 1 to {MAX_MATRIX_SIZE} "
                               f"are accepted")
        if form in (1, 6) and self.rows != cols:
            raise Op4Error(f"{self.where}: form {form} ({FORMS[form]}) but {self.rows} rows "
                           f"and {cols} columns")
        self.complex = mtype in (3, 4)
        self.dtype = np.complex128 if self.complex else np.float64
        self.keep, self.budget = keep, budget
        self.last = 0
        self.storage = ""
        self.dense: np.ndarray | None = None
        self.parts: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []

    def begin(self, icol: int, irow: int) -> bool:
        """Check a column header; ``False`` for the closing column ``cols + 1``."""
        if icol <= self.last or icol > self.cols + 1:
            raise Op4Error(f"{self.where}: column {icol} after column {self.last} (columns "
                           f"are 1 to {self.cols + 1}, increasing)")
        self.last = icol
        if icol == self.cols + 1:
            return False
        storage = "dense" if irow > 0 else ("bigmat" if self.bigmat else "sparse")
        if irow < 0 or (self.storage and storage != self.storage):
            raise Op4Error(f"{self.where}: column {icol} has first row {irow} (dense columns "
                           f"start at a row >= 1, sparse ones at 0, never mixed)")
        if not self.storage:
            self.storage = storage
            if storage == "dense" and self.keep:
                size = np.dtype(self.dtype).itemsize
                self.budget.spend(float(self.rows) * self.cols * size,
                                  f"matrix {self.name!r} ({self.rows} x {self.cols}, dense)")
                self.dense = np.zeros((self.rows, self.cols), dtype=self.dtype)
        return True

    def numbers(self, count: int, what: str) -> int:
        """Entries of ``count`` numbers (pairs if complex), with the check of the pairs."""
        if self.complex and count % 2:
            raise Op4Error(f"{self.where}: {what} holds {count} numbers, not pairs of a "
                           f"complex matrix")
        return count // 2 if self.complex else count

    def put(self, icol: int, row: int, values: np.ndarray, what: str) -> None:
        """Entries from 1-based ``row`` down column ``icol`` (real, or pairs if complex)."""
        n = values.size // 2 if self.complex else values.size
        if row < 1 or row - 1 + n > self.rows:
            raise Op4Error(f"{self.where}: {what} covers rows {row} to {row - 1 + n}, "
                           f"outside 1 to {self.rows}")
        if not self.keep:
            return
        vals = values[0::2] + 1j * values[1::2] if self.complex else values
        if self.dense is not None:
            self.dense[row - 1:row - 1 + n, icol - 1] = vals
            return
        self.budget.spend(float(n) * _SPARSE_ENTRY, f"matrix {self.name!r}")
        r = np.arange(row - 1, row - 1 + n, dtype=np.int64)
        self.parts.append((r, np.full(n, icol - 1, dtype=np.int64),
                           np.asarray(vals, dtype=self.dtype)))

    def done(self) -> Op4Matrix:
        """The matrix read."""
        if self.last != self.cols + 1:
            raise Op4Error(f"{self.where}: ends without its closing column {self.cols + 1}")
        data: Any = self.dense
        if data is None:  # sparse storage, or no column at all
            if self.parts:
                r, c, v = (np.concatenate(x) for x in zip(*self.parts))
            else:
                r = c = np.zeros(0, dtype=np.int64)
                v = np.zeros(0, dtype=self.dtype)
            data = sp.csc_array((v, (r, c)), shape=(self.rows, self.cols))
        return Op4Matrix(self.name, self.rows, self.cols, self.form, self.type,
                         self.storage or "dense", data)


def _strings(m: _Matrix, icol: int, words: Callable[[int, int], np.ndarray],
             ints: Callable[[int, int], list[int]], nwords: int, wper: int) -> None:
    """Put the sparse strings of a column: ``ints(at, k)`` reads ``k`` integer words at word
    ``at``, ``words(at, n)`` ``n`` numbers of ``wper`` words each."""
    at = 0
    k = 0
    while at < nwords:
        k += 1
        what = f"column {icol} string {k}"
        head = 2 if m.bigmat else 1
        if at + head > nwords:
            raise Op4Error(f"{m.where}: {what} header runs past the column's {nwords} words")
        if m.bigmat:
            length, row = ints(at, 2)
            length -= 1
        else:
            (code,) = ints(at, 1)
            length, row = (code >> 16) - 1, code & 0xFFFF
        at += head
        if length < wper or length % wper or at + length > nwords:
            raise Op4Error(f"{m.where}: {what} declares {length} words, not a positive "
                           f"multiple of {wper} within the column's {nwords} words")
        count = length // wper
        m.numbers(count, what)
        m.put(icol, row, words(at, count), what)
        at += length


# ----------------------------------------------------------------------------- binary


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
                 wanted: Callable[[str], bool], budget: _Budget) -> Iterator[Op4Matrix]:
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
        m = _Matrix(file, (cols, rows, form, mtype, name), wanted(name), budget)
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
                _strings(m, icol, words, ints, nwords, wper)
        yield m.done()


# ------------------------------------------------------------------------------- text


class _Lines:
    """Lines of a text file, each at most :data:`MAX_OP4_LINE` characters."""

    def __init__(self, fp: BinaryIO, file: str) -> None:
        self.fp, self.file, self.number = fp, file, 0

    def next(self, where: str, eof_ok: bool = False) -> str | None:
        raw = self.fp.readline(MAX_OP4_LINE + 1)
        self.number += 1
        if not raw:
            if eof_ok:
                return None
            raise Op4Error(f"{where}: truncated: the file ends at line {self.number}")
        if len(raw) > MAX_OP4_LINE and not raw.endswith(b"\n"):
            raise Op4Error(f"{where}: line {self.number} is longer than {MAX_OP4_LINE} characters")
        return raw.decode("latin-1").rstrip("\r\n")

    def integers(self, where: str, widths: Sequence[int]) -> list[int]:
        line = self.next(where)
        assert line is not None
        out, at = [], 0
        for w in widths:
            field = line[at:at + w].strip()
            at += w
            if not re.fullmatch(r"-?\d{1,15}", field):
                raise Op4Error(f"{where}: line {self.number}: expected {len(widths)} integers "
                               f"of {w} characters, got {line[:60]!r}")
            out.append(int(field))
        return out

    def whole(self, where: str) -> list[int]:
        """The one integer of a line (a non-BIGMAT string header, of any width)."""
        line = self.next(where) or ""
        if not re.fullmatch(r"\s*\d{1,15}\s*", line):
            raise Op4Error(f"{where}: line {self.number}: expected a string header (one "
                           f"integer), got {line[:60]!r}")
        return [int(line)]

    def numbers(self, where: str, count: int, per: int, width: int) -> np.ndarray:
        out = np.empty(count)
        for start in range(0, count, per):
            line = self.next(where) or ""
            k = min(per, count - start)
            fields = [line[j * width:(j + 1) * width] for j in range(k)]
            try:
                out[start:start + k] = [float(f.replace("D", "E").replace("d", "e"))
                                        for f in fields]
            except ValueError:
                raise Op4Error(f"{where}: line {self.number}: expected {k} numbers of "
                               f"{width} characters, got {line[:60]!r}") from None
        return out


def _read_text(fp: BinaryIO, file: str, wanted: Callable[[str], bool],
               budget: _Budget) -> Iterator[Op4Matrix]:
    lines = _Lines(fp, file)
    while True:
        line = lines.next(f"{file}: after the last matrix", eof_ok=True)
        while line is not None and not line.strip():  # blank lines between matrices
            line = lines.next(f"{file}: after the last matrix", eof_ok=True)
        if line is None:
            return
        wide = line.rstrip().endswith("|I16")
        w = 16 if wide else 8
        text = line.rstrip()[:-4] if wide else line
        try:
            cols, rows, form, mtype = (int(text[0:w]), int(text[w:2 * w]),
                                       int(text[2 * w:2 * w + 8]),
                                       int(text[2 * w + 8:2 * w + 16]))
        except ValueError:
            raise Op4Error(f"{file}: line {lines.number}: not an OP4 matrix header (columns, "
                           f"rows, form, type, name, format), got {line[:60]!r}") from None
        name = text[2 * w + 16:2 * w + 24].replace(" ", "")
        fmt = text[2 * w + 24:].strip().upper()
        m = _Matrix(file, (cols, rows, form, mtype, name), wanted(name), budget)
        per, width = 5, 16
        if fmt:
            got = _FORMAT.match(fmt)
            if not got or not 1 <= int(got.group(1)) <= 20 or \
                    not 6 <= int(got.group(2)) <= 40:
                raise Op4Error(f"{m.where}: line {lines.number}: number format {fmt!r} is "
                               f"not like 1P,3E23.16")
            per, width = int(got.group(1)), int(got.group(2))
        wper = 1 if mtype in (1, 3) else 2

        def single(x: np.ndarray, cast: bool = mtype in (1, 3)) -> np.ndarray:
            """Text numbers of a single-precision matrix are the nearest float32."""
            return x.astype(np.float32).astype(np.float64) if cast else x

        while True:
            icol, irow, nwords = lines.integers(m.where, (8, 8, 8))
            if not m.begin(icol, irow):
                lines.numbers(m.where, max(nwords, 0), per, width)
                break
            if nwords < 1:
                raise Op4Error(f"{m.where}: column {icol} declares {nwords} words")
            if irow > 0:  # dense text columns count numbers, not words
                m.numbers(nwords, f"column {icol}")
                m.put(icol, irow, single(lines.numbers(m.where, nwords, per, width)),
                      f"column {icol}")
                continue

            def ints(at: int, k: int) -> list[int]:
                return lines.integers(m.where, (8, 8)) if k == 2 else lines.whole(m.where)

            def words(at: int, n: int) -> np.ndarray:
                return single(lines.numbers(m.where, n, per, width))

            _strings(m, icol, words, ints, nwords, wper)
        yield m.done()


# --------------------------------------------------------------------------- entry points


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
    budget = _Budget(file, MEMORY_LIMIT if limit is None else limit)
    with fp:
        head = fp.read(4)
        fp.seek(0)
        if len(head) < 4:
            raise Op4Error(f"{file}: not an OP4 file: {size} byte(s)")
        kind = _binary_kind(head)
        if kind is not None:
            yield from _read_binary(fp, size, file, kind[0], kind[1], wanted, budget)
        elif all(32 <= b < 127 for b in head):
            yield from _read_text(fp, file, wanted, budget)
        else:
            raise Op4Error(f"{file}: not an OP4 file: it starts neither with a text header "
                           f"nor with a binary record of 24 or 48 bytes")


def read_op4(path: str | os.PathLike, names: Sequence[str] | None = None,
             limit: float | None = None) -> dict[str, Op4Matrix]:
    """The matrices of an OP4 file, by name as written (all of them, or ``names``, matched
    without regard to case; the others are read through and checked but not kept).

    Args:
        path: the file (text or binary, detected from its first bytes).
        names: the matrices wanted; each must be in the file.
        limit: bytes allowed for the matrices kept (:data:`MEMORY_LIMIT` if ``None``).

    Raises:
        Op4Error: one line naming the file, the matrix and the problem (see the module).
    """
    want = None if names is None else {n.upper() for n in names}
    out: dict[str, Op4Matrix] = {}
    seen: dict[str, str] = {}
    for m in _matrices(path, lambda n: want is None or n.upper() in want, limit):
        if m.name.upper() in seen:
            raise Op4Error(f"{Path(path).name}: matrix {m.name!r} is written twice")
        seen[m.name.upper()] = m.name
        if want is None or m.name.upper() in want:
            out[m.name] = m
    missing = [n for n in (names or []) if n.upper() not in seen]
    if missing:
        raise Op4Error(f"{Path(path).name}: no matrix {missing[0]!r} (it has "
                       f"{', '.join(seen.values()) or 'none'})")
    return out


def op4_names(path: str | os.PathLike) -> list[str]:
    """The names of the matrices of an OP4 file, in order (the file is read through and
    checked, nothing is kept)."""
    return [m.name for m in _matrices(path, lambda n: False, None)]
