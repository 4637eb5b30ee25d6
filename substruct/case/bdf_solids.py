"""The solid cards of a Nastran file: CHEXA (8 or 20 grids), CPENTA (6 or 15), CTETRA (4 or
10), and their PSOLID property, read from the fields of a
:class:`~substruct.case.bdf_fields.RawCard` (field indices as in
:mod:`substruct.case.bdf_cards`).  Every field is read or refused.

The elements are the linear isoparametric solids (trilinear hexahedron, linear wedge, linear
tetrahedron), the 10-grid quadratic tetrahedron (:mod:`substruct.models.nastran_tet10`,
whose stiffness on straight edges no integration choice changes; curved, it takes the 4-point
rule whatever IN says) and the 20-grid CHEXA and 15-grid CPENTA
(:mod:`substruct.models.nastran_quad_solids`, full 3 x 3 x 3 integration, PSOLID IN 3 and
ISOP FULL).  PSOLID's integration fields are read as MSC Nastran's QRG defines
them for elements without mid-side grids: ``IN`` blank/``0``/``BUBBLE`` with ``ISOP``
blank/``REDUCED`` (the default) gives the 8-grid CHEXA and the 6-grid CPENTA their bubble functions
(incompatible modes, :mod:`substruct.models.nastran_bubble`); ``IN`` ``2``/``TWO`` with ``ISOP``
``1``/``FULL`` is the standard isoparametric integration (2 x 2 x 2 on the hexahedron, 3 x 2
on the wedge).  The linear tetrahedron is exact with either.  Other combinations (reduced
shear only; ``IN = 3`` without mid-side grids; the quadratic CHEXA and CPENTA without
``IN = 3, ISOP = FULL``), an element with only some of its mid-side grids, and fluid elements
(``FCTN`` other than ``SMECH``) are refused.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from substruct.case.bdf_fields import BdfError, RawCard, nastran_int

__all__ = ["SolidCell", "Psolid", "read_solid", "read_psolid", "SOLID_CORNERS",
           "quadratic_integration_error", "check_solid_shapes"]

#: Corner grids of each solid card, the most grids it can have, and meshio's name of the cell
#: (whose corner order is Nastran's: G1-G4 one face of the hexahedron, G5-G8 the other; G1-G3
#: one triangle of the wedge, G4-G6 the other).
SOLID_CORNERS: dict[str, tuple[int, int, str]] = {
    "CHEXA": (8, 20, "hexahedron"), "CPENTA": (6, 15, "wedge"), "CTETRA": (4, 10, "tetra")}


_WORDS = {6: "six", 9: "nine", 12: "twelve"}


@dataclass(frozen=True)
class SolidCell:
    """CHEXA / CPENTA / CTETRA: its corner grids in Nastran's order; ``bubble``: a CHEXA or
    CPENTA whose PSOLID asks for bubble functions (set when the property is cross-referenced)."""

    kind: str
    id: int
    pid: int
    nodes: tuple[int, ...]
    line: int
    bubble: bool = False


@dataclass(frozen=True)
class Psolid:
    """PSOLID: material ``mid``, the material coordinate system ``cordm`` (no effect with
    an isotropic MAT1; checked to exist) and ``bubble``: the hexahedra's and wedges' bubble
    functions (IN blank/BUBBLE, ISOP blank/REDUCED) rather than 2 x 2 x 2 Gauss points (IN 2);
    ``three``: IN 3/THREE (3 x 3 x 3); ``full``: ISOP 1/FULL (every strain term at every
    point).  Which combinations an element takes is checked when the elements are
    cross-referenced (:func:`quadratic_integration_error`)."""

    id: int
    mid: int
    cordm: int
    line: int
    bubble: bool = True
    three: bool = False
    full: bool = False


def read_solid(c: RawCard) -> SolidCell:
    """CHEXA EID PID G1 ... G8 [G9 ... G20], CPENTA EID PID G1 ... G6 [G7 ... G15], CTETRA EID
    PID G1 ... G4 [G5 ... G10]: the corners and either all mid-side grids (the 20-grid CHEXA,
    15-grid CPENTA, 10-grid CTETRA) or none (a mid-side grid 0 is blank, as in Nastran).  An
    element with only some of them (Nastran allows it) is refused, naming the first blank."""
    n, most, _ = SOLID_CORNERS[c.name]
    given = [k for k in range(2 + n, 2 + most) if c.text(k) not in ("", "0")]
    if len(given) == most - n:
        n = most
    elif given:
        k = min(set(range(2 + n, 2 + most)) - set(given))
        raise c.error(f"{c.name} needs all {_WORDS[most - n]} mid-side grids G{n + 1}-G{most} "
                      f"or none (the {most}- or the {n}-grid element)", c.text(k) or "blank",
                      f"G{k - 1}")
    c.blank_after(2 + most, f"{c.name} has at most {most} grids")
    eid = c.integer(0, "EID")
    nodes = tuple(c.integer(2 + k, f"G{k + 1}") for k in range(n))
    if len(set(nodes)) != n:
        raise c.error("the grids must be different", list(nodes), "G1")
    return SolidCell(c.name, eid, c.integer(1, "PID"), nodes, c.line)


def _choice(c: RawCard, i: int, name: str, allowed: tuple[str, ...], why: str) -> str:
    value = c.text(i).upper()
    if value not in allowed:
        raise c.error(why, c.text(i), name)
    return value


def read_psolid(c: RawCard) -> Psolid:
    """PSOLID PID MID CORDM IN STRESS ISOP FCTN.

    * ``CORDM`` (blank: 0): the material axes, no effect with an isotropic MAT1;
    * ``IN`` and ``ISOP`` together (QRG PSOLID, remarks 6 and 10): ``IN`` blank, ``0`` or
      ``BUBBLE`` with ``ISOP`` blank or ``REDUCED``: the default, bubble functions in the
      8-grid CHEXA and the 6-grid CPENTA; ``IN`` ``2``/``TWO`` with ``ISOP`` ``1``/``FULL``:
      standard integration; ``IN`` ``3``/``THREE`` with ``ISOP`` ``1``/``FULL``: the standard
      integration of the elements with mid-side grids (the only one the 20-grid CHEXA and
      15-grid CPENTA take, :func:`quadratic_integration_error`).  ``IN = 2`` with reduced shear
      (``ISOP`` blank or ``REDUCED``) and the combinations outside Nastran's table are refused;
    * ``STRESS`` (where stresses are output): read and not used;
    * ``FCTN``: blank or ``SMECH``; fluids (``PFLUID``, ``FFLUID``) are refused.
    """
    c.blank_after(7, "PSOLID has one line")
    pid, mid = c.integer(0, "PID"), c.integer(1, "MID")
    if mid <= 0:
        raise c.error("must be a positive material id", mid, "MID")
    cordm = c.integer(2, "CORDM", 0)
    network = _choice(c, 3, "IN", ("", "0", "BUBBLE", "2", "TWO", "3", "THREE"), "only bubble "
                      "functions (IN blank, 0 or BUBBLE), 2 x 2 x 2 (2 or TWO) or 3 x 3 x 3 Gauss "
                      "points (3 or THREE) are supported")
    _choice(c, 4, "STRESS", ("", "0", "1", "GRID", "GAUSS"), "must be blank, 0, 1, GRID or "
            "GAUSS")
    scheme = _choice(c, 5, "ISOP", ("", "REDUCED", "1", "FULL"), "must be blank, REDUCED, 1 or "
                     "FULL")
    bubble = network in ("", "0", "BUBBLE")
    three = network in ("3", "THREE")
    if bubble and scheme in ("1", "FULL"):
        raise c.error("bubble functions (IN blank, 0 or BUBBLE) go with reduced shear "
                      "integration (ISOP blank or REDUCED) only", c.text(5), "ISOP")
    if network in ("2", "TWO") and scheme in ("", "REDUCED"):
        raise c.error("2 x 2 x 2 reduced shear integration without bubble functions is not "
                      "supported (IN 2 needs ISOP 1 or FULL)", c.text(5) or "blank", "ISOP")
    _choice(c, 6, "FCTN", ("", "SMECH"), "only structural solids (FCTN blank or SMECH) are "
            "supported")
    if c.text(2) and nastran_int(c.text(2)) is None:
        raise c.error("must be an integer", c.text(2), "CORDM")
    return Psolid(pid, mid, cordm, c.line, bubble, three, scheme in ("1", "FULL"))


def quadratic_integration_error(cell: SolidCell, p: Psolid) -> tuple[str, str, str] | None:
    """``(problem, value, PSOLID field)`` when the PSOLID's integration does not fit the element,
    else None.  The 20-grid CHEXA and 15-grid CPENTA are built with full integration only
    (``IN`` 3/THREE with ``ISOP`` 1/FULL): Nastran's default for them (``IN`` and ``ISOP``
    blank) is reduced shear integration, whose points and terms the QRG does not give, and
    ``IN = 2`` is reduced integration.  The elements without mid-side grids do not take
    ``IN = 3``.  The 10-grid CTETRA takes any (module docstring)."""
    n = len(cell.nodes)
    if cell.kind == "CTETRA":
        return None
    if n == SOLID_CORNERS[cell.kind][0]:
        if p.three:
            return (f"3 x 3 x 3 Gauss points (IN 3) are for the {cell.kind} with mid-side grids; "
                    "the one without takes bubble functions (IN blank, 0 or BUBBLE) or IN 2",
                    "THREE", "IN")
        return None
    if not (p.three and p.full):
        return (f"the {n}-grid {cell.kind} is built with full 3 x 3 x 3 integration only "
                "(PSOLID IN 3 or THREE with ISOP 1 or FULL); Nastran's default reduced shear "
                "integration and IN 2 are not reproduced",
                f"IN {'THREE' if p.three else ('2' if not p.bubble else 'blank')}, ISOP "
                f"{'FULL' if p.full else 'blank/REDUCED'}", "IN" if not p.three else "ISOP")
    return None


#: The three edges at each corner of a solid, ``[corner, a, b, c]`` (Nastran's grid order),
#: ordered so that a positively numbered element has a positive Jacobian at every corner.
_CORNER_EDGES = {
    8: np.array([[0, 1, 3, 4], [1, 2, 0, 5], [2, 3, 1, 6], [3, 0, 2, 7],
                 [4, 7, 5, 0], [5, 4, 6, 1], [6, 5, 7, 2], [7, 6, 4, 3]]),
    6: np.array([[0, 1, 2, 3], [1, 2, 0, 4], [2, 0, 1, 5], [3, 5, 4, 0], [4, 3, 5, 1],
                 [5, 4, 3, 2]]),
    4: np.array([[0, 1, 2, 3]]),
}
#: A corner Jacobian below this fraction of the element's span cubed is zero.
COLLAPSED_JACOBIAN = 1e-12


def check_solid_shapes(cells: list[SolidCell], grids: dict[int, np.ndarray],
                       source: str) -> None:
    r"""Refuse a collapsed or folded solid before anything is built: at each corner ``c``
    of its corner grids the Jacobian determinant
    :math:`J_c = \det[x_a - x_c,\ x_b - x_c,\ x_d - x_c]` over the corner's three edges, zero
    (:math:`|J_c| \le 10^{-12} h^3`, ``h`` the element's largest extent along an axis: two
    grids at one point, a flat corner) or of both signs over the corners (a folded element).
    All corners negative is a mirrored numbering, which integrates correctly.

    Args:
        cells: the solids.
        grids: grid id -> position in basic coordinates.
        source: the file, for messages.

    Raises:
        BdfError: the first collapsed or folded element, naming its card and grids.
    """
    for nv, corners in _CORNER_EDGES.items():
        group = [cell for cell in cells if SOLID_CORNERS[cell.kind][0] == nv]
        if not group:
            continue
        X = np.array([[grids[g] for g in cell.nodes[:nv]] for cell in group])
        span = np.ptp(X, axis=1).max(axis=1)
        edges = X[:, corners[:, 1:], :] - X[:, corners[:, :1], :]  # (cells, corners, 3, 3)
        with np.errstate(all="ignore"):
            jac = np.linalg.det(edges)
        small = ~(np.abs(jac) > COLLAPSED_JACOBIAN * span[:, None] ** 3)
        mixed = (jac.max(axis=1) > 0) & (jac.min(axis=1) < 0)
        for k in np.flatnonzero(small.any(axis=1) | mixed):
            cell = group[int(k)]
            what = "collapsed (a zero Jacobian at a corner: grids at one point, or a flat " \
                "corner)" if small[k].any() else "folded (its corners have Jacobians of " \
                "both signs)"
            raise BdfError(source, f"the element is {what}", list(cell.nodes),
                           line=cell.line, card=cell.kind, ident=cell.id)
