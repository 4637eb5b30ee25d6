"""Substructures given by their matrices: inline rows or ``.npz``/``.npy``/``.mtx`` files.

:class:`MatrixSpec` loads ``M``, ``K`` and ``C`` while the case is validated and checks what
the coupler relies on: square, of one size, finite and within the range of
:mod:`substruct.case.numbers`, ``M`` and ``K`` symmetric and positive semidefinite.

A file's header is read before its data, so that a matrix too large for the memory (or a
header that lies about its size) is refused up front instead of being allocated: at most
:data:`~substruct.case.fields.MAX_MATRIX_SIZE` coordinates, at most
:data:`~substruct.case.fields.MAX_DENSE_ENTRIES` entries for a dense matrix (``.npy``,
``.npz``, Matrix Market ``array``), about :data:`~substruct.case.fields.MEMORY_LIMIT` bytes
while it is read, and no more data promised than the file (or the zip member) holds.  The file
must be a regular file (not a FIFO or a device).
"""

from __future__ import annotations

from collections import Counter

import os
import re
import stat
from pathlib import Path
from typing import Annotated, Any, Literal, Mapping

import numpy as np
import scipy.sparse as sp
from pydantic import (
    AfterValidator,
    PrivateAttr,
    StringConstraints,
    ValidationInfo,
    model_validator,
)

from substruct.case.errors import FieldError
from substruct.case.expressions import ExpressionError, scalar
from substruct.case.fields import (
    DENSE_CHECK,
    MAX_DENSE_ENTRIES,
    MAX_MATRIX_SIZE,
    MEMORY_LIMIT,
    Name,
    StrictModel,
    gigabytes,
)
from substruct.case.npz_files import npz_members, read_npz
from substruct.case.numbers import array_problem, number_problem

__all__ = ["MatrixSpec", "MatrixSource", "load_matrix"]

_FORMS = "a matrix is a list of rows, or {file: name.npz, key: K} or {file: name.mtx}"
#: Bytes of a Matrix Market header (banner, comments, size line) read at most.
MTX_HEADER = 65_536
#: Bytes per stored entry of a sparse matrix while it is read and converted (indices, copies).
_SPARSE_ENTRY = 40
#: Bytes per entry of a dense matrix while it is read and converted to float64 (two copies).
_DENSE_ENTRY = 16


def _matrix_source(value: Any) -> Any:
    if value is None or isinstance(value, list):
        return value
    if isinstance(value, dict):
        extra = sorted(set(map(str, value)) - {"file", "key"})
        if not extra and "file" in value and isinstance(value["file"], str):
            return value
    raise ValueError(_FORMS)


#: What ``M``, ``K`` and ``C`` may be: rows, or a file (and a key in an ``.npz``).
MatrixSource = Annotated[Any, AfterValidator(_matrix_source)]


def _entries(field: str, rows: list, parameters: Mapping[str, float]) -> list:
    """Inline rows with expression entries (of the case parameters) evaluated."""
    out = []
    for i, row in enumerate(rows):
        if not isinstance(row, list):
            raise FieldError((field, i), "must be a row (a list of numbers)", row)
        new = []
        for j, v in enumerate(row):
            if isinstance(v, str):
                try:
                    v = scalar(v, parameters)
                except ExpressionError as err:
                    raise FieldError((field, i, j), str(err), v) from None
            elif isinstance(v, bool) or not isinstance(v, (int, float)):
                raise FieldError((field, i, j), "must be a number or an expression of the "
                                 "parameters", v)
            else:
                problem = number_problem(v)
                if problem is not None:
                    raise FieldError((field, i, j), problem, v)
            new.append(v)
        out.append(new)
    return out


# ----------------------------------------------------------------------- file headers


def _npy_header(fp: Any) -> tuple[tuple[int, ...], np.dtype]:
    version = np.lib.format.read_magic(fp)
    if version == (1, 0):
        shape, _, dtype = np.lib.format.read_array_header_1_0(fp)
    else:
        shape, _, dtype = np.lib.format.read_array_header_2_0(fp)
    return tuple(shape), dtype


