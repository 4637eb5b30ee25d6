r"""Abaqus matrix files: the text ``.mtx`` files written by ``*MATRIX GENERATE`` with
``*MATRIX OUTPUT`` (one file per matrix: ``<job>_STIF<step>.mtx``, ``<job>_MASS<step>.mtx``,
``<job>_DMPV<step>.mtx``, ...), in either of two layouts:

* the *matrix input* layout (``FORMAT=MATRIX INPUT``, the default, and the data lines of
  ``*MATRIX INPUT``): one term a line, comma-separated, ``row node, row dof, column node,
  column dof, value`` (``101,2, 101,1,  3.571428571428572e+01``), one triangle of a symmetric
  matrix.  The nodes and degrees of freedom are the DOF map: the union of the ``(node, dof)``
  pairs of the matrices read, in ascending order;
* the *coordinate* layout (``FORMAT=COORDINATE``): ``row column value`` with 1-based equation
  numbers, separated by blanks as Abaqus writes it (``1 2  3.749985979900784e+08``, both
  triangles, each off-diagonal term followed by its mirror) or by commas; its DOF map is given
  beside it (``dofs:`` of the superelement), since the file does not name the equations.

``FORMAT=LABELS`` files are not read: no description or sample of their lines was found to
check a reader against, so they are refused as lines of neither layout.

A symmetric matrix is given by one triangle (every off-diagonal term on one side of the
diagonal), the other filled in, :math:`A = L + L^T - \operatorname{diag} L`; a matrix with terms
on both sides is square: every off-diagonal term must come with its mirror term (the
superelement then checks the symmetry to the precision of the data).

Refused, in one line naming the file, the line and the problem: a line of neither layout (or
two layouts in one file), a degree of freedom outside 1-6 (Abaqus's 7 warping, 8 pore
pressure, 11 temperature...), a node that is not 1 to 999999999 (Abaqus numbers its internal
nodes, Lagrange multipliers and element variables, negatively), a value that is not a finite
number, a value of 1e36 (the diagonal Abaqus writes for a degree of freedom held by a boundary
condition), a term given twice, a keyword line, an equation number beyond the DOF map, a square
matrix missing a mirror term.  ``**`` lines are comments.  Sizes are checked before anything
is allocated: the file's bytes, the coordinates
(:data:`~substruct.case.fields.MAX_MATRIX_SIZE`) and the dense matrices' memory
(:data:`~substruct.case.fields.MEMORY_LIMIT`).
"""

from __future__ import annotations

import re
from array import array
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np

from substruct.case.errors import CaseError
from substruct.case.fields import MAX_MATRIX_SIZE, MEMORY_LIMIT, gigabytes

__all__ = ["MtxTerms", "read_mtx", "abaqus_matrices", "MAX_MTX_FILE", "HELD_MARK"]

#: Largest matrix file read (bytes): about 25 million terms.
MAX_MTX_FILE = 1_000_000_000
#: Abaqus's diagonal for a degree of freedom held by a boundary condition (refused).
HELD_MARK = 1.0e36
_INT = re.compile(r"[+-]?\d{1,12}")
_FLOAT = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eEdD][+-]?\d{1,4})?")


@dataclass
class MtxTerms:
    """The terms of one matrix file as given.

    Attributes:
        layout: ``"nodes"`` (row node, dof, column node, dof, value) or ``"coordinate"`` (row,
            column, value).
        rows, cols: per term, ``node * 8 + dof`` (nodes layout) or the 0-based equation
            number (coordinate layout).
        values: per term.
        lines: per term, its line in the file.
    """

    layout: str
    rows: np.ndarray
    cols: np.ndarray
    values: np.ndarray
    lines: np.ndarray


def _fail(source: str, line: int, problem: str, value: object = None) -> CaseError:
    if value is None:
        return CaseError(source, f"line {line}", problem)
    return CaseError(source, f"line {line}", problem, value)


