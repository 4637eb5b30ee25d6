"""The bulk data cards read from a Nastran file, one small record each, read from the fields of
a :class:`~substruct.case.bdf_fields.RawCard` with the field names of the Nastran Quick
Reference Guide.  Each reader takes every field of its card or refuses it (a field that would
change the model and is not read is an error naming it, never skipped).

Field indices follow :mod:`substruct.case.bdf_fields`: ``fields[0]`` is field 2 of the first
line, ``fields[8 k + j]`` field ``j + 2`` of continuation ``k``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from substruct.case.bdf_fields import RawCard, nastran_int, nastran_real

__all__ = ["components", "Grid", "Coord", "Rod", "Bar", "Mat1", "Conm2", "Spring", "Rbe2",
           "Rbe3", "Mpc", "Eigrl", "read_grid", "read_cord2r", "read_prod", "read_pbar",
           "read_pbeam", "read_mat1", "read_rod", "read_bar", "read_conm2", "read_celas",
           "read_pelas", "read_rbe2", "read_rbe3", "read_mpc", "read_spc", "read_spc1",
           "read_eigrl"]


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
class Grid:
    """GRID: id, position in coordinate system ``cp``, permanent constraints ``ps``."""

    id: int
    cp: int
    x: tuple[float, float, float]
    ps: str
    line: int


@dataclass(frozen=True)
class Coord:
    """CORD2R: ``A`` origin, ``B`` on the z axis, ``C`` in the x-z plane, in system ``rid``."""

    id: int
    rid: int
    a: np.ndarray
    b: np.ndarray
    c: np.ndarray
    line: int


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


@dataclass(frozen=True)
class Mat1:
    """MAT1: ``E``, ``G`` (completed from ``NU`` as Nastran does) and ``rho``."""

    id: int
    E: float
    G: float
    rho: float
    line: int


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


@dataclass(frozen=True)
class Spring:
    """CELAS1 / CELAS2: stiffness ``k`` (CELAS1: from PELAS ``pid``) between ``(grid,
    component)`` ends, the second ``None`` when grounded."""

    id: int
    k: float | None
    pid: int | None
    a: tuple[int, int]
    b: tuple[int, int] | None
    line: int


@dataclass(frozen=True)
class Rbe2:
    """RBE2: independent grid ``gn``, components ``cm`` of the dependent grids ``gm``."""

    id: int
    gn: int
    cm: str
    gm: tuple[int, ...]
    line: int


@dataclass(frozen=True)
class Rbe3:
    """RBE3: reference grid and components, and groups ``(weight, components, grids)``."""

    id: int
    ref: int
    refc: str
    groups: tuple[tuple[float, str, tuple[int, ...]], ...]
    line: int


@dataclass(frozen=True)
class Mpc:
    """MPC: set ``sid``, terms ``(grid, component, coefficient)``, the first dependent."""

    sid: int
    terms: tuple[tuple[int, int, float], ...]
    line: int


@dataclass(frozen=True)
class Eigrl:
    """EIGRL: set ``sid``, frequency range ``v1``-``v2`` (Hz, ``None`` when blank), ``nd``."""

    sid: int
    v1: float | None
    v2: float | None
    nd: int | None
    line: int


def read_grid(c: RawCard) -> Grid:
    """GRID ID CP X1 X2 X3 CD PS SEID."""
    gid = c.integer(0, "ID")
    if gid <= 0:
        raise c.error("grid ids are positive", gid, "ID")
    cd = c.integer(5, "CD", 0)
    if cd != 0:
        raise c.error("displacement coordinate systems other than basic are not supported",
                      cd, "CD")
    if c.integer(7, "SEID", 0) != 0:
        raise c.error("superelements are not supported", c.text(7), "SEID")
    c.blank_after(8, "GRID has one line")
    x = (c.real(2, "X1", 0.0), c.real(3, "X2", 0.0), c.real(4, "X3", 0.0))
    return Grid(gid, c.integer(1, "CP", 0), x, components(c, 6, "PS", blank_ok=True), c.line)


def read_cord2r(c: RawCard) -> Coord:
    """CORD2R CID RID A1 A2 A3 B1 B2 B3 / C1 C2 C3."""
    cid = c.integer(0, "CID")
    if cid <= 0:
        raise c.error("coordinate system ids are positive", cid, "CID")
    c.blank_after(11, "CORD2R has eleven fields")
    pts = [np.array([c.real(k, f"{p}{j + 1}") for j, k in enumerate(range(s, s + 3))])
           for p, s in (("A", 2), ("B", 5), ("C", 8))]
    return Coord(cid, c.integer(1, "RID", 0), pts[0], pts[1], pts[2], c.line)


def read_prod(c: RawCard) -> tuple[int, int, float, float, float]:
    """PROD PID MID A J C NSM: ``(pid, mid, A, J, nsm)`` (``C``, stress recovery, unused)."""
    c.blank_after(6, "PROD has six fields")
    return (c.integer(0, "PID"), c.integer(1, "MID"), c.real(2, "A"), c.real(3, "J", 0.0),
            c.real(5, "NSM", 0.0))


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
    return (c.integer(0, "PID"), c.integer(1, "MID"), c.real(2, "A", 0.0), c.real(3, "I1", 0.0),
            c.real(4, "I2", 0.0), c.real(5, "J", 0.0), c.real(6, "NSM", 0.0))


def read_pbeam(c: RawCard) -> tuple[int, int, float, float, float, float, float]:
    """PBEAM (basic: one constant section) PID MID A I1 I2 I12 J NSM / C1 .. F2:
    ``(pid, mid, A, I1, I2, J, nsm)``; shear factors are Nastran's default ``K1 = K2 = 1``."""
    c.blank_after(16, "basic PBEAM: one constant section and its stress points; tapered "
                  "sections, K1 K2, NSI and warping lines are not supported")
    if c.text(5) and c.real(5, "I12") != 0.0:
        raise c.error("unsymmetric sections (I12) are not supported", c.text(5), "I12")
    return (c.integer(0, "PID"), c.integer(1, "MID"), c.real(2, "A"), c.real(3, "I1", 0.0),
            c.real(4, "I2", 0.0), c.real(6, "J", 0.0), c.real(7, "NSM", 0.0))


