"""The constraint cards of a Nastran file: rigid elements (RBE2, RBE3, RBAR), multi-point
constraints (MPC) and single-point constraints (SPC, SPC1, SPCADD), read from the fields of a
:class:`~substruct.case.bdf_fields.RawCard` with the field names of the Nastran Quick
Reference Guide (field indices as in :mod:`substruct.case.bdf_cards`).  Every field is read or
refused.
"""

from __future__ import annotations

from dataclasses import dataclass

from substruct.case.bdf_cards import components
from substruct.case.bdf_fields import RawCard, nastran_int

__all__ = ["Rbe2", "Rbe3", "Rbar", "Mpc", "read_rbe2", "read_rbe3", "read_rbar", "read_mpc",
           "read_spc", "read_spc1", "read_spcadd", "int_list"]


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
class Rbar:
    """RBAR: a rigid bar between grids ``ga`` and ``gb``; independent components ``cna`` (at
    GA) and ``cnb`` (at GB), six in all, and dependent ones ``cma``, ``cmb`` (when both are
    blank on the card, every component not independent at each end: Nastran's rule)."""

    id: int
    ga: int
    gb: int
    cna: str
    cnb: str
    cma: str
    cmb: str
    line: int


@dataclass(frozen=True)
class Mpc:
    """MPC: set ``sid``, terms ``(grid, component, coefficient)``, the first dependent."""

    sid: int
    terms: tuple[tuple[int, int, float], ...]
    line: int


def int_list(c: RawCard, start: int, name: str) -> tuple[list[int], int]:
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
    gm, k = int_list(c, 3, "GM1")
    if k < len(c.fields):
        c.real(k, "ALPHA")
        c.blank_after(k + 1, "RBE2 ends with ALPHA")
    return Rbe2(c.integer(0, "EID"), c.integer(1, "GN"), components(c, 2, "CM"), tuple(gm), c.line)


def read_rbar(c: RawCard) -> Rbar:
    """RBAR EID GA GB CNA CNB CMA CMB ALPHA.  CNA and CNB hold six components in all (whether
    they determine the bar's rigid motion is checked where the grids' positions are known);
    CMA and CMB blank (or 0) make every other component dependent.  ALPHA (thermal
    expansion) is read and not used: thermal loads are not analysed, and normal modes do not
    depend on it."""
    c.blank_after(8, "RBAR has one line")
    ga, gb = c.integer(1, "GA"), c.integer(2, "GB")
    if ga == gb:
        raise c.error("GA and GB are the same grid", gb, "GB")
    cna, cnb = components(c, 3, "CNA", blank_ok=True), components(c, 4, "CNB", blank_ok=True)
    if len(cna) + len(cnb) != 6:
        raise c.error("CNA and CNB hold six independent components in all", f"{cna}+{cnb}",
                      "CNA")
    cm = [components(c, k, name, blank_ok=True) if c.text(k) != "0" else ""
          for k, name in ((5, "CMA"), (6, "CMB"))]
    if not cm[0] and not cm[1]:
        cm = ["".join(d for d in "123456" if d not in cn) for cn in (cna, cnb)]
    for cn, dep, name in ((cna, cm[0], "CMA"), (cnb, cm[1], "CMB")):
        both = sorted(set(cn) & set(dep))
        if both:
            raise c.error("a component is both independent and dependent at the same grid",
                          "".join(both), name)
    if c.text(7):
        c.real(7, "ALPHA")
    return Rbar(c.integer(0, "EID"), ga, gb, cna, cnb, cm[0], cm[1], c.line)


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
        grids, k = int_list(c, k + 2, f"G{len(groups) + 1},1")
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
            terms.append((c.integer(s, f"G{n}"), int(comp) - 1,
                          c.real(s + 2, f"A{n}", coefficient=True)))
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
    grids, k = int_list(c, 2, "G1")
    c.blank_after(k, "SPC1 grids are integers")
    return sid, comp, grids


def read_spcadd(c: RawCard) -> tuple[int, list[int]]:
    """SPCADD SID S1 S2 ...: ``(sid, [S1, S2, ...])``, the union of the SPC/SPC1 sets ``Si``
    (chosen by ``SPC = SID`` as one set)."""
    sets, k = int_list(c, 1, "S1")
    c.blank_after(k, "SPCADD set ids are integers")
    if not sets:
        raise c.error("needs at least one set", name="S1")
    sid = c.integer(0, "SID")
    for n, s in enumerate(sets):
        if s <= 0 or s == sid:
            raise c.error("set ids are positive and differ from the SPCADD's own", s,
                          f"S{n + 1}")
    return sid, sets
