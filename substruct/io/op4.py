r"""Writing Nastran OUTPUT4 (``.op4``) files: the layouts :mod:`substruct.case.op4` reads.

Text (``1P,3E24.16``: 17 significant digits, so that a double read back is the double
written) or binary (Fortran records, either byte order, 4-byte or 8-byte integers); dense
columns (first to last non-zero) or sparse strings of consecutive non-zeros (non-BIGMAT, or
BIGMAT with the rows written negative); real or complex; double or single precision.  All-zero
columns are left out, and each matrix closes with the column ``cols + 1`` holding ``1.0``.
The file is written beside its final name and renamed into place.
"""

from __future__ import annotations

import io
import os
import struct
from pathlib import Path
from typing import Any, BinaryIO, Iterator, Mapping

import numpy as np
import scipy.sparse as sp

from substruct.case.op4 import BIGMAT_ROWS

__all__ = ["write_op4", "STORAGES"]

#: How columns are written: ``"auto"`` is dense for arrays, sparse for sparse matrices.
STORAGES = ("auto", "dense", "sparse", "bigmat")


def _form(A: Any) -> int:
    """Nastran form: 6 symmetric, 1 square, 2 rectangular."""
    r, c = A.shape
    if r != c:
        return 2
    diff = abs(A - A.T)
    return 6 if float(diff.max() if diff.size else 0.0) == 0.0 else 1


def _columns(A: sp.csc_array) -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
    """``(column, rows, values)`` of each column with a non-zero, rows ascending."""
    A = sp.csc_array(A)
    A.sum_duplicates()
    A.sort_indices()
    for j in range(A.shape[1]):
        a, b = A.indptr[j], A.indptr[j + 1]
        keep = A.data[a:b] != 0
        if keep.any():
            yield j, A.indices[a:b][keep], A.data[a:b][keep]


def _runs(rows: np.ndarray) -> list[tuple[int, int]]:
    """``(start, length)`` of each run of consecutive rows (as positions in ``rows``)."""
    breaks = np.flatnonzero(np.diff(rows) != 1) + 1
    starts = np.concatenate([[0], breaks])
    ends = np.concatenate([breaks, [rows.size]])
    return [(int(s), int(e - s)) for s, e in zip(starts, ends)]


def _flat(values: np.ndarray, complex_: bool, single: bool) -> np.ndarray:
    """Numbers as written: reals, or (real, imaginary) pairs; rounded to single precision
    for types 1 and 3."""
    if complex_:
        v = np.asarray(values, dtype=np.complex128)
        x = np.column_stack([v.real, v.imag]).ravel()
    else:
        x = np.asarray(values, dtype=np.float64)
    return x.astype(np.float32).astype(np.float64) if single else x


