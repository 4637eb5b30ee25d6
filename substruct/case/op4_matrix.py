r"""The matrices of an OP4 file as they are read, whatever the file's kind: the header checks,
the memory budget, and the columns gathered into a dense or sparse matrix
(:mod:`substruct.case.op4` reads the files, :mod:`substruct.case.op4_text` their text form)."""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np
import scipy.sparse as sp

from substruct.case.fields import MAX_MATRIX_SIZE, gigabytes
__all__ = ["Op4Error", "Op4Matrix", "ReadBudget", "MatrixBuilder", "column_strings", "BIGMAT_ROWS",
           "FORMS", "MAX_OP4_LINE", "MATRIX_NAME", "NUMBER_FORMAT", "SPARSE_ENTRY_BYTES"]

#: Rows from which a sparse matrix uses the BIGMAT strings (Nastran's rule).
BIGMAT_ROWS = 65536
#: Forms read (stored as full columns); 3, 8 and 9 are stored otherwise and refused.
FORMS = {1: "square", 2: "rectangular", 4: "lower triangular", 5: "upper triangular",
         6: "symmetric"}
#: Longest line of a text file (characters).
MAX_OP4_LINE = 1024
#: Bytes held per stored entry of a sparse matrix while it is read (row index, value, copies).
SPARSE_ENTRY_BYTES = 40
MATRIX_NAME = re.compile(r"^[A-Za-z0-9_.-]{1,16}$")
NUMBER_FORMAT = re.compile(r"^(?:1P,)?(\d{1,2})[ED](\d{1,2})(?:\.(\d{1,2}))?$")


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


class ReadBudget:
    """Bytes allowed for what is read, spent before each allocation."""

    def __init__(self, where: str, limit: float) -> None:
        self.where, self.limit, self.used = where, limit, 0.0

    def spend(self, nbytes: float, what: str) -> None:
        if self.used + nbytes > self.limit:
            raise Op4Error(f"{self.where}: {what} would need about "
                           f"{gigabytes(self.used + nbytes)} of memory, more than the "
                           f"{gigabytes(self.limit)} allowed")
        self.used += nbytes


class MatrixBuilder:
    """A matrix being read: its header checked, its columns put in place."""

    def __init__(self, file: str, header: tuple[int, int, int, int, str], keep: bool,
                 budget: ReadBudget) -> None:
        cols, rows, form, mtype, name = header
        self.where = f"{file}: matrix {name!r}"
        self.name, self.form, self.type = name, form, mtype
        if not MATRIX_NAME.match(name):
            raise Op4Error(f"{file}: a matrix name is letters, digits, '_', '.' or '-' "
                           f"(at most 16): {name!r}")
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
        self.budget.spend(float(n) * SPARSE_ENTRY_BYTES, f"matrix {self.name!r}")
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


def column_strings(m: MatrixBuilder, icol: int, words: Callable[[int, int], np.ndarray],
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


