"""The bulk data cards read from a Nastran file, one small record each, read from the fields of
a :class:`~substruct.case.bdf_fields.RawCard` with the field names of the Nastran Quick
Reference Guide.  Each reader takes every field of its card or refuses it (a field that would
change the model and is not read is an error naming it, never skipped).

Field indices follow :mod:`substruct.case.bdf_fields`: ``fields[0]`` is field 2 of the first
line, ``fields[8 k + j]`` field ``j + 2`` of continuation ``k``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from substruct.case.bdf_fields import RawCard, nastran_int, nastran_real

__all__ = ["components", "GridCard", "Rod", "Bar", "Mat1", "Conm2", "read_grid",
           "read_prod", "read_pbar", "read_pbarl", "read_mat1",
           "read_rod", "read_bar", "read_conm2"]


def components(card: RawCard, i: int, name: str, blank_ok: bool = False) -> str:
    """A component field: digits 1-6, each once (Nastran's component codes), sorted."""
    t = card.text(i)
    if not t and blank_ok:
        return ""
    if not t or not t.isdigit() or any(c not in "123456" for c in t) or len(set(t)) != len(t):
        raise card.error("components are digits 1-6, each once (scalar points, 0, are not "
                         "supported)", t, name)
    return "".join(sorted(t))


@dataclass(frozen=True)
class GridCard:
    """GRID: id, position in coordinate system ``cp``, permanent constraints ``ps`` (in
    ``cd``), displacement coordinate system ``cd``."""

    id: int
    cp: int
    x: tuple[float, float, float]
    ps: str
    line: int
    cd: int = 0


@dataclass(frozen=True)
class Rod:
    """CROD with its PROD: area ``A``, torsion constant ``J``, non-structural mass ``nsm``."""

    id: int
    pid: int
    nodes: tuple[int, int]
    line: int


@dataclass(frozen=True)
class Bar:
    """CBAR / CBEAM: end grids, orientation (a vector in basic or a grid ``g0``), pin flags and
    offsets (in basic)."""

    kind: str
    id: int
    pid: int
    nodes: tuple[int, int]
    v: tuple[float, float, float] | None
    g0: int | None
    pa: str
    pb: str
    wa: tuple[float, float, float]
    wb: tuple[float, float, float]
    line: int
    offt: str = "GGG"


@dataclass(frozen=True)
class Mat1:
    """MAT1: ``E``, ``G`` (completed from ``NU`` as Nastran does), ``rho`` and ``NU`` when all
    three of ``E, G, NU`` are given (``given_nu``).  As in Nastran, line elements use ``E``
    and ``G``, shells and solids ``E`` and :attr:`nu`."""

    id: int
    E: float
    G: float
    rho: float
    line: int
    given_nu: float | None = None

    @property
    def nu(self) -> float:
        """Poisson's ratio: ``NU`` as given, or :math:`E / 2G - 1` when it was derived."""
        return self.given_nu if self.given_nu is not None else self.E / (2 * self.G) - 1


@dataclass(frozen=True)
class Conm2:
    """CONM2: mass ``m`` at grid ``g``, offset ``x`` and inertia ``I`` (3 x 3, Nastran's sign
    convention applied) in system ``cid`` (``-1``: ``x`` is the position in basic)."""

    id: int
    g: int
    cid: int
    m: float
    x: np.ndarray
    inertia: np.ndarray
    line: int


def read_grid(c: RawCard) -> GridCard:
    """GRID ID CP X1 X2 X3 CD PS SEID."""
    gid = c.integer(0, "ID")
    if gid <= 0:
        raise c.error("grid ids are positive", gid, "ID")
    cd = c.integer(5, "CD", 0)
    if cd < 0:
        raise c.error("CD is 0 (basic) or a coordinate system id", cd, "CD")
    if c.integer(7, "SEID", 0) != 0:
        raise c.error("superelements are not supported", c.text(7), "SEID")
    c.blank_after(8, "GRID has one line")
    x = (c.real(2, "X1", 0.0), c.real(3, "X2", 0.0), c.real(4, "X3", 0.0))
    return GridCard(gid, c.integer(1, "CP", 0), x, components(c, 6, "PS", blank_ok=True), c.line,
                    cd)


def read_prod(c: RawCard) -> tuple[int, int, float, float, float]:
    """PROD PID MID A J C NSM: ``(pid, mid, A, J, nsm)`` (``C``, stress recovery, unused)."""
    c.blank_after(6, "PROD has six fields")
    values = (c.real(2, "A"), c.real(3, "J", 0.0), c.real(5, "NSM", 0.0))
    _not_negative(c, values, ("A", "J", "NSM"))
    return (c.integer(0, "PID"), c.integer(1, "MID"), *values)


def _not_negative(c: RawCard, values: tuple[float, ...], names: tuple[str, ...]) -> None:
    """Refuse a negative section property (area, moments of inertia, torsion constant,
    non-structural mass)."""
    for value, name in zip(values, names):
        if value < 0:
            raise c.error("must not be negative", value, name)


def read_pbar(c: RawCard) -> tuple[int, int, float, float, float, float, float]:
    """PBAR PID MID A I1 I2 J NSM / C1 .. F2 (stress points, unused) / K1 K2 I12:
    ``(pid, mid, A, I1, I2, J, nsm)``; shear factors and ``I12`` are refused."""
    for k, name in ((16, "K1"), (17, "K2")):
        if c.text(k):
            raise c.error("shear flexibility of CBAR (K1, K2) is not supported: leave blank "
                          "or use CBEAM", c.text(k), name)
    if c.text(18) and c.real(18, "I12") != 0.0:
        raise c.error("unsymmetric sections (I12) are not supported", c.text(18), "I12")
    c.blank_after(19, "PBAR has three lines")
    values = (c.real(2, "A", 0.0), c.real(3, "I1", 0.0), c.real(4, "I2", 0.0),
              c.real(5, "J", 0.0), c.real(6, "NSM", 0.0))
    _not_negative(c, values, ("A", "I1", "I2", "J", "NSM"))
    return (c.integer(0, "PID"), c.integer(1, "MID"), *values)


def read_pbarl(c: RawCard) -> tuple[int, int, float, float, float, float, float]:
    r"""PBARL / PBEAML PID MID GROUP TYPE / DIM1 NSM of the ``ROD`` section only (a solid
    circle of radius ``r = DIM1``): ``(pid, mid, A, I1, I2, J, nsm)`` with
    :math:`A = \pi r^2`, :math:`I_1 = I_2 = \pi r^4 / 4`, :math:`J = \pi r^4 / 2`, the
    PBAR/PBEAM Nastran puts in their place (its shear factors ``K1 = K2 = 0.9`` are set where
    the property is cross-referenced).  GROUP blank or ``MSCBML0``; other sections, and a
    PBEAML's tapered stations, are refused."""
    group = c.text(2) or "MSCBML0"
    if group != "MSCBML0":
        raise c.error("only the section library MSCBML0 is supported", group, "GROUP")
    if c.text(3) != "ROD":
        raise c.error("only the ROD section (a solid circle) is supported", c.text(3), "TYPE")
    c.blank_after(10, f"{c.name} ROD of one constant section: DIM1 and NSM")
    r = c.real(8, "DIM1")
    if not r > 0:
        raise c.error("the radius must be positive", r, "DIM1")
    A, I = math.pi * r ** 2, math.pi * r ** 4 / 4
    return c.integer(0, "PID"), c.integer(1, "MID"), A, I, I, 2 * I, c.real(9, "NSM", 0.0)


def read_mat1(c: RawCard) -> Mat1:
    """MAT1 MID E G NU RHO A TREF GE / ST SC SS MCSID, with Nastran's rules for the blank one
    of ``E, G, NU``: two given fix the third; ``E`` or ``G`` alone leaves the other 0.
    ``A, TREF`` and the stress limits are not used; a ``GE`` other than 0 is refused."""
    c.blank_after(12, "MAT1 has two lines")
    E, G = c.real(1, "E", 0.0) if c.text(1) else None, c.real(2, "G") if c.text(2) else None
    nu = c.real(3, "NU") if c.text(3) else None
    if E is None and G is None:
        raise c.error("E and G are both blank", name="E")
    if E is not None and G is None:
        G = E / (2 * (1 + nu)) if nu is not None else 0.0
    elif G is not None and E is None:
        E = 2 * (1 + nu) * G if nu is not None else 0.0
    rho = c.real(4, "RHO", 0.0)
    c.no_damping(7, "GE")
    for value, name in ((E, "E"), (G, "G"), (rho, "RHO")):
        if value is None or value < 0:
            raise c.error("must not be negative", value, name)
    assert E is not None and G is not None
    given = nu if c.text(1) and c.text(2) and nu is not None else None
    return Mat1(c.integer(0, "MID"), E, G, rho, c.line, given)


def read_rod(c: RawCard) -> Rod:
    """CROD EID PID G1 G2."""
    c.blank_after(4, "CROD has four fields")
    eid = c.integer(0, "EID")
    return Rod(eid, c.integer(1, "PID", eid), (c.integer(2, "G1"), c.integer(3, "G2")), c.line)


def read_bar(c: RawCard) -> Bar:
    """CBAR / CBEAM EID PID GA GB X1|G0 X2 X3 OFFT / PA PB W1A W2A W3A W1B W2B W3B (/ SA SB)."""
    eid = c.integer(0, "EID")
    c.blank_after(16, f"{c.name} warping points SA SB are not supported")
    offt = c.text(7) or "GGG"
    if c.name == "CBEAM" and nastran_real(offt) is not None:
        raise c.error("BIT (built-in twist) is not supported", offt, "BIT")
    if len(offt) != 3 or offt[0] not in "GB" or offt[1] not in "GB" or offt[2] not in "GB":
        raise c.error("OFFT must be made of G and B (the displacement systems are basic); "
                      "offsets in the element system, O, are not supported", offt, "OFFT")
    g0 = nastran_int(c.text(4)) if c.text(4) else None
    v = None
    if g0 is None:
        v = (c.real(4, "X1", 0.0), c.real(5, "X2", 0.0), c.real(6, "X3", 0.0))
    elif c.text(5) or c.text(6):
        raise c.error("with G0 in field 6, X2 and X3 are blank", c.text(5) or c.text(6), "X2")
    pins = []
    for k, name in ((8, "PA"), (9, "PB")):
        pins.append(components(c, k, name, blank_ok=True))
    wa = (c.real(10, "W1A", 0.0), c.real(11, "W2A", 0.0), c.real(12, "W3A", 0.0))
    wb = (c.real(13, "W1B", 0.0), c.real(14, "W2B", 0.0), c.real(15, "W3B", 0.0))
    return Bar(c.name, eid, c.integer(1, "PID", eid), (c.integer(2, "GA"), c.integer(3, "GB")), v, g0,
               pins[0], pins[1], wa, wb, c.line, offt)


def read_conm2(c: RawCard) -> Conm2:
    r"""CONM2 EID G CID M X1 X2 X3 / I11 I21 I22 I31 I32 I33.  The inertia about the centre
    of gravity is Nastran's :math:`[[I_{11}, -I_{21}, -I_{31}], [-I_{21}, I_{22}, -I_{32}],
    [-I_{31}, -I_{32}, I_{33}]]` (products of inertia entered as positive integrals)."""
    c.blank_after(14, "CONM2 has two lines")
    if c.text(7):
        raise c.error("field 9 of CONM2 is blank", c.text(7), "field 9")
    i11, i21, i22, i31, i32, i33 = (c.real(8 + k, n, 0.0) for k, n in
                                    enumerate(("I11", "I21", "I22", "I31", "I32", "I33")))
    inertia = np.array([[i11, -i21, -i31], [-i21, i22, -i32], [-i31, -i32, i33]])
    m = c.real(3, "M")
    if m < 0:
        raise c.error("must not be negative", m, "M")
    if np.linalg.eigvalsh(inertia).min() < -1e-12 * max(np.abs(inertia).max(), 1e-300):
        raise c.error("the inertia matrix about the centre of gravity is not positive "
                      "semi-definite", [i11, i21, i22, i31, i32, i33], "I11")
    x = np.array([c.real(4, "X1", 0.0), c.real(5, "X2", 0.0), c.real(6, "X3", 0.0)])
    return Conm2(c.integer(0, "EID"), c.integer(1, "G"), c.integer(2, "CID", 0), m, x, inertia, c.line)
