"""The shell cards of a Nastran file: CQUAD4 and CTRIA3 elements and their PSHELL property,
read from the fields of a :class:`~substruct.case.bdf_fields.RawCard` (field indices as in
:mod:`substruct.case.bdf_cards`).  Every field is read or refused.
"""

from __future__ import annotations

from dataclasses import dataclass

from substruct.case.bdf_fields import RawCard, nastran_int

__all__ = ["Plate", "Pshell", "read_cquad4", "read_ctria3", "read_pshell"]


@dataclass(frozen=True)
class Plate:
    """CQUAD4 / CTRIA3: its corner grids in order."""

    kind: str
    id: int
    pid: int
    nodes: tuple[int, ...]
    line: int


@dataclass(frozen=True)
class Pshell:
    """PSHELL: membrane material ``mid1`` and bending material ``mid2`` (``None`` when blank:
    no membrane, no bending), thickness ``t``, bending inertia ratio ``bend`` (``12 I / T^3``,
    1.0 by default), non-structural mass per area ``nsm``, the transverse shear material
    ``mid3`` (``None``: blank, a Kirchhoff plate) and ``ts`` (``TS/T``, 5/6 by default)."""

    id: int
    mid1: int | None
    t: float
    mid2: int | None
    bend: float
    nsm: float
    line: int
    mid3: int | None = None
    ts: float = 5.0 / 6.0


def _plate(c: RawCard, n: int, theta: int, zoffs: int, tflag: int) -> Plate:
    eid = c.integer(0, "EID")
    nodes = tuple(c.integer(2 + k, f"G{k + 1}") for k in range(n))
    if c.text(theta) and nastran_int(c.text(theta)) is None:  # MCID (an integer) or THETA:
        c.real(theta, "THETA")  # material axes, no effect with an isotropic MAT1
    if c.real(zoffs, "ZOFFS", 0.0) != 0.0:
        raise c.error("offsets of the reference plane (ZOFFS) are not supported",
                      c.text(zoffs), "ZOFFS")
    for k in range(tflag, tflag + 1 + n):
        if c.text(k):
            name = "TFLAG" if k == tflag else f"T{k - tflag}"
            raise c.error("thicknesses at the corners (TFLAG, T1 - Tn) are not supported: the "
                          "PSHELL's T is used", c.text(k), name)
    if len(set(nodes)) != n:
        raise c.error("the corners are different grids", list(nodes), "G1")
    return Plate(c.name, eid, c.integer(1, "PID", eid), nodes, c.line)


def read_cquad4(c: RawCard) -> Plate:
    """CQUAD4 EID PID G1 G2 G3 G4 THETA/MCID ZOFFS / blank TFLAG T1 T2 T3 T4.  ``THETA``/
    ``MCID`` (the material axes) is read and has no effect on an isotropic MAT1."""
    c.blank_after(14, "CQUAD4 has two lines")
    if c.text(8):
        raise c.error("field 2 of the CQUAD4 continuation is blank", c.text(8), "field 2")
    return _plate(c, 4, 6, 7, 9)


def read_ctria3(c: RawCard) -> Plate:
    """CTRIA3 EID PID G1 G2 G3 THETA/MCID ZOFFS / blank blank TFLAG T1 T2 T3."""
    c.blank_after(14, "CTRIA3 has two lines")
    for k in (7, 8, 9):
        if c.text(k):
            raise c.error("this field of CTRIA3 is blank", c.text(k), f"field {k + 2}")
    return _plate(c, 3, 5, 6, 10)


def read_pshell(c: RawCard) -> Pshell:
    """PSHELL PID MID1 T MID2 12I/T**3 MID3 TS/T NSM / Z1 Z2 MID4.  ``MID4`` (membrane-bending
    coupling) is refused.  ``MID3`` given makes the plate Reissner-Mindlin's (MITC4 / MITC3)
    with the transverse shear stiffness per width ``TS/T * T * G3`` (``G3`` MID3's shear
    modulus, ``TS/T`` 5/6 by default and positive); ``MID3`` blank, Kirchhoff's (DKQ / DKT),
    as Nastran's.  The fibre distances ``Z1``, ``Z2`` (stress recovery) are read and not
    used."""
    c.blank_after(11, "PSHELL has two lines")
    if c.text(10):
        raise c.error("MID4 is not supported (the shells have no membrane-bending coupling)",
                      c.text(10), "MID4")
    mid3 = c.integer(5, "MID3") if c.text(5) else None
    if mid3 is not None and mid3 <= 0:
        raise c.error("material ids are positive", mid3, "MID3")
    ts = c.real(6, "TS/T", 5.0 / 6.0)
    if not ts > 0:
        raise c.error("must be positive", c.text(6), "TS/T")
    c.real(8, "Z1", 0.0)
    c.real(9, "Z2", 0.0)
    mids = []
    for k, name in ((1, "MID1"), (3, "MID2")):
        mid = c.integer(k, name) if c.text(k) else None
        if mid is not None and mid <= 0:
            raise c.error("material ids are positive (plane strain, -1, is not supported)",
                          mid, name)
        mids.append(mid)
    if mids == [None, None]:
        raise c.error("MID1 and MID2 are both blank (no membrane and no bending)",
                      name="MID1")
    t = c.real(2, "T")
    bend = c.real(4, "12I/T**3", 1.0)
    nsm = c.real(7, "NSM", 0.0)
    for value, name in ((t, "T"), (bend, "12I/T**3")):
        if not value > 0:
            raise c.error("must be positive", value, name)
    if nsm < 0:
        raise c.error("must not be negative", nsm, "NSM")
    return Pshell(c.integer(0, "PID"), mids[0], t, mids[1], bend, nsm, c.line, mid3, ts)
