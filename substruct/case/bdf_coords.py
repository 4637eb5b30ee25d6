r"""Nastran coordinate systems: the cards CORD2R, CORD2C, CORD2S (three points ``A``, ``B``,
``C`` in a reference system ``RID``) and CORD1R, CORD1C, CORD1S (three grids), resolved into
:class:`CoordSystem` in basic, with the grids' positions (GRID ``CP``) and the displacement
frames of GRID ``CD``.

**Axes** (all six cards, Nastran Quick Reference Guide): ``A`` is the origin, ``B`` lies on
the local :math:`z` axis, ``C`` in the local :math:`x`-:math:`z` plane,

.. math::  e_z = \frac{B - A}{|B - A|}, \qquad
           e_y = \frac{e_z \times (C - A)}{|e_z \times (C - A)|}, \qquad e_x = e_y \times e_z

with ``A, B, C`` in basic (a CORD2's points are coordinates of ``RID``, itself possibly
cylindrical or spherical; a CORD1's are its grids' positions).  A point's basic position is
:math:`x = A + [e_x\, e_y\, e_z]\, q` with :math:`q` its local rectangular coordinates:

* rectangular ``(X, Y, Z)``: :math:`q = (X, Y, Z)`;
* cylindrical ``(R, \theta, Z)``, :math:`\theta` in degrees from :math:`x` about :math:`z`:
  :math:`q = (R\cos\theta, R\sin\theta, Z)`;
* spherical ``(R, \theta, \phi)``, :math:`\theta` in degrees from :math:`z`, :math:`\phi`
  from :math:`x` about :math:`z`:
  :math:`q = (R\sin\theta\cos\phi, R\sin\theta\sin\phi, R\cos\theta)`.

**Displacement frames** (GRID ``CD``, :meth:`CoordSystem.frame`): a grid's six coordinates are
its translations and rotations along three unit vectors of the system at the grid's place:
:math:`e_x, e_y, e_z` of a rectangular system; :math:`e_R, e_\theta, e_z` (radial,
tangential, axial) of a cylindrical one; :math:`e_R, e_\theta, e_\phi` of a spherical one.
With ``F`` the 3 x 3 matrix of those vectors (columns, basic),
:math:`u_{basic} = F\, u_{CD}` for the translations and the rotations alike.  The curvilinear
frames are undefined on the axis (cylindrical :math:`R = 0`; spherical
:math:`\sin\theta = 0`): such a grid is refused.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from substruct.case.bdf_fields import BdfError, RawCard

__all__ = ["CoordCard", "CoordSystem", "BASIC", "read_cord2", "read_cord1", "place_grids"]

#: The cards read here.
COORD_CARDS = ("CORD2R", "CORD2C", "CORD2S", "CORD1R", "CORD1C", "CORD1S")

#: A grid whose distance from a curvilinear system's axis is below this fraction of its
#: distance from the origin has no displacement frame.
AXIS_TOL = 1e-12


@dataclass(frozen=True)
class CoordCard:
    """A coordinate system as read: ``kind`` ``"R"``, ``"C"`` or ``"S"``; a CORD2's points
    ``a``, ``b``, ``c`` in system ``rid``, or a CORD1's three ``grids``."""

    id: int
    kind: str
    rid: int
    a: np.ndarray | None
    b: np.ndarray | None
    c: np.ndarray | None
    grids: tuple[int, int, int] | None
    line: int

    @property
    def name(self) -> str:
        """The card's name (``CORD2C``, ...)."""
        return f"CORD{1 if self.grids is not None else 2}{self.kind}"


@dataclass(frozen=True)
class CoordSystem:
    """A resolved system: ``kind``, ``origin`` (basic) and ``axes`` (rows
    :math:`e_x, e_y, e_z` in basic)."""

    kind: str
    origin: np.ndarray
    axes: np.ndarray

    def local(self, x: np.ndarray) -> np.ndarray:
        """The local rectangular coordinates ``q`` of the system's coordinates ``x`` (module
        docstring)."""
        x = np.asarray(x, dtype=float)
        if self.kind == "C":
            t = math.radians(x[1])
            return np.array([x[0] * math.cos(t), x[0] * math.sin(t), x[2]])
        if self.kind == "S":
            t, p = math.radians(x[1]), math.radians(x[2])
            return x[0] * np.array([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p),
                                    math.cos(t)])
        return x

    def to_basic(self, x: np.ndarray) -> np.ndarray:
        """The basic position of the point of coordinates ``x`` in this system."""
        return self.origin + self.axes.T @ self.local(x)

    def frame(self, p: np.ndarray) -> np.ndarray | None:
        """``F`` (3 x 3, columns the unit vectors of the displacement frame at the basic
        point ``p``, module docstring), or ``None`` on a curvilinear system's axis."""
        if self.kind == "R":
            return self.axes.T.copy()
        q = self.axes @ (np.asarray(p, dtype=float) - self.origin)
        rho, s = float(np.linalg.norm(q)), math.hypot(q[0], q[1])
        if not s > AXIS_TOL * rho:
            return None
        c, n = q[0] / s, q[1] / s  # cos and sin of the azimuth
        if self.kind == "C":
            local = np.array([[c, -n, 0.0], [n, c, 0.0], [0.0, 0.0, 1.0]])
        else:
            ct, st = q[2] / rho, s / rho
            local = np.array([[st * c, ct * c, -n], [st * n, ct * n, c], [ct, -st, 0.0]])
        return self.axes.T @ local