class _Writer:
    """One file's layout: text or binary, integer size, byte order, precision."""

    def __init__(self, fp: BinaryIO, binary: bool, order: str, int_bytes: int, single: bool,
                 digits: int) -> None:
        self.fp, self.binary, self.order, self.isz = fp, binary, order, int_bytes
        self.single, self.digits = single, digits
        self.width = digits + 8  # sign, digit, point, digits, E, sign, three exponent digits
        self.per = max(1, 80 // self.width)
        # words per number: text sparse strings and 4-byte binary count a double as two
        self.wper = 1 if (single or (binary and int_bytes == 8)) else 2
        self.ichar = "i" if int_bytes == 4 else "q"

    def _record(self, body: bytes) -> None:
        mark = struct.pack(self.order + "i", len(body))
        self.fp.write(mark + body + mark)

    def _ints(self, *values: int) -> bytes:
        return struct.pack(self.order + len(values) * self.ichar, *values)

    def _numbers(self, x: np.ndarray) -> bytes:
        kind = "f4" if self.single and self.isz == 4 else "f8"
        return np.asarray(x, dtype=np.dtype(self.order + kind)).tobytes()

    def _text_numbers(self, x: np.ndarray) -> str:
        fmt = f"%{self.width}.{self.digits}E"
        lines = []
        for k in range(0, x.size, self.per):
            lines.append("".join(fmt % v for v in x[k:k + self.per]))
        return "\n".join(lines) + "\n"

    def header(self, name: str, rows: int, cols: int, form: int, mtype: int) -> None:
        if self.binary:
            size = 8 if self.isz == 4 else 16
            self._record(self._ints(cols, rows, form, mtype) +
                         name.upper().ljust(size).encode("ascii"))
            return
        wide = abs(rows) > 9_999_999 or cols > 9_999_998
        w = 16 if wide else 8
        self.fp.write((f"{cols:{w}d}{rows:{w}d}{form:8d}{mtype:8d}{name.upper():<8s}"
                       f"1P,{self.per}E{self.width}.{self.digits}"
                       f"{'|I16' if wide else ''}\n").encode("ascii"))

    def dense(self, icol: int, row: int, x: np.ndarray) -> None:
        """A dense column ``icol`` (1-based) from 1-based ``row``: ``x`` the numbers."""
        if self.binary:
            self._record(self._ints(icol, row, x.size * self.wper) + self._numbers(x))
        else:  # text dense columns count numbers
            self.fp.write(f"{icol:8d}{row:8d}{x.size:8d}\n".encode("ascii") +
                          self._text_numbers(x).encode("ascii"))

    def sparse(self, icol: int, strings: list[tuple[int, np.ndarray]], bigmat: bool) -> None:
        """A sparse column: ``(1-based first row, numbers)`` of each string."""
        head = 2 if bigmat else 1
        nwords = sum(head + x.size * self.wper for _, x in strings)
        if self.binary:
            parts = [self._ints(icol, 0, nwords)]
            for row, x in strings:
                L = x.size * self.wper
                parts.append(self._ints(L + 1, row) if bigmat else
                             self._ints(((L + 1) << 16) + row))
                parts.append(self._numbers(x))
            self._record(b"".join(parts))
            return
        out = [f"{icol:8d}{0:8d}{nwords:8d}\n"]
        for row, x in strings:
            L = x.size * self.wper
            out.append(f"{L + 1:8d}{row:8d}\n" if bigmat else f"{((L + 1) << 16) + row:d}\n")
            out.append(self._text_numbers(x))
        self.fp.write("".join(out).encode("ascii"))

    def close(self, cols: int) -> None:
        self.dense(cols + 1, 1, np.ones(1))


def write_op4(path: str | os.PathLike, matrices: Mapping[str, Any], *, binary: bool = False,
              order: str = "<", int_bytes: int = 4, storage: str = "auto",
              precision: str = "double", digits: int | None = None,
              forms: Mapping[str, int] | None = None) -> None:
    """Write ``matrices`` (name -> dense or sparse, real or complex) to an OP4 file, in order.

    Args:
        path: the file to write (replaced).
        binary: Fortran records instead of text.
        order: ``"<"`` little-endian or ``">"`` big-endian (binary).
        int_bytes: 4 or 8 (binary): the size of integers, and of words.
        storage: ``"dense"``, ``"sparse"`` (BIGMAT from 65536 rows, Nastran's rule),
            ``"bigmat"`` or ``"auto"`` (:data:`STORAGES`).
        precision: ``"double"`` (types 2, 4) or ``"single"`` (types 1, 3).
        digits: text digits after the point (16 for doubles: 17 significant digits, which
            read back exactly; 9 for singles).
        forms: the Nastran form of some matrices (6 symmetric, 1 square, 2 rectangular by
            default, from the matrix).

    Raises:
        ValueError: a name that is not 1-8 letters, digits or ``_`` (16 in 8-byte binary
            files), a matrix that is not 2-D or not finite, an unknown option.
    """
    if storage not in STORAGES or precision not in ("double", "single") or \
            int_bytes not in (4, 8) or order not in ("<", ">"):
        raise ValueError(f"storage {storage!r}, precision {precision!r}, int_bytes "
                         f"{int_bytes!r}, order {order!r}: not an OP4 layout")
    single = precision == "single"
    digits = (9 if single else 16) if digits is None else int(digits)
    if not 1 <= digits <= 30:
        raise ValueError(f"digits must be 1 to 30, got {digits}")
    longest = 16 if binary and int_bytes == 8 else 8
    p = Path(path)
    tmp = p.with_name(p.name + ".tmp")
    buf = io.BytesIO()
    w = _Writer(buf, binary, order, int_bytes, single, digits)
    for name, A in matrices.items():
        if not (name.isascii() and name.replace("_", "a").isalnum()) or \
                not 1 <= len(name) <= longest:
            raise ValueError(f"an OP4 matrix name is 1 to {longest} letters, digits or '_', "
                             f"got {name!r}")
        M = sp.csc_array(A) if sp.issparse(A) else np.asarray(A)
        if M.ndim != 2 or 0 in M.shape:
            raise ValueError(f"{name}: not a 2-D matrix with rows and columns, shape "
                             f"{M.shape}")
        values = M.data if sp.issparse(M) else M
        if not np.all(np.isfinite(values)):
            raise ValueError(f"{name}: entries that are not finite")
        complex_ = np.iscomplexobj(values)
        mtype = (3 if single else 4) if complex_ else (1 if single else 2)
        rows, cols = M.shape
        kind = storage if storage != "auto" else ("sparse" if sp.issparse(M) else "dense")
        bigmat = kind == "bigmat" or (kind == "sparse" and rows >= BIGMAT_ROWS)
        form = (forms or {}).get(name) or _form(M)
        w.header(name, -rows if bigmat else rows, cols, form, mtype)
        for j, r, v in _columns(sp.csc_array(M)):
            if kind == "dense":
                full = np.zeros(int(r[-1] - r[0] + 1), dtype=v.dtype)
                full[r - r[0]] = v
                w.dense(j + 1, int(r[0]) + 1, _flat(full, complex_, single))
            else:
                w.sparse(j + 1, [(int(r[s]) + 1, _flat(v[s:s + n], complex_, single))
                                 for s, n in _runs(r)], bigmat)
        w.close(cols)
    try:
        tmp.write_bytes(buf.getvalue())
        os.replace(tmp, p)
    finally:
        if tmp.exists():
            tmp.unlink()