def _size_check(field: str, file: str, shape: tuple[int, ...], entries: int,
                per_entry: int, dense: bool) -> None:
    """Refuse a matrix whose header promises more than :data:`MEMORY_LIMIT`,
    :data:`MAX_MATRIX_SIZE` coordinates or (dense) :data:`MAX_DENSE_ENTRIES` entries, before
    reading its data."""
    if any(d > MAX_MATRIX_SIZE * 1000 for d in shape) or entries > 10 ** 18:
        raise FieldError((field, "file"), f"a matrix of shape {list(shape)} is more than the "
                         f"{MAX_MATRIX_SIZE} coordinates accepted", file)
    need = float(entries) * per_entry
    dims = " x ".join(str(d) for d in shape)
    if need > MEMORY_LIMIT:
        raise FieldError((field, "file"), f"a {dims} matrix with {entries} stored entries "
                         f"would need about {gigabytes(need)} of memory, more than the "
                         f"{gigabytes(MEMORY_LIMIT)} allowed", file)
    if shape and max(shape) > MAX_MATRIX_SIZE:
        raise FieldError((field, "file"), f"a {dims} matrix is more than the "
                         f"{MAX_MATRIX_SIZE} coordinates accepted", file)
    if dense and entries > MAX_DENSE_ENTRIES:
        raise FieldError((field, "file"), f"a dense {dims} matrix has {entries} entries, more "
                         f"than the {MAX_DENSE_ENTRIES} accepted (4000 x 4000): give a large "
                         f"sparse matrix as a Matrix Market coordinate file (.mtx)", file)


def _promised(field: str, file: str, need: int, have: int, what: str) -> None:
    """Refuse a header that promises more data than the file holds (before allocating)."""
    if need > have:
        raise FieldError((field, "file"), f"the header promises {what} ({need} bytes or "
                         f"more) but the file holds {have} bytes after it: a truncated file "
                         f"or a header that lies", file)


_MTX_FORMATS = ("coordinate", "array")
_MTX_FIELDS = ("real", "integer", "complex", "pattern")
_MTX_SYMMETRY = ("general", "symmetric", "skew-symmetric", "hermitian")


def _mtx_header(field: str, file: str, path: Path) -> tuple[int, int, int, str, str, str, int]:
    """``(rows, cols, entries, format, field, symmetry, bytes after the header)`` of a Matrix
    Market file, read from at most :data:`MTX_HEADER` bytes; numbers of more than 12 digits
    are refused before they are converted."""
    def bad(problem: str) -> FieldError:
        return FieldError((field, "file"), f"not a Matrix Market file: {problem}", file)

    size = path.stat().st_size
    with open(path, "rb") as fp:
        head = fp.read(MTX_HEADER)
    lines = head.split(b"\n")
    banner = lines[0].decode("latin-1").strip().split()
    if len(banner) != 5 or banner[0].lower() != "%%matrixmarket" or \
            banner[1].lower() != "matrix":
        raise bad("the first line must be %%MatrixMarket matrix <format> <field> <symmetry>")
    form, kind, symmetry = (b.lower() for b in banner[2:])
    if form not in _MTX_FORMATS or kind not in _MTX_FIELDS or symmetry not in _MTX_SYMMETRY:
        raise bad(f"unknown format, field or symmetry {' '.join(banner[2:])[:60]!r}")
    offset = len(lines[0]) + 1
    for k, raw in enumerate(lines[1:], start=1):
        if k == len(lines) - 1 and size > len(head):  # a line cut off by the limit
            raise bad(f"no size line in its first {MTX_HEADER} bytes")
        offset += len(raw) + 1
        text = raw.decode("latin-1").strip()
        if not text or text.startswith("%"):
            continue
        numbers = text.split()
        want = 3 if form == "coordinate" else 2
        if len(numbers) != want or not all(re.fullmatch(r"\d{1,12}", n) for n in numbers):
            raise bad(f"the size line must be {want} integers (of at most 12 digits), got "
                      f"{text[:60]!r}")
        rows, cols = int(numbers[0]), int(numbers[1])
        entries = int(numbers[2]) if form == "coordinate" else rows * cols
        return rows, cols, entries, form, kind, symmetry, max(size - offset, 0)
    raise bad("no size line")