def _node_dof(source: str, k: int, node: str, dof: str, raw: str) -> int:
    n, d = int(node), int(dof)
    if n < 0:
        raise _fail(source, k, f"node {n} is an internal node of Abaqus (a Lagrange multiplier "
                    "or an element variable); only the displacements and rotations of nodes "
                    "are read", raw)
    if not 1 <= n <= 999_999_999:
        raise _fail(source, k, "a node number is 1 to 999999999", raw)
    if not 1 <= d <= 6:
        raise _fail(source, k, f"degree of freedom {d} is not a displacement or a rotation "
                    "(1-6)", raw)
    return n * 8 + d


def read_mtx(path: Path, source: str) -> MtxTerms:
    """The terms of the Abaqus matrix file ``path`` (module docstring), named ``source`` in
    errors.

    Raises:
        CaseError: ``<source>: line <k>: <problem>, got <line>`` (module docstring); a file
            too large or that cannot be read.
    """
    try:
        size = path.stat().st_size
        if size > MAX_MTX_FILE:
            raise CaseError(source, "", f"{size} bytes, more than the {MAX_MTX_FILE} read")
        handle = path.open("r", encoding="ascii", errors="replace", newline=None)
    except OSError as err:
        raise CaseError(source, "", f"cannot be read ({err.strerror})") from None
    rows, cols, lines = array("q"), array("q"), array("q")
    values = array("d")
    layout = ""
    with handle:
        for k, text in enumerate(handle, start=1):
            raw = text.strip()
            if not raw or raw.startswith("**"):
                continue
            if raw.startswith("*"):
                raise _fail(source, k, "a keyword line; a matrix file holds data lines only",
                            raw[:40])
            if "," in raw:
                parts = [p.strip() for p in raw.rstrip(",").split(",")]
                kind = {5: "nodes", 3: "coordinate"}.get(len(parts))
            else:  # Abaqus writes the coordinate layout separated by blanks
                parts = raw.split()
                kind = "coordinate" if len(parts) == 3 else None
            if kind is None or not all(_INT.fullmatch(p) for p in parts[:-1]) or \
                    not _FLOAT.fullmatch(parts[-1]):
                raise _fail(source, k, "expected 'node, dof, node, dof, value' (comma-separated) "
                            "or 'row column value' (blank- or comma-separated numbers)", raw[:60])
            if layout and kind != layout:
                raise _fail(source, k, f"a {kind} line in a file of {layout} lines", raw[:60])
            layout = kind
            if kind == "nodes":
                r = _node_dof(source, k, parts[0], parts[1], raw[:60])
                c = _node_dof(source, k, parts[2], parts[3], raw[:60])
            else:
                r, c = int(parts[0]) - 1, int(parts[1]) - 1
                if not (0 <= r < MAX_MATRIX_SIZE and 0 <= c < MAX_MATRIX_SIZE):
                    raise _fail(source, k, f"an equation number is 1 to {MAX_MATRIX_SIZE}",
                                raw[:60])
            value = float(re.sub("[dD]", "e", parts[-1]))
            if not np.isfinite(value):
                raise _fail(source, k, "the value is not a finite number", parts[-1])
            if abs(value) >= HELD_MARK:
                raise _fail(source, k, "1e36 is the diagonal Abaqus writes for a degree of "
                            "freedom held by a boundary condition; generate the matrices "
                            "without *BOUNDARY on the part and hold it in the case instead",
                            parts[-1])
            rows.append(r)
            cols.append(c)
            values.append(value)
            lines.append(k)
    if not layout:
        raise CaseError(source, "", "no matrix terms in the file")
    return MtxTerms(layout, np.frombuffer(rows, np.int64), np.frombuffer(cols, np.int64),
                    np.frombuffer(values, np.float64), np.frombuffer(lines, np.int64))


def _dense(t: MtxTerms, index: np.ndarray, n: int, source: str) -> np.ndarray:
    """The dense ``n x n`` matrix of the terms, ``index`` their rows and columns mapped to
    ``0 .. n-1`` (``2 x terms``)."""
    i, j = index
    key = i * n + j
    order = np.argsort(key, kind="stable")
    same = np.nonzero(key[order][1:] == key[order][:-1])[0]
    if same.size:
        first, again = t.lines[order[same[0]]], t.lines[order[same[0] + 1]]
        raise _fail(source, int(again), f"term ({_name(t, index, order[same[0]])}) is given "
                    f"twice (also on line {first})")
    lower, upper = np.any(i > j), np.any(i < j)
    A = np.zeros((n, n))
    A[i, j] = t.values
    if lower and upper:  # square: every off-diagonal term with its mirror
        off = i != j
        mirror = np.isin(j[off] * n + i[off], key, assume_unique=False)
        if not np.all(mirror):
            bad = np.nonzero(off)[0][np.argmin(mirror)]
            raise _fail(source, int(t.lines[bad]), f"term ({_name(t, index, bad)}) has no "
                        "mirror term: give one triangle of a symmetric matrix, or every term "
                        "of the square matrix")
    elif lower or upper:
        A[j, i] = t.values
    return A


