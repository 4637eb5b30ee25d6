r"""Output transformation matrices of a superelement (``recovery:``): the responses inside a
part that its reduced coordinates give,

.. math::  y = \sum_{s \in \text{of}} R_s\, x_s, \qquad R = [R_{s_1} \; R_{s_2} \dots],

with :math:`x_s` the part's coordinates (in the order of its DOF map: boundary and modal) in
displacement, velocity or acceleration.  Nastran's DTM (displacements) is ``of:
displacement``, ATM (accelerations) ``of: acceleration``, an LTM (element forces) by the mode
displacement method ``of: displacement``, or ``of: [acceleration, displacement]`` for the
two-block LTM :math:`[R_a \; R_d]` of the mode acceleration form.

.. code-block:: yaml

    recovery:
      - name: dtm               # outputs are named <part>.<name>@<label>
        matrix: DTM             # in the superelement's file, or in file:
        file: sc_otm.op4        # optional (.op4 or .npz)
        of: displacement        # or velocity, acceleration, or a list of them
        labels: {file: dtm_rows.csv}   # or {key: <member>} or an inline list

Labels name the rows: inline strings, a text file with one per line (a line ``grid,
component`` becomes ``<grid>:<ux..rz>``), or a member of the matrix file (``n x 2`` integers
``grid, component``, or an NPZ array of strings); without ``labels`` the rows are numbered
from 1.  Checked when the case is read: a real, finite matrix of
``len(of) x n`` columns for the ``n`` coordinates, one distinct printable label per row.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import Field, PrivateAttr

from substruct.case.errors import FieldError
from substruct.case.fields import MAX_MATRIX_SIZE, Name, StrictModel
from substruct.case.numbers import array_problem

__all__ = ["RecoverySpec", "RECOVERY_OF", "MAX_LABEL", "MAX_LABEL_FILE", "load_recovery"]

#: The histories a recovery matrix may act on.
RECOVERY_OF = ("displacement", "velocity", "acceleration")
#: Longest row label (characters).
MAX_LABEL = 80
#: Largest label file read (bytes).
MAX_LABEL_FILE = 50_000_000
_COMPONENTS = ("ux", "uy", "uz", "rx", "ry", "rz")
Of = Literal["displacement", "velocity", "acceleration"]


class RecoverySpec(StrictModel):
    """One output transformation matrix of a superelement (module docstring)."""

    name: Name
    matrix: Annotated[str, Field(min_length=1)]
    file: Annotated[str, Field(min_length=1)] | None = None
    of: Of | Annotated[list[Of], Field(min_length=1, max_length=3)] = "displacement"
    labels: Any = None
    _matrix: np.ndarray = PrivateAttr(default_factory=lambda: np.zeros((0, 0)))
    _labels: list[str] = PrivateAttr(default_factory=list)

    def histories(self) -> tuple[str, ...]:
        """The histories the column blocks act on, in order."""
        return (self.of,) if isinstance(self.of, str) else tuple(self.of)

    def matrix_read(self) -> np.ndarray:
        """The matrix ``n_rows x (len(of) n)``."""
        return self._matrix

    def row_labels(self) -> list[str]:
        """One label per row."""
        return list(self._labels)


def _label(value: Any, loc: Any) -> str:
    if isinstance(value, bool) or not isinstance(value, (str, int, np.integer, np.str_)):
        raise FieldError(loc, "a row label is a text or an integer", value)
    text = str(value).strip()
    if not text or len(text) > MAX_LABEL or not text.isprintable():
        raise FieldError(loc, f"a row label is 1 to {MAX_LABEL} printable characters", value)
    return text


def _grid_label(g: float, c: float, loc: Any) -> str:
    if g != round(g) or c != round(c) or not 1 <= g <= 999_999_999 or not 0 <= c <= 6:
        raise FieldError(loc, "rows of a label member are (grid 1-999999999, component 0-6)",
                         f"{g:g}, {c:g}")
    return f"{int(g)}" if c == 0 else f"{int(g)}:{_COMPONENTS[int(c) - 1]}"


def _label_file(base: Path, file: str, loc: Any) -> list[str]:
    path = Path(file)
    path = path if path.is_absolute() else base / path
    try:
        if not path.is_file():
            raise FieldError(loc, f"no such file ({path})", file)
        if path.stat().st_size > MAX_LABEL_FILE:
            raise FieldError(loc, f"more than {MAX_LABEL_FILE} bytes", file)
        text = path.read_bytes().decode("utf-8", errors="replace")
    except OSError as err:
        raise FieldError(loc, f"cannot be read ({err.strerror})", file) from None
    out = []
    for k, line in enumerate(text.splitlines(), start=1):
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        pair = re.fullmatch(r"(\d{1,9})\s*[,;\s]\s*(\d)", line)
        out.append(_grid_label(float(pair[1]), float(pair[2]), (*loc, f"line {k}")) if pair
                   else _label(line, (*loc, f"line {k}")))
    return out


def _labels(spec: RecoverySpec, base: Path, member: Any, loc: tuple) -> list[str] | None:
    value = spec.labels
    if value is None:
        return None
    if isinstance(value, list):
        return [_label(v, (*loc, "labels", k)) for k, v in enumerate(value)]
    if not isinstance(value, dict) or len(value) != 1 or next(iter(value)) not in \
            ("file", "key") or not isinstance(next(iter(value.values())), str):
        raise FieldError((*loc, "labels"), "row labels are a list, {file: labels.txt} or "
                         "{key: <member of the matrix file>}", value)
    if "file" in value:
        return _label_file(base, value["file"], (*loc, "labels", "file"))
    where = (*loc, "labels", "key")
    table = np.asarray(member)
    if table.dtype.kind == "U":
        return [_label(v, where) for v in table.ravel().tolist()]
    if table.dtype.kind not in "iuf":  # a complex part or a truth value is not an id
        raise FieldError(where, "a label member is n x 2 (grid, component) or an array of "
                         f"strings, got {table.dtype} entries", value["key"])
    if table.ndim != 2 or table.shape[1] != 2 or not np.all(np.isfinite(table)):
        raise FieldError(where, "a label member is n x 2 (grid, component) or an array of "
                         f"strings, got {' x '.join(map(str, table.shape))}", value["key"])
    return [_grid_label(float(g), float(c), where) for g, c in table.tolist()]


def load_recovery(specs: list[RecoverySpec], base: Path, default_file: str | None, n: int
                  ) -> None:
    """Read and check each recovery matrix of a superelement of ``n`` coordinates (its
    matrices and labels are kept on the spec).

    Raises:
        FieldError: at ``recovery.<i>.<field>``, one line naming the file, the matrix and the
            problem.
    """
    seen: set[str] = set()
    for i, spec in enumerate(specs):
        loc = ("recovery", i)
        if spec.name in seen:
            raise FieldError((*loc, "name"), "a recovery name is given twice", spec.name)
        seen.add(spec.name)
        of = spec.histories()
        if len(set(of)) != len(of):
            raise FieldError((*loc, "of"), "each history once", list(of))
        key = spec.labels.get("key") if isinstance(spec.labels, dict) else None
        file = spec.file or default_file
        if file is None:
            raise FieldError((*loc, "file"), "the file of the recovery matrix (.op4 or .npz) is "
                             "required beside Abaqus matrix files", spec.matrix)
        from substruct.case.superelement_files import read_matrix_file  # when a file is read

        got = read_matrix_file(file, base, (*loc, "file") if spec.file else "file",
                               {"R": spec.matrix}, [key] if isinstance(key, str) else [],
                               {"R": (*loc, "matrix")}, (".op4", ".npz"))
        R = got.matrices["R"]
        if R.ndim != 2 or R.shape[1] != len(of) * n or not 1 <= R.shape[0] <= MAX_MATRIX_SIZE:
            raise FieldError((*loc, "matrix"), f"matrix {spec.matrix!r} must have {len(of)} x "
                             f"{n} columns (the coordinates of the superelement for each of "
                             f"{', '.join(of)}), is {' x '.join(map(str, R.shape))}",
                             spec.matrix)
        problem = array_problem(R)
        if problem is not None:
            raise FieldError((*loc, "matrix"), f"matrix {spec.matrix!r} {problem}", spec.matrix)
        labels = _labels(spec, base, got.members.get(key) if isinstance(key, str) else None,
                         loc)
        if labels is None:
            labels = [str(k) for k in range(1, R.shape[0] + 1)]
        if len(labels) != R.shape[0]:
            raise FieldError((*loc, "labels"), f"{len(labels)} labels for the {R.shape[0]} "
                             f"rows of matrix {spec.matrix!r}", _shown(spec.labels))
        if len(set(labels)) != len(labels):
            met: set[str] = set()  # the first label met again (in one pass: up to 10^6 rows)
            twice = ""
            for lab in labels:
                if lab in met:
                    twice = lab
                    break
                met.add(lab)
            raise FieldError((*loc, "labels"), f"label {twice!r} names two rows",
                             _shown(spec.labels))
        spec._matrix, spec._labels = R, labels


def _shown(value: Any) -> Any:
    return f"{len(value)} items" if isinstance(value, list) else value
