r"""Nastran ``DMIG`` entries (direct matrix input at grid points) read from bulk data.

A matrix is one header entry and one entry per column holding non-zeros::

    DMIG  NAME  0   IFO  TIN  TOUT  POLAR        NCOL
    DMIG  NAME  GJ  CJ         G1   C1     A1    B1
          G2    C2  A2   B2    G3   C3     A3    B3  ...

Read: real matrices (``TIN`` 1 or 2; ``TOUT`` blank, 0, 1 or 2), ``IFO`` 6 (symmetric: one
triangle is given, each off-diagonal term once, and the other is filled in) and 1 (square:
every term as given).  Rows and columns are ``(grid, component)`` pairs: components 1-6 of a
grid, 0 of a scalar point.  Complex (``TIN`` 3, 4), rectangular (``IFO`` 2, 9), diagonal and
polar forms are refused, as is any card but ``DMIG`` (and ``PARAM`` is not read either: the
file holds the matrices only).  ``NCOL`` is used by Nastran for ``IFO`` 9 only; on the forms
read it is not used (as in Nastran, whose punch files write it there too): it must be blank or
an integer of at least 0, and is otherwise ignored.  A term given twice, a column given on two entries, a symmetric
matrix given with both triangles or a missing header is an error naming the line.

:func:`dmig_matrices` gathers the named matrices on one set of coordinates, the union of
their rows and columns in ascending ``(grid, component)`` order (Nastran's external sort),
which becomes the superelement's DOF map: scalar points are its modal coordinates.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

import numpy as np

from substruct.case.bdf_fields import BdfError, RawCard, read_bdf_text, split_bdf
from substruct.case.fields import MAX_MATRIX_SIZE, MEMORY_LIMIT, gigabytes
from substruct.case.numbers import MAX_MAGNITUDE, RANGE

__all__ = ["DmigMatrix", "read_dmig", "dmig_matrices", "DMIG_FORMS"]

#: The ``IFO`` forms read: 6 symmetric, 1 square.
DMIG_FORMS = (6, 1)


@dataclass
class DmigMatrix:
    """One DMIG matrix as given: its form and its terms ``(row, column) -> value`` with rows
    and columns ``(grid, component)``."""

    name: str
    form: int
    precision: int
    line: int
    terms: dict[tuple[tuple[int, int], tuple[int, int]], float] = field(default_factory=dict)
    columns: dict[tuple[int, int], int] = field(default_factory=dict)

    def dofs(self) -> set[tuple[int, int]]:
        """Every ``(grid, component)`` the matrix names, as a row or a column."""
        out = set(self.columns)
        for r, c in self.terms:
            out.add(r)
            out.add(c)
        return out


def _dof(card: RawCard, i: int, what: str) -> tuple[int, int]:
    g = card.integer(i, f"{what} grid")
    c = card.integer(i + 1, f"{what} component")
    if not 1 <= g <= 999_999_999:
        raise card.error("a grid or scalar point id is 1 to 999999999", g, f"{what} grid")
    if not 0 <= c <= 6:
        raise card.error("a component is 1-6 (0 for a scalar point)", c, f"{what} component")
    return g, c


def _header(card: RawCard) -> DmigMatrix:
    ifo = card.integer(2, "IFO")
    tin = card.integer(3, "TIN")
    if ifo not in DMIG_FORMS:
        raise card.error("IFO 6 (symmetric) and 1 (square) are read; rectangular (2, 9) and "
                         "diagonal forms are not", ifo, "IFO")
    if tin not in (1, 2):
        raise card.error("TIN 1 and 2 (real) are read; a superelement's matrices are real",
                         tin, "TIN")
    tout = card.integer(4, "TOUT", 0)
    if tout not in (0, 1, 2):
        raise card.error("TOUT is blank, 0, 1 or 2 (real)", tout, "TOUT")
    if card.text(5) not in ("", "0"):
        raise card.error("POLAR is blank or 0 (real matrices)", card.text(5), "POLAR")
    if card.text(6):
        raise card.error("field 8 of a DMIG header is blank", card.text(6), "field 8")
    # NCOL (field 9) is used by Nastran for IFO 9 only; its punch files write it for the
    # square and symmetric forms too, where it is not used: an integer, checked, not used.
    ncol = card.integer(7, "NCOL", 0)
    if ncol < 0:
        raise card.error("NCOL (not used for IFO 1 and 6) is blank or a count of columns, "
                         "not negative", ncol, "NCOL")
    card.blank_after(8, "a DMIG header is one line")
    return DmigMatrix(card.text(0), ifo, tin, card.line)


def read_dmig(path: str | Path, source: str, names: Sequence[str] | None = None
              ) -> dict[str, DmigMatrix]:
    """The DMIG matrices of a bulk data file (all, or ``names``, matched upper case).

    Raises:
        BdfError: one line naming the file, the line, the card and the field.
    """
    split = split_bdf(read_bdf_text(Path(path), source), source)
    want = None if names is None else {n.upper() for n in names}
    mats: dict[str, DmigMatrix] = {}
    pending: list[RawCard] = []
    for card in split.cards:
        if card.name != "DMIG":
            raise card.error(f"card {card.name} is not read from a file of DMIG matrices "
                             "(it holds DMIG entries only)")
        name = card.text(0)
        if not name:
            raise card.error("a DMIG entry needs a matrix name", name="NAME")
        if card.text(1) == "0":
            if name in mats:
                raise card.error(f"a second header of DMIG {name} (the first on line "
                                 f"{mats[name].line})")
            mats[name] = _header(card)
        else:
            pending.append(card)
    for card in pending:
        name = card.text(0)
        m = mats.get(name)
        if m is None:
            raise card.error(f"a column of DMIG {name} with no header entry (NAME 0 IFO TIN)")
        if want is not None and name not in want:
            continue
        col = _dof(card, 1, "GJ")
        if card.text(3):
            raise card.error("field 5 of a DMIG column entry is blank", card.text(3))
        if col in m.columns:
            raise card.error(f"column {col[0]}:{col[1]} of DMIG {name} is given twice (also "
                             f"on line {m.columns[col]})")
        m.columns[col] = card.line
        if len(card.fields) <= 4:
            raise card.error("a DMIG column entry holds at least one term (G1 C1 A1)")
        for i in range(4, len(card.fields), 4):
            if not any(card.text(i + k) for k in range(4)):
                continue
            row = _dof(card, i, f"G{(i - 4) // 4 + 1}")
            # an entry of a matrix: finite and at most 1e30 in size, but a round-off entry
            # below 1e-30 beside the others is kept (as the matrix files' rule)
            value = card.real(i + 2, f"A{(i - 4) // 4 + 1}", coefficient=True)
            if abs(value) > MAX_MAGNITUDE:
                raise card.error(f"out of range: too large ({RANGE})", card.text(i + 2),
                                 f"A{(i - 4) // 4 + 1}")
            if card.text(i + 3):
                raise card.error("B (the imaginary part) is blank for a real matrix",
                                 card.text(i + 3), f"B{(i - 4) // 4 + 1}")
            key = (row, col)
            if key in m.terms:
                raise card.error(f"term ({row[0]}:{row[1]}, {col[0]}:{col[1]}) of DMIG {name} "
                                 "is given twice")
            if m.form == 6 and row != col and (col, row) in m.terms:
                raise card.error(f"DMIG {name} is symmetric (IFO 6): give one triangle, but "
                                 f"term ({row[0]}:{row[1]}, {col[0]}:{col[1]}) is given in both")
            m.terms[key] = value
    if want is not None:
        missing = [n for n in names or [] if n.upper() not in mats]
        if missing:
            raise BdfError(source, f"no DMIG {missing[0]!r} (it has "
                           f"{', '.join(mats) or 'none'})")
        mats = {k: v for k, v in mats.items() if k in want}
    return mats


def dmig_matrices(path: str | Path, source: str, names: Sequence[str]
                  ) -> tuple[list[tuple[int, int]], dict[str, np.ndarray], int]:
    r"""The DMIG matrices ``names`` on their common coordinates.

    Returns:
        ``(dofs, matrices, nbytes)``: the ``(grid, component)`` of each coordinate, the union
        of the matrices' rows and columns sorted ascending; each matrix dense on them (a
        symmetric one filled in from its triangle, :math:`A = L + L^T - \operatorname{diag}
        L`); 8 if every matrix is symmetric (IFO 6) in double precision (TIN 2), else 4 (a
        square matrix written as text is symmetric to the precision of its fields only).

    Raises:
        BdfError: see :func:`read_dmig`; more coordinates than
            :data:`~substruct.case.fields.MAX_MATRIX_SIZE`.
    """
    mats = read_dmig(path, source, names)
    union: set[tuple[int, int]] = set()
    for m in mats.values():
        union |= m.dofs()
    dofs = sorted(union)
    scalar = {g for g, c in dofs if c == 0}
    both = sorted(g for g, c in dofs if c != 0 and g in scalar)
    if both:   # Nastran's ids of grids and scalar points are one set
        raise BdfError(source, f"id {both[0]} is named as a scalar point (component 0) and as "
                       "a grid (components 1-6) by the DMIG matrices: one id is one or the other")
    n = len(dofs)
    if n > MAX_MATRIX_SIZE:
        raise BdfError(source, f"the DMIG matrices name {n} coordinates, more than the "
                       f"{MAX_MATRIX_SIZE} accepted")
    need = 8.0 * n * n * len(names)
    if need > MEMORY_LIMIT:
        raise BdfError(source, f"{len(names)} dense matrices of {n} coordinates would need "
                       f"about {gigabytes(need)}, more than the {gigabytes(MEMORY_LIMIT)} "
                       "allowed")
    index = {d: k for k, d in enumerate(dofs)}
    out: dict[str, np.ndarray] = {}
    for name in names:
        m = mats[name.upper()]
        A = np.zeros((n, n))
        for (r, c), v in m.terms.items():
            A[index[r], index[c]] = v
            if m.form == 6 and r != c:
                A[index[c], index[r]] = v
        out[name] = A
    exact = all(m.form == 6 and m.precision == 2 for m in mats.values())
    return dofs, out, 8 if exact else 4