def read_mat1(c: RawCard) -> Mat1:
    """MAT1 MID E G NU RHO A TREF GE / ST SC SS MCSID, with Nastran's rules for the blank one
    of ``E, G, NU``: two given fix the third; ``E`` or ``G`` alone leaves the other 0."""
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
    for value, name in ((E, "E"), (G, "G"), (rho, "RHO")):
        if value is None or value < 0:
            raise c.error("must not be negative", value, name)
    assert E is not None and G is not None
    return Mat1(c.integer(0, "MID"), E, G, rho, c.line)


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
               pins[0], pins[1], wa, wb, c.line)


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


def _end(c: RawCard, gi: int, name: str, blank_ok: bool) -> tuple[int, int] | None:
    g = c.integer(gi, f"G{name}", 0)
    if g == 0 and blank_ok:
        if c.text(gi + 1) not in ("", "0"):
            raise c.error("a grounded end has no component", c.text(gi + 1), f"C{name}")
        return None
    comp = components(c, gi + 1, f"C{name}")
    if len(comp) != 1:
        raise c.error("a scalar spring joins one component at each end", comp, f"C{name}")
    return g, int(comp) - 1


def read_celas(c: RawCard) -> Spring:
    """CELAS1 EID PID G1 C1 G2 C2 or CELAS2 EID K G1 C1 G2 C2 GE S (``GE``, ``S`` unused by
    normal modes)."""
    eid = c.integer(0, "EID")
    c.blank_after(8 if c.name == "CELAS2" else 6, f"{c.name} has one line")
    a = _end(c, 2, "1", blank_ok=False)
    b = _end(c, 4, "2", blank_ok=True)
    assert a is not None
    if c.name == "CELAS1":
        return Spring(eid, None, c.integer(1, "PID", eid), a, b, c.line)
    return Spring(eid, c.real(1, "K"), None, a, b, c.line)


def read_pelas(c: RawCard) -> list[tuple[int, float]]:
    """PELAS PID1 K1 GE1 S1 PID2 K2 GE2 S2: ``[(pid, k), ...]`` (``GE``, ``S`` unused)."""
    c.blank_after(8, "PELAS has one line")
    out = [(c.integer(0, "PID1"), c.real(1, "K1"))]
    if c.text(4):
        out.append((c.integer(4, "PID2"), c.real(5, "K2")))
    return out


def _int_list(c: RawCard, start: int, name: str) -> tuple[list[int], int]:
    """Integers from ``start`` on (blanks skipped) up to a non-integer: ``(values, index)``."""
    out, k = [], start
    while k < len(c.fields):
        t = c.fields[k]
        if t and nastran_int(t) is None:
            break
        if t:
            out.append(int(t))
        k += 1
    if not out:
        raise c.error("needs at least one grid", name=name)
    return out, k


def read_rbe2(c: RawCard) -> Rbe2:
    """RBE2 EID GN CM GM1 GM2 ... (ALPHA: thermal, unused)."""
    gm, k = _int_list(c, 3, "GM1")
    if k < len(c.fields):
        c.real(k, "ALPHA")
        c.blank_after(k + 1, "RBE2 ends with ALPHA")
    return Rbe2(c.integer(0, "EID"), c.integer(1, "GN"), components(c, 2, "CM"), tuple(gm), c.line)


