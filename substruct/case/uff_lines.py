"""Reading a Universal File line by line: the lines (each at most :data:`MAX_UFF_LINE`
bytes, counted for the messages), the ``-1`` delimiter and the fixed-column fields of a
record (:mod:`substruct.case.uff_records`)."""

from __future__ import annotations

from typing import BinaryIO, Iterator

__all__ = ["UffLines", "MAX_UFF_LINE", "is_delimiter", "fixed_field", "ints", "floats"]

#: Longest line read (the specification's records are 80 columns).
MAX_UFF_LINE = 1024


class UffLines:
    """Lines of a binary stream, each at most :data:`MAX_UFF_LINE` bytes, counted."""

    def __init__(self, fh: BinaryIO, name: str, size: int):
        self.fh, self.name, self.size, self.number = fh, name, size, 0

    def next(self) -> bytes | None:
        raw = self.fh.readline(MAX_UFF_LINE + 2)
        if not raw:
            return None
        self.number += 1
        if len(raw) > MAX_UFF_LINE and not raw.endswith(b"\n"):
            raise ValueError(f"{self.name}: line {self.number} is longer than {MAX_UFF_LINE} "
                             "characters: not a Universal File")
        if b"\0" in raw:
            raise ValueError(f"{self.name}: line {self.number} holds a NUL byte: not a text "
                             "line of a Universal File")
        return raw.rstrip(b"\r\n")

    def left(self) -> int:
        return self.size - self.fh.tell()

    def until_delimiter(self, what: str) -> Iterator[bytes]:
        """The lines up to the closing ``-1`` of a dataset (not included); ``what`` names the
        dataset (or record) in the error when the file ends before it."""
        while True:
            line = self.next()
            if line is None:
                raise ValueError(f"{what} ends without the closing -1")
            if is_delimiter(line):
                return
            yield line


def is_delimiter(line: bytes) -> bool:
    """Whether ``line`` is the ``    -1`` that opens and closes a dataset."""
    return line.strip() == b"-1" and line[:6] == b"    -1"


def fixed_field(text: str, a: int, b: int, kind: type, what: str) -> int | float:
    """Columns ``a:b`` of ``text`` as ``kind`` (``int`` or ``float``, a Fortran ``D``
    exponent read as ``E``).

    Raises:
        ValueError: ``<what>: '<text>' is not an integer`` (or a number).
    """
    raw = text[a:b].strip()
    try:
        return kind(raw.replace("D", "E").replace("d", "e")) if kind is float else kind(raw)
    except ValueError:
        raise ValueError(f"{what}: {raw!r} is not {'an integer' if kind is int else 'a number'}"
                         ) from None


def ints(text: str, n: int, what: str) -> list[int]:
    """The first ``n`` fields ``I10`` of ``text``."""
    return [int(fixed_field(text, 10 * i, 10 * i + 10, int, f"{what} field {i + 1}"))
            for i in range(n)]


def floats(text: str, n: int, width: int, what: str) -> tuple[float, ...]:
    """The first ``n`` real fields of ``width`` columns of ``text``."""
    return tuple(float(fixed_field(text, width * i, width * i + width, float,
                                    f"{what} field {i + 1}")) for i in range(n))