def _name(t: MtxTerms, index: np.ndarray, k: int) -> str:
    if t.layout == "coordinate":
        return f"{t.rows[k] + 1}, {t.cols[k] + 1}"
    return f"{t.rows[k] // 8}:{t.rows[k] % 8}, {t.cols[k] // 8}:{t.cols[k] % 8}"


def abaqus_matrices(paths: Mapping[str, Path], sources: Mapping[str, str],
                    dofs: Sequence[tuple[int, int]] | None = None
                    ) -> tuple[list[tuple[int, int]], dict[str, np.ndarray]]:
    """The matrices of the Abaqus files ``paths`` (key -> file) on their common coordinates.

    Args:
        paths: one file per matrix.
        sources: the name of each file in errors.
        dofs: the DOF map ``(grid, component)`` of coordinate-layout files (``None`` for files
            of the nodes layout, which carry their own).

    Returns:
        ``(dofs, matrices)``: the ``(node, dof)`` of each coordinate (the union of the
        matrices' rows and columns, ascending, for the nodes layout; ``dofs`` as given for the
        coordinate layout) and each matrix dense (``float64``).

    Raises:
        CaseError: see :func:`read_mtx`; files of the two layouts together; a nodes-layout
            file with a DOF map, or a coordinate-layout one without; an equation number beyond
            the DOF map; too many coordinates or too much memory.
    """
    terms = {key: read_mtx(path, sources[key]) for key, path in paths.items()}
    layouts = {t.layout for t in terms.values()}
    key0 = next(iter(terms))
    if len(layouts) > 1:
        raise CaseError(sources[key0], "", "the matrix files mix the nodes layout (node, dof, "
                        "node, dof, value) and the coordinate layout (row, column, value)")
    layout = layouts.pop()
    if layout == "nodes":
        if dofs is not None:
            raise CaseError(sources[key0], "", "the file names its nodes and degrees of "
                            "freedom: the DOF map is that of the file (leave dofs out)")
        codes = np.unique(np.concatenate([np.concatenate([t.rows, t.cols])
                                          for t in terms.values()]))
        table = [(int(c) // 8, int(c) % 8) for c in codes]
    else:
        if dofs is None:
            raise CaseError(sources[key0], "", "a file of 'row, column, value' lines (Abaqus's "
                            "coordinate format) needs the DOF map: give dofs")
        table = list(dofs)
        for key, t in terms.items():
            top = int(max(t.rows.max(), t.cols.max()))
            if top >= len(table):
                k = int(np.argmax(np.maximum(t.rows, t.cols)))
                raise _fail(sources[key], int(t.lines[k]), f"equation number {top + 1} is "
                            f"beyond the {len(table)} rows of the DOF map")
    n = len(table)
    if n > MAX_MATRIX_SIZE:
        raise CaseError(sources[key0], "", f"the matrices name {n} coordinates, more than the "
                        f"{MAX_MATRIX_SIZE} accepted")
    need = 8.0 * n * n * len(terms)
    if need > MEMORY_LIMIT:
        raise CaseError(sources[key0], "", f"{len(terms)} dense matrices of {n} coordinates "
                        f"would need about {gigabytes(need)}, more than the "
                        f"{gigabytes(MEMORY_LIMIT)} allowed")
    out = {}
    for key, t in terms.items():
        if layout == "nodes":
            index = np.searchsorted(codes, np.vstack([t.rows, t.cols]))
        else:
            index = np.vstack([t.rows, t.cols])
        out[key] = _dense(t, index, n, sources[key])
    return table, out
