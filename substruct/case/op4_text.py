r"""The text form of OP4 files (``1P,3E23.16``-style fixed-width numbers, ``%8d`` integer lines;
``|I16`` for 16-character integers), read a line at a time, each line at most
:data:`~substruct.case.op4_matrix.MAX_OP4_LINE` characters (:mod:`substruct.case.op4`).  A line
holding more than its fields is refused, and numbers are kept as their lines are read (a
count the file does not hold allocates nothing)."""

from __future__ import annotations

import re
from typing import BinaryIO, Callable, Iterator, Sequence

import numpy as np

from substruct.case.op4_matrix import (
    MAX_OP4_LINE,
    NUMBER_FORMAT,
    MatrixBuilder,
    Op4Error,
    Op4Matrix,
    ReadBudget,
    column_strings,
)

__all__ = ["read_text"]

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
                               f"of {w} characters: {line[:60]!r}")
            out.append(int(field))
        if line[at:].strip():  # a number wider than its field, or one too many
            raise Op4Error(f"{where}: line {self.number}: expected {len(widths)} integers "
                           f"of {widths[0]} characters, but the line holds more: "
                           f"{line[:60]!r}")
        return out

    def whole(self, where: str) -> list[int]:
        """The one integer of a line (a non-BIGMAT string header, of any width)."""
        line = self.next(where) or ""
        if not re.fullmatch(r"\s*\d{1,15}\s*", line):
            raise Op4Error(f"{where}: line {self.number}: expected a string header (one "
                           f"integer): {line[:60]!r}")
        return [int(line)]

    def numbers(self, where: str, count: int, per: int, width: int) -> np.ndarray:
        """``count`` numbers, ``per`` a line of ``width`` characters: kept as the lines are
        read, so that a count the file does not hold allocates nothing."""
        out: list[float] = []
        for start in range(0, count, per):
            line = self.next(where) or ""
            k = min(per, count - start)
            fields = [line[j * width:(j + 1) * width] for j in range(k)]
            if line[k * width:].strip():  # a number wider than its field, or one too many
                raise Op4Error(f"{where}: line {self.number}: expected {k} numbers of "
                               f"{width} characters, but the line holds more: {line[:60]!r}")
            try:
                out.extend(float(f.replace("D", "E").replace("d", "e")) for f in fields)
            except ValueError:
                raise Op4Error(f"{where}: line {self.number}: expected {k} numbers of "
                               f"{width} characters: {line[:60]!r}") from None
        return np.array(out, dtype=np.float64)


def read_text(fp: BinaryIO, file: str, wanted: Callable[[str], bool],
               budget: ReadBudget) -> Iterator[Op4Matrix]:
    """The matrices of the text file open as ``fp`` (named ``file`` in errors) whose names
    ``wanted`` accepts, one at a time, each checked against ``budget`` before it is read."""
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
                           f"rows, form, type, name, format): {line[:60]!r}") from None
        name = text[2 * w + 16:2 * w + 24].replace(" ", "")
        fmt = text[2 * w + 24:].strip().upper()
        m = MatrixBuilder(file, (cols, rows, form, mtype, name), wanted(name), budget)
        per, width = 5, 16
        if fmt:
            got = NUMBER_FORMAT.match(fmt)
            if not got or not 1 <= int(got.group(1)) <= 20 or \
                    not 6 <= int(got.group(2)) <= 40:
                raise Op4Error(f"{m.where}: line {lines.number}: number format {fmt!r} is "
                               f"not like 1P,3E23.16")
            per, width = int(got.group(1)), int(got.group(2))
        # Words per number in sparse strings and the closing column (a double is two
        # single-precision words).  The numbers themselves are read as float64 whatever the
        # type: the digits written are what a text file holds, and the type code says how the
        # matrix was held by the program that wrote it.
        wper = 1 if mtype in (1, 3) else 2

        while True:
            icol, irow, nwords = lines.integers(m.where, (8, 8, 8))
            if not m.begin(icol, irow):
                # The closing column's words: one number of the matrix's precision, declared
                # as its words (2 for a double) or as one number (1); read, not kept.
                lines.numbers(m.where, -(-max(nwords, 0) // wper), per, width)
                break
            if nwords < 1:
                raise Op4Error(f"{m.where}: column {icol} declares {nwords} words")
            if irow > 0:  # dense text columns count numbers, not words
                m.numbers(nwords, f"column {icol}")
                m.put(icol, irow, lines.numbers(m.where, nwords, per, width),
                      f"column {icol}")
                continue

            def ints(at: int, k: int) -> list[int]:
                return lines.integers(m.where, (8, 8)) if k == 2 else lines.whole(m.where)

            def words(at: int, n: int) -> np.ndarray:
                return lines.numbers(m.where, n, per, width)

            column_strings(m, icol, words, ints, nwords, wper)
        yield m.done()


# --------------------------------------------------------------------------- entry points