def _check_header(field: str, file: str, path: Path, suffix: str, key: str | None) -> None:
    """Read the header of a matrix file (shape, type) and refuse what cannot be loaded."""
    if suffix == ".mtx":
        rows, cols, entries, form, kind, symmetry, left = _mtx_header(field, file, path)
        if kind == "complex" or symmetry == "hermitian":
            raise FieldError((field, "file"), "must be a real matrix, the file holds a "
                             "complex one", file)
        stored = entries * 2 if symmetry != "general" and form == "coordinate" else entries
        per = _SPARSE_ENTRY if form == "coordinate" else _DENSE_ENTRY
        _size_check(field, file, (rows, cols), stored, per, dense=form == "array")
        # the shortest entry lines: "i j v" (coordinate), "i j" (pattern), "v" (array)
        line = 2 if form == "array" else 4 if kind == "pattern" else 6
        _promised(field, file, entries * line - 1, left, f"{entries} entries")
        return
    if suffix == ".npy":
        with open(path, "rb") as fp:
            shape, dtype = _npy_header(fp)
            left = os.fstat(fp.fileno()).st_size - fp.tell()
    else:  # the zip directory and the .npy headers only (substruct.case.npz_files)
        try:
            members = npz_members(path)
        except ValueError as err:
            raise FieldError((field, "file"), f"cannot read matrix ({err})", file) from None
        if key not in members:
            raise FieldError((field, "key"), f"no array {key!r} in {path.name} (it has "
                             f"{', '.join(members) or 'none'})", key)
        shape, dtype = members[key].shape, members[key].dtype
        left = members[key].held
    if any(not isinstance(d, int) or d < 0 for d in shape):
        raise FieldError((field, "file"), "not an .npy array: its shape is not a list of "
                         "sizes", file)
    if dtype.kind not in "biuf":
        what = "complex numbers" if dtype.kind == "c" else f"{dtype} entries"
        raise FieldError((field, "file"), f"must hold a real matrix, holds {what}", file)
    entries = 1  # a shape other than 2-D is reported once read, if it is small
    for d in shape:
        entries *= d
    _size_check(field, file, shape, entries, _DENSE_ENTRY, dense=True)
    _promised(field, file, entries * dtype.itemsize, left,
              f"a {' x '.join(map(str, shape))} array of {dtype}")


def load_matrix(field: str, value: Any, base: Path, parameters: Mapping[str, float]
                ) -> sp.csr_array | np.ndarray:
    """A 2-D float array (inline lists, ``.npy``/``.npz``) or a sparse matrix (``.mtx``).

    Raises:
        FieldError: at ``field`` (inline rows) or ``field.file``/``field.key`` (files).
    """
    if isinstance(value, list):
        rows = _entries(field, value, parameters)
        try:
            arr = np.array(rows, dtype=float)
        except (TypeError, ValueError):
            raise FieldError(field, "must be a list of rows of numbers, all of equal length",
                             value) from None
        if arr.ndim != 2:
            raise FieldError(field, "must be a list of rows (a 2-D matrix)", value)
        return arr
    file = value["file"]
    path = Path(file)
    path = path if path.is_absolute() else base / path
    key = value.get("key")
    suffix = path.suffix.lower()
    if suffix not in (".npz", ".npy", ".mtx"):
        raise FieldError((field, "file"), "matrix files are .npz, .npy or .mtx", file)
    try:
        mode = path.stat().st_mode
    except OSError:
        raise FieldError((field, "file"), f"no such file ({path})", file) from None
    if not stat.S_ISREG(mode):
        what = "a directory" if stat.S_ISDIR(mode) else "a FIFO, a device or a socket"
        raise FieldError((field, "file"), f"{path} is {what}, not a matrix file", file)
    if suffix in (".mtx", ".npy") and key is not None:
        raise FieldError((field, "key"), f"a {suffix} file holds one matrix: no key", key)
    try:
        _check_header(field, file, path, suffix, field if key is None else key)
        if suffix == ".mtx":
            import scipy.io
            mat = scipy.io.mmread(str(path))
            return sp.csr_array(mat, dtype=float) if sp.issparse(mat) else \
                np.asarray(mat, dtype=float)
        if suffix == ".npy":
            arr = np.asarray(np.load(path, allow_pickle=False), dtype=float)
        else:
            key = field if key is None else key
            arr = read_npz(path, [key], {key: np.float64})[key]
    except FieldError:
        raise
    except Exception as err:  # unreadable file: a bad input, reported in one line
        raise FieldError((field, "file"), f"cannot read matrix ({type(err).__name__}: "
                         f"{' '.join(str(err).split())[:200]})", file) from None
    if arr.ndim != 2:
        raise FieldError((field, "file"), f"holds a {arr.ndim}-D array, not a matrix", file)
    return arr


# -------------------------------------------------------------------------- the spec


