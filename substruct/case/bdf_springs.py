"""The spring cards of a Nastran file: scalar springs (CELAS1 with PELAS, CELAS2) and
six-component bushings (CBUSH with PBUSH), read from the fields of a
:class:`~substruct.case.bdf_fields.RawCard` (field indices as in
:mod:`substruct.case.bdf_cards`).  Every field is read or refused.
"""

from __future__ import annotations

from dataclasses import dataclass

from substruct.case.bdf_cards import components
from substruct.case.bdf_fields import RawCard, nastran_int

__all__ = ["Spring", "Bush", "read_celas", "read_pelas", "read_cbush", "read_pbush"]


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
class Bush:
    """CBUSH: grids ``ga`` and ``gb`` (``None``: grounded), the element axes from a coordinate
    system ``cid`` or (``cid`` ``None``) from the axis ``GA -> GB`` and an orientation vector
    ``v`` or grid ``g0`` as for CBAR, and the spring's place ``s`` along ``GA -> GB``."""

    id: int
    pid: int
    ga: int
    gb: int | None
    v: tuple[float, float, float] | None
    g0: int | None
    cid: int | None
    s: float
    line: int

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
    """CELAS1 EID PID G1 C1 G2 C2 or CELAS2 EID K G1 C1 G2 C2 GE S (``S`` unused by
    normal modes; a ``GE`` other than 0 refused)."""
    eid = c.integer(0, "EID")
    c.blank_after(8 if c.name == "CELAS2" else 6, f"{c.name} has one line")
    a = _end(c, 2, "1", blank_ok=False)
    b = _end(c, 4, "2", blank_ok=True)
    assert a is not None
    if b == a:  # k (u - u) = 0: the spring adds nothing
        raise c.error("the spring joins a coordinate to itself (G1, C1 and G2, C2 are the "
                      "same): it would add no stiffness", [a[0], a[1] + 1], "G2")
    if c.name == "CELAS2":
        c.no_damping(6, "GE")
    if c.name == "CELAS1":
        return Spring(eid, None, c.integer(1, "PID", eid), a, b, c.line)
    return Spring(eid, _stiffness(c, 1, "K"), None, a, b, c.line)


def _stiffness(c: RawCard, i: int, name: str) -> float:
    """A scalar spring's stiffness: not negative, as PBUSH's (a negative spring makes a
    stiffness that is not positive semi-definite, and modes that are not vibrations)."""
    k = c.real(i, name)
    if k < 0:
        raise c.error("stiffnesses must not be negative", c.text(i), name)
    return k


def read_pelas(c: RawCard) -> list[tuple[int, float]]:
    """PELAS PID1 K1 GE1 S1 PID2 K2 GE2 S2: ``[(pid, k), ...]`` (``S`` unused, a ``GE``
    other than 0 refused)."""
    c.blank_after(8, "PELAS has one line")
    c.no_damping(2, "GE1")
    c.no_damping(6, "GE2")
    out = [(c.integer(0, "PID1"), _stiffness(c, 1, "K1"))]
    if c.text(4):
        out.append((c.integer(4, "PID2"), _stiffness(c, 5, "K2")))
    return out


def _unused_orientation(c: RawCard) -> None:
    """Check the form of a CBUSH's ``GO`` or ``X1 - X3`` beside ``CID``: by Nastran's CBUSH
    remarks ``CID >= 0`` overrides them (FEMAP writes both), so they are read and not used."""
    if c.text(4) and nastran_int(c.text(4)) is not None:
        if c.text(5) or c.text(6):
            raise c.error("with GO in field 6, X2 and X3 are blank", c.text(5) or c.text(6),
                          "X2")
        c.integer(4, "GO")
    elif any(c.text(k) for k in (4, 5, 6)):
        for k, name in ((4, "X1"), (5, "X2"), (6, "X3")):
            c.real(k, name, 0.0)


