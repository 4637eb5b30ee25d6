"""The solid cards of a Nastran file: CHEXA (8 grids), CPENTA (6) and CTETRA (4) and their
PSOLID property, read from the fields of a :class:`~substruct.case.bdf_fields.RawCard` (field
indices as in :mod:`substruct.case.bdf_cards`).  Every field is read or refused.

The elements are the linear isoparametric solids (trilinear hexahedron, linear wedge, linear
tetrahedron) and the 10-grid quadratic tetrahedron (:mod:`substruct.models.nastran_tet10`,
whose stiffness on straight edges no integration choice changes; curved, it takes the 4-point
rule whatever IN says).  PSOLID's integration fields are read as MSC Nastran's QRG defines
them for elements without mid-side grids: ``IN`` blank/``0``/``BUBBLE`` with ``ISOP``
blank/``REDUCED`` (the default) gives the 8-grid CHEXA and the 6-grid CPENTA their bubble functions
(incompatible modes, :mod:`substruct.models.nastran_bubble`); ``IN`` ``2``/``TWO`` with ``ISOP``
``1``/``FULL`` is the standard isoparametric integration (2 x 2 x 2 on the hexahedron, 3 x 2
on the wedge).  The linear tetrahedron is exact with either.  Other combinations (reduced
shear only, ``IN = 3``), mid-side grids of CHEXA (20) and CPENTA (15), a CTETRA with only
some of its six, and fluid elements (``FCTN`` other than ``SMECH``) are refused.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from substruct.case.bdf_fields import BdfError, RawCard, nastran_int

__all__ = ["SolidCell", "Psolid", "read_solid", "read_psolid", "SOLID_CORNERS",
           "check_solid_shapes"]

#: Corner grids of each solid card, the most grids it can have, and meshio's name of the cell
#: (whose corner order is Nastran's: G1-G4 one face of the hexahedron, G5-G8 the other; G1-G3
#: one triangle of the wedge, G4-G6 the other).
SOLID_CORNERS: dict[str, tuple[int, int, str]] = {
    "CHEXA": (8, 20, "hexahedron"), "CPENTA": (6, 15, "wedge"), "CTETRA": (4, 10, "tetra")}


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
    functions (IN blank/BUBBLE, ISOP blank/REDUCED) rather than full integration (IN 2, ISOP
    FULL)."""

    id: int
    mid: int
    cordm: int
    line: int
    bubble: bool = True


def read_solid(c: RawCard) -> SolidCell:
    """CHEXA EID PID G1 ... G8 (G9 - G20 blank), CPENTA EID PID G1 ... G6 (G7 - G15 blank),
    CTETRA EID PID G1 ... G4 and either all six mid-side grids G5 - G10 (the 10-grid
    quadratic tetrahedron) or none; a CTETRA with some of them (Nastran allows it) is
    refused."""
    n, most, _ = SOLID_CORNERS[c.name]
    given = [k for k in range(2 + n, 2 + most) if c.text(k)]
    if c.name == "CTETRA" and len(given) == most - n:
        n = most
    elif given and c.name == "CTETRA":
        k = min(set(range(2 + n, 2 + most)) - set(given))
        raise c.error("CTETRA needs all six mid-side grids G5-G10 or none (the 10- or the "
                      "4-grid element)", "blank", f"G{k - 1}")
    elif given:
        raise c.error(f"{c.name} with mid-side grids is not supported (the {n}-grid element "
                      "only)", c.text(given[0]), f"G{given[0] - 1}")
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
      standard integration.  ``IN = 3``/``THREE``, ``IN = 2`` with reduced shear (``ISOP`` blank or
      ``REDUCED``) and the combinations outside Nastran's table are refused;
    * ``STRESS`` (where stresses are output): read and not used;
    * ``FCTN``: blank or ``SMECH``; fluids (``PFLUID``, ``FFLUID``) are refused.
    """
    c.blank_after(7, "PSOLID has one line")
    pid, mid = c.integer(0, "PID"), c.integer(1, "MID")
    if mid <= 0:
        raise c.error("must be a positive material id", mid, "MID")
    cordm = c.integer(2, "CORDM", 0)
    network = _choice(c, 3, "IN", ("", "0", "BUBBLE", "2", "TWO"), "only bubble functions "
                      "(IN blank, 0 or BUBBLE) or 2 x 2 x 2 Gauss points (2 or TWO) are supported")
    _choice(c, 4, "STRESS", ("", "0", "1", "GRID", "GAUSS"), "must be blank, 0, 1, GRID or "
            "GAUSS")
    scheme = _choice(c, 5, "ISOP", ("", "REDUCED", "1", "FULL"), "must be blank, REDUCED, 1 or "
                     "FULL")
    bubble = network in ("", "0", "BUBBLE")
    if bubble and scheme in ("1", "FULL"):
        raise c.error("bubble functions (IN blank, 0 or BUBBLE) go with reduced shear "
                      "integration (ISOP blank or REDUCED) only", c.text(5), "ISOP")
    if not bubble and scheme in ("", "REDUCED"):
        raise c.error("2 x 2 x 2 reduced shear integration without bubble functions is not "
                      "supported (IN 2 needs ISOP 1 or FULL)", c.text(5) or "blank", "ISOP")
    _choice(c, 6, "FCTN", ("", "SMECH"), "only structural solids (FCTN blank or SMECH) are "
            "supported")
    if c.text(2) and nastran_int(c.text(2)) is None:
        raise c.error("must be an integer", c.text(2), "CORDM")
    return Psolid(pid, mid, cordm, c.line, bubble)


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
DEGENERATE = 1e-12


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
        small = ~(np.abs(jac) > DEGENERATE * span[:, None] ** 3)
        mixed = (jac.max(axis=1) > 0) & (jac.min(axis=1) < 0)
        for k in np.flatnonzero(small.any(axis=1) | mixed):
            cell = group[int(k)]
            what = "collapsed (a zero Jacobian at a corner: grids at one point, or a flat " \
                "corner)" if small[k].any() else "folded (its corners have Jacobians of " \
                "both signs)"
            raise BdfError(source, f"the element is {what}", list(cell.nodes),
                           line=cell.line, card=cell.kind, ident=cell.id)