class MatrixSpec(StrictModel):
    """A substructure given by its matrices (inline or from ``.npz``/``.npy``/``.mtx`` files)."""

    name: Name
    type: Literal["matrices"]
    M: MatrixSource
    K: MatrixSource
    C: MatrixSource = None
    labels: list[Annotated[str, StringConstraints(min_length=1)]] | None = None
    _matrices: dict[str, Any] = PrivateAttr(default_factory=dict)

    def _shown(self, field: str) -> Any:
        """The value of ``field`` as the file has it (the rows, or the file name)."""
        value = getattr(self, field)
        return value if isinstance(value, list) else value.get("file")

    @model_validator(mode="after")
    def _load(self, info: ValidationInfo) -> "MatrixSpec":
        base = Path((info.context or {}).get("base_dir", "."))
        params = dict((info.context or {}).get("parameters", {}))
        mats: dict[str, Any] = {}
        for field in ("M", "K", "C"):
            value = getattr(self, field)
            if value is None and field != "C":
                raise FieldError(field, "required: the matrix as rows, or {file: ...}", None)
            if value is None:
                continue
            mat = load_matrix(field, value, base, params)
            shown = self._shown(field)
            r, c = mat.shape
            if r != c:
                raise FieldError(field, f"must be square, is {r} x {c}", shown)
            if field != "M" and r != mats["M"].shape[0]:
                n = mats["M"].shape[0]
                raise FieldError(field, f"must be {n} x {n} like M, is {r} x {c}", shown)
            if r > MAX_MATRIX_SIZE:
                raise FieldError(field, f"{r} x {r} is more than the {MAX_MATRIX_SIZE} "
                                 f"coordinates accepted", shown)
            if r == 0:
                raise FieldError(field, "must have at least one row", shown)
            problem = array_problem(mat.data if sp.issparse(mat) else mat)
            if problem is not None:
                raise FieldError(field, problem, shown)
            if field in ("M", "K"):
                scale = max(float(abs(mat).max()), 1e-300)
                asym = float(abs(mat - mat.T).max())
                if asym > 1e-10 * scale:
                    raise FieldError(field, f"must be symmetric: max |{field} - {field}^T| = "
                                     f"{asym:.3g}", shown)
            mats[field] = mat
        self._check_semidefinite("M", mats["M"], 1e-12)
        self._check_semidefinite("K", mats["K"], 1e-12)
        n = mats["M"].shape[0]
        if self.labels is not None:
            if len(self.labels) != n:
                raise FieldError("labels", f"{len(self.labels)} labels for {n} coordinates",
                                 self.labels)
            counts = Counter(self.labels)
            dupes = sorted(lab for lab, c in counts.items() if c > 1)
            if dupes:
                raise FieldError("labels", f"duplicate label {dupes[0]!r}", self.labels)
        self._matrices = mats
        return self

    def _check_semidefinite(self, field: str, X: Any, rtol: float) -> None:
        """``M`` or ``K`` positive semidefinite: its diagonal always, its eigenvalues up to
        :data:`~substruct.case.fields.DENSE_CHECK` coordinates (smallest below ``-rtol``
        times the largest in magnitude refused).

        An indefinite ``K`` is a statically unstable structure: ``lambda^2 M + K`` has a real
        root pair ``+-lambda`` (divergence), which eqs (30)-(34) report as two "modes" of
        damping ratio ``+-1``.  A rigid-body motion written with a few digits
        (``[[0.33333333, -0.33333334], ...]``) is such a pair near zero, and it takes the
        place of an elastic mode in the ``count`` lowest: it is refused too, with a hint.
        """
        diag = X.diagonal()
        if np.any(diag < 0):
            raise FieldError(field, f"must be positive semidefinite: diagonal entry "
                             f"{float(diag.min()):g}", self._shown(field))
        if X.shape[0] <= DENSE_CHECK:
            dense = X.toarray() if sp.issparse(X) else X
            eig = np.linalg.eigvalsh((dense + dense.T) / 2)
            top = max(abs(eig).max(), 1e-300) if eig.size else 1.0
            if eig.size and eig[0] < -rtol * top:
                hint = ""
                if field == "K" and eig[0] > -1e-6 * top:
                    hint = (f" ({-eig[0] / top:.1e} of the largest: a rigid-body motion "
                            f"needs K u = 0 to rounding; write K with all its digits)")
                raise FieldError(field, f"must be positive semidefinite: smallest eigenvalue "
                                 f"{eig[0]:.6g}{hint}", self._shown(field))

    def matrix(self, name: str) -> Any:
        """The loaded ``M``, ``K`` or ``C`` (``None`` for an absent ``C``)."""
        return self._matrices.get(name)

    def dof_labels(self) -> list[str]:
        """Labels of the coordinates (``q1 .. qn`` unless given)."""
        n = self._matrices["M"].shape[0]
        return list(self.labels) if self.labels else [f"q{i}" for i in range(1, n + 1)]

    def n_dof(self) -> int:
        """Number of coordinates."""
        return self._matrices["M"].shape[0]