#: The basic system.
BASIC = CoordSystem("R", np.zeros(3), np.eye(3))


def read_cord2(c: RawCard) -> CoordCard:
    """CORD2R / CORD2C / CORD2S CID RID A1 A2 A3 B1 B2 B3 / C1 C2 C3."""
    cid = c.integer(0, "CID")
    if cid <= 0:
        raise c.error("coordinate system ids are positive", cid, "CID")
    c.blank_after(11, f"{c.name} has eleven fields")
    pts = [np.array([c.real(k, f"{p}{j + 1}") for j, k in enumerate(range(s, s + 3))])
           for p, s in (("A", 2), ("B", 5), ("C", 8))]
    return CoordCard(cid, c.name[-1], c.integer(1, "RID", 0), pts[0], pts[1], pts[2], None,
                     c.line)


def read_cord1(c: RawCard) -> list[CoordCard]:
    """CORD1R / CORD1C / CORD1S CIDA G1A G2A G3A CIDB G1B G2B G3B: one or two systems, each
    from three distinct grids (origin, a point on :math:`z`, a point in :math:`x`-:math:`z`)."""
    c.blank_after(8, f"{c.name} has one line")
    out = []
    for s, tag in ((0, "A"), (4, "B")):
        if s and not any(c.text(s + k) for k in range(4)):
            continue
        cid = c.integer(s, f"CID{tag}")
        if cid <= 0:
            raise c.error("coordinate system ids are positive", cid, f"CID{tag}")
        g = tuple(c.integer(s + k, f"G{k}{tag}") for k in (1, 2, 3))
        if len(set(g)) != 3:
            raise c.error("the three grids are distinct", list(g), f"G1{tag}")
        out.append(CoordCard(cid, c.name[-1], 0, None, None, None, (g[0], g[1], g[2]), c.line))
    return out


def _axes(card: CoordCard, a: np.ndarray, b: np.ndarray, p: np.ndarray, src: str
          ) -> CoordSystem:
    """The system of origin ``a``, ``b`` on :math:`z`, ``p`` in :math:`x`-:math:`z` (basic)."""
    ez = b - a
    ey = np.cross(ez, p - a)
    if float(np.linalg.norm(ez)) == 0 or float(np.linalg.norm(ey)) <= \
            1e-12 * float(np.linalg.norm(ez)) * max(float(np.linalg.norm(p - a)), 1e-300):
        raise BdfError(src, "A, B and C do not define axes (coincident or collinear)",
                       line=card.line, card=card.name, ident=card.id)
    ez, ey = ez / np.linalg.norm(ez), ey / np.linalg.norm(ey)
    return CoordSystem(card.kind, a, np.vstack([np.cross(ey, ez), ey, ez]))


def place_grids(coords: Mapping[int, CoordCard], grids: Mapping[int, Any], src: str
                ) -> tuple[dict[int, CoordSystem], dict[int, np.ndarray]]:
    """Every system of ``coords`` and every grid's basic position (``grids``: id -> a record
    with ``cp``, ``x``, ``line``), resolved together: a CORD2 needs its ``RID``, a CORD1 its
    grids, a grid its ``CP``.

    Raises:
        BdfError: a missing system or grid, or systems that depend on each other in a loop
            (through ``RID`` or a CORD1's grids), naming the card and field that refers.
    """
    systems: dict[int, CoordSystem] = {0: BASIC}
    where: dict[int, np.ndarray] = {}
    active: list[int] = []  # systems being resolved, for loops
    via: dict[int, str] = {}  # the field through which each of them is being resolved

    def system(cid: int, card: str, ident: int, line: int, field: str) -> CoordSystem:
        if cid in systems:
            return systems[cid]
        if cid not in coords:
            raise BdfError(src, "no such coordinate system", cid, line, card, ident, field)
        c = coords[cid]
        if cid in active:
            raise BdfError(src, "coordinate systems refer to each other in a loop",
                           active[active.index(cid):] + [cid], c.line, c.name, cid,
                           via[cid])
        active.append(cid)
        if c.grids is None:
            via[cid] = "RID"
            ref = system(c.rid, c.name, cid, c.line, "RID")
            assert c.a is not None and c.b is not None and c.c is not None
            pts = [ref.to_basic(v) for v in (c.a, c.b, c.c)]
        else:
            pts = []
            for k, g in enumerate(c.grids):
                via[cid] = f"G{k + 1}A (GRID {g})"
                pts.append(position(g, c, f"G{k + 1}A"))
        active.pop()
        systems[cid] = _axes(c, pts[0], pts[1], pts[2], src)
        return systems[cid]

    def position(gid: int, ref: CoordCard | None = None, field: str = "") -> np.ndarray:
        if gid in where:
            return where[gid]
        if gid not in grids:
            assert ref is not None
            raise BdfError(src, "no such GRID", gid, ref.line, ref.name, ref.id, field)
        g = grids[gid]
        where[gid] = system(g.cp, "GRID", gid, g.line, "CP").to_basic(np.asarray(g.x, float))
        return where[gid]

    for cid in coords:
        system(cid, "", 0, 0, "")
    for gid in grids:
        position(gid)
    return systems, where