def read_rbe3(c: RawCard) -> Rbe3:
    """RBE3 EID blank REFGRID REFC WT1 C1 G1,1 ... WT2 C2 G2,1 ... ; ``UM`` is refused."""
    if c.text(1):
        raise c.error("field 3 of RBE3 is blank", c.text(1), "field 3")
    groups: list[tuple[float, str, tuple[int, ...]]] = []
    k = 4
    while k < len(c.fields):
        t = c.fields[k]
        if not t:
            k += 1
            continue
        if t in ("UM", "ALPHA"):
            if t == "UM":
                raise c.error("user-chosen dependent components (UM) are not supported", t,
                              "UM")
            c.real(k + 1, "ALPHA")
            c.blank_after(k + 2, "RBE3 ends with ALPHA")
            break
        w = c.real(k, f"WT{len(groups) + 1}")
        comp = components(c, k + 1, f"C{len(groups) + 1}")
        grids, k = _int_list(c, k + 2, f"G{len(groups) + 1},1")
        groups.append((w, comp, tuple(grids)))
    if not groups:
        raise c.error("needs at least one weight, component and grid", name="WT1")
    return Rbe3(c.integer(0, "EID"), c.integer(2, "REFGRID"), components(c, 3, "REFC"),
                tuple(groups), c.line)


def read_mpc(c: RawCard) -> Mpc:
    """MPC SID G1 C1 A1 G2 C2 A2 / blank G3 C3 A3 G4 C4 A4 / ..."""
    terms: list[tuple[int, int, float]] = []
    for line in range((len(c.fields) + 7) // 8):
        if line and c.text(8 * line):
            raise c.error("field 2 of an MPC continuation is blank", c.text(8 * line),
                          f"line {line + 1} field 2")
        for s in (8 * line + 1, 8 * line + 4):
            if not any(c.text(s + j) for j in range(3)):
                continue
            n = len(terms) + 1
            comp = components(c, s + 1, f"C{n}")
            if len(comp) != 1:
                raise c.error("one component per term", comp, f"C{n}")
            terms.append((c.integer(s, f"G{n}"), int(comp) - 1, c.real(s + 2, f"A{n}")))
        if c.text(8 * line + 7):
            raise c.error("field 9 of an MPC line is blank", c.text(8 * line + 7),
                          f"line {line + 1} field 9")
    if not terms:
        raise c.error("needs at least one term", name="G1")
    return Mpc(c.integer(0, "SID"), tuple(terms), c.line)


def read_spc(c: RawCard) -> tuple[int, list[tuple[int, str]]]:
    """SPC SID G1 C1 D1 G2 C2 D2: ``(sid, [(grid, components)])``; enforced motion refused."""
    c.blank_after(7, "SPC has one line")
    out = []
    for s in (1, 4):
        if not c.text(s):
            continue
        n = 1 if s == 1 else 2
        if c.real(s + 2, f"D{n}", 0.0) != 0.0:
            raise c.error("enforced displacements are not supported", c.text(s + 2), f"D{n}")
        out.append((c.integer(s, f"G{n}"), components(c, s + 1, f"C{n}")))
    return c.integer(0, "SID"), out


def read_spc1(c: RawCard) -> tuple[int, str, list[int] | range]:
    """SPC1 SID C G1 G2 ... or SID C G1 THRU G2 (a ``range``: the grids of the model in it)."""
    sid, comp = c.integer(0, "SID"), components(c, 1, "C")
    if c.text(3) == "THRU":
        c.blank_after(5, "SPC1 with THRU has one range")
        a, b = c.integer(2, "G1"), c.integer(4, "G2")
        if b < a:
            raise c.error("a THRU range goes up", f"{a} THRU {b}", "G2")
        return sid, comp, range(a, b + 1)
    grids, k = _int_list(c, 2, "G1")
    c.blank_after(k, "SPC1 grids are integers")
    return sid, comp, grids


def read_eigrl(c: RawCard) -> Eigrl:
    """EIGRL SID V1 V2 ND MSGLVL MAXSET SHFSCL NORM (V1, V2 in Hz; NORM MASS only)."""
    c.blank_after(8, "EIGRL option lines are not supported")
    norm = c.text(7) or "MASS"
    if norm != "MASS":
        raise c.error("modes are normalised to unit modal mass (NORM MASS)", norm, "NORM")
    v1 = c.real(1, "V1") if c.text(1) else None
    v2 = c.real(2, "V2") if c.text(2) else None
    nd = c.integer(3, "ND") if c.text(3) else None
    if nd is not None and nd <= 0:
        raise c.error("must be positive", nd, "ND")
    if nd is None and v2 is None:
        raise c.error("EIGRL needs ND or V2 (the modes wanted)", name="ND")
    if v1 is not None and v2 is not None and v2 <= v1:
        raise c.error("V2 must be above V1", v2, "V2")
    return Eigrl(c.integer(0, "SID"), v1, v2, nd, c.line)