def read_cbush(c: RawCard) -> Bush:
    """CBUSH EID PID GA GB GO/X1 X2 X3 CID / S OCID S1 S2 S3.  With ``CID`` (0: basic) the
    element axes are that system's, and ``GO/X``, when given, is checked and not used (Nastran's
    precedence: ``CID >= 0`` overrides it); without it they come from ``GA -> GB`` and ``GO/X``
    (as CBAR).  ``S`` places the spring on ``GA -> GB`` (0.5); ``OCID`` other
    than -1 and the offsets ``S1 - S3`` are refused."""
    eid = c.integer(0, "EID")
    c.blank_after(13, "CBUSH has two lines")
    for k, name in ((10, "S1"), (11, "S2"), (12, "S3")):
        if c.text(k):
            raise c.error("spring offsets in a coordinate system (OCID, S1 - S3) are not "
                          "supported", c.text(k), name)
    if c.integer(9, "OCID", -1) != -1:
        raise c.error("spring offsets in a coordinate system (OCID) are not supported",
                      c.text(9), "OCID")
    s = c.real(8, "S", 0.5)
    if not 0.0 <= s <= 1.0:
        raise c.error("S is a fraction of GA -> GB, 0 to 1", s, "S")
    gb = c.integer(3, "GB", 0) or None
    cid = c.integer(7, "CID") if c.text(7) else None
    g0, v = None, None
    if cid is not None:
        if cid < 0:
            raise c.error("CID is 0 (basic) or a coordinate system id", cid, "CID")
        _unused_orientation(c)
    elif c.text(4) and nastran_int(c.text(4)) is not None:
        if c.text(5) or c.text(6):
            raise c.error("with GO in field 6, X2 and X3 are blank", c.text(5) or c.text(6),
                          "X2")
        g0 = c.integer(4, "GO")
    elif any(c.text(k) for k in (4, 5, 6)):
        v = (c.real(4, "X1", 0.0), c.real(5, "X2", 0.0), c.real(6, "X3", 0.0))
    else:
        raise c.error("the element axes need CID, or GB with GO or X1 - X3", name="CID")
    if cid is None and gb is None:
        raise c.error("a grounded CBUSH needs CID for its axes", name="CID")
    return Bush(eid, c.integer(1, "PID", eid), c.integer(2, "GA"), gb, v, g0, cid, s, c.line)


def read_pbush(c: RawCard) -> tuple[int, tuple[float, ...]]:
    """PBUSH PID "K" K1 - K6 / "B" B1 - B6 / "GE" GE1 / "RCV" SA ST EA ET: ``(pid, (K1 ..
    K6))`` (blank: 0).  Damping ``B`` and ``GE`` other than 0 are refused (the damping would go
    unused); ``RCV`` (stress recovery) is read and not used; other lines are refused."""
    pid = c.integer(0, "PID")
    k: tuple[float, ...] | None = None
    for line in range((len(c.fields) + 7) // 8):
        base = 8 * line
        if line and c.text(base):
            raise c.error("field 2 of a PBUSH continuation is blank", c.text(base),
                          f"line {line + 1} field 2")
        key = c.text(base + 1)
        values = [c.real(base + 2 + j, f"{key}{j + 1}", 0.0) for j in range(6)
                  if key in ("K", "B", "GE")]
        if key == "K":
            if k is not None:
                raise c.error("the K line is given twice", key, "K")
            if any(v < 0 for v in values):
                raise c.error("stiffnesses must not be negative", values, "K1")
            k = tuple(values)
        elif key in ("B", "GE"):
            if any(values):
                raise c.error(f"{key} (damping) is not supported: normal modes and the "
                              f"undamped responses of a substructure do not use it", values,
                              f"{key}1")
        elif key != "RCV":
            raise c.error("PBUSH lines are K, B, GE and RCV", key, f"line {line + 1} field 3")
    if k is None:
        raise c.error("PBUSH needs its K line", name="K")
    return pid, k
