"""A Nastran file's cards cross-referenced into a :class:`~substruct.case.bdf.BulkData`:
grids placed in basic coordinates (coordinate systems resolved,
:mod:`substruct.case.bdf_coords`), elements joined to their
properties and materials, masses and springs to their grids, the chosen SPC, MPC and EIGRL
sets and the PARAM values applied.  A reference to something missing is an error naming the
card, its id and the field.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from substruct.case.bdf_cards import Bar, Conm2, GridCard, Mat1
from substruct.case.bdf_control import param, select_sets
from substruct.case.bdf_coords import CoordCard, CoordSystem, place_grids
from substruct.case.bdf_fields import BdfError, RawCard
from substruct.case.bdf_model import BulkData, BushSpring, BdfSection, ShellSection
from substruct.case.bdf_pcomp import COUPLING_TOLERANCE, Pcomp, laminate
from substruct.case.bdf_shells import Pshell
from substruct.case.bdf_solids import (
    SOLID_CORNERS,
    Psolid,
    check_solid_shapes,
    quadratic_integration_error,
)
from substruct.case.fields import MAX_ELEMENTS, MAX_MATRIX_SIZE

__all__ = ["ELEMENTS", "ELEMENT_TABLES", "Cards", "cross_reference"]

#: Cards that are elements, by id table.  Nastran keeps structural elements, mass elements
#: (CONM2) and rigid elements (RBE2, RBE3, RBAR) in separate tables, as pyNastran does
#: (``elements``, ``masses``, ``rigid_elements``): an id is unique within its table, and one
#: id may name an element of each (MSC Nastran runs a CONM2 100 beside a CBAR 100).
ELEMENT_TABLES: dict[str, str] = {
    **{name: "element" for name in ("CROD", "CBAR", "CBEAM", "CELAS1", "CELAS2", "CBUSH",
                                    "CQUAD4", "CTRIA3", "CHEXA", "CPENTA", "CTETRA")},
    "CONM2": "mass element",
    **{name: "rigid element" for name in ("RBE2", "RBE3", "RBAR")}}
#: Cards that are elements.
ELEMENTS = tuple(ELEMENT_TABLES)


@dataclass
class Cards:
    """The cards of a file as read, before cross-referencing: element-like cards ``by`` name
    (``(card, record)`` pairs), grids, coordinate systems, line properties, PSHELL, PBUSH,
    materials, PELAS, PARAM, SPC and SPC1 sets (``spc_first``: the first SPC or SPC1 card of
    each set, which a refusal names), and the ``control`` choices."""

    source: str
    control: dict[str, Any]
    by: dict[str, list[Any]] = field(default_factory=dict)
    grids: dict[int, GridCard] = field(default_factory=dict)
    coords: dict[int, CoordCard] = field(default_factory=dict)
    props: dict[int, tuple[RawCard, tuple[Any, ...]]] = field(default_factory=dict)
    pshell: dict[int, tuple[RawCard, Pshell]] = field(default_factory=dict)
    pbush: dict[int, tuple[RawCard, tuple[float, ...]]] = field(default_factory=dict)
    psolid: dict[int, tuple[RawCard, Psolid]] = field(default_factory=dict)
    pcomp: dict[int, tuple[RawCard, Pcomp]] = field(default_factory=dict)
    spcadd: dict[int, tuple[RawCard, list[int]]] = field(default_factory=dict)
    mats: dict[int, Mat1] = field(default_factory=dict)
    pelas: dict[int, float] = field(default_factory=dict)
    params: dict[str, tuple[RawCard, str]] = field(default_factory=dict)
    spc_sets: dict[int, list[tuple[RawCard, int, str]]] = field(default_factory=dict)
    spc1: list[tuple[RawCard, int, str, Any]] = field(default_factory=list)
    spc_first: dict[int, RawCard] = field(default_factory=dict)



def cross_reference(cards: Cards) -> BulkData:
    """The :class:`BulkData` of ``cards`` (module docstring).

    Raises:
        BdfError: a missing grid, property, material or coordinate system, a set the case
            control does not choose, the size limits.
    """
    source, control, by, grids = cards.source, cards.control, cards.by, cards.grids
    props, mats, pelas, params = cards.props, cards.mats, cards.pelas, cards.params
    spc_sets, spc1 = cards.spc_sets, cards.spc1
    if not grids:
        raise BdfError(source, "the bulk data has no GRID")
    if 6 * len(grids) > MAX_MATRIX_SIZE:
        raise BdfError(source, f"{len(grids)} grids, {6 * len(grids)} coordinates; at most "
                       f"{MAX_MATRIX_SIZE} are accepted", len(grids), card="GRID")
    n_el = sum(len(v) for k, v in by.items() if k in ELEMENTS)
    if n_el > MAX_ELEMENTS:
        raise BdfError(source, f"{n_el} elements; at most {MAX_ELEMENTS} are accepted", n_el)
    systems, where = place_grids(cards.coords, grids, source)
    out = BulkData(source)
    for gr in grids.values():
        out.grids[gr.id] = where[gr.id]
        if gr.cd != 0:
            if gr.cd not in systems:
                raise BdfError(source, "no such coordinate system", gr.cd, gr.line, "GRID",
                               gr.id, "CD")
            frame = systems[gr.cd].frame(where[gr.id])
            if frame is None:
                raise BdfError(source, "the grid is on the axis of its cylindrical or "
                               "spherical CD system, where the directions are undefined",
                               gr.cd, gr.line, "GRID", gr.id, "CD")
            out.frames[gr.id] = frame
        if gr.ps:
            out.spc.setdefault(gr.id, set()).update(int(c) - 1 for c in gr.ps)

    def grid(card: RawCard, gid: int, name: str) -> int:
        if gid not in grids:
            raise card.error("no such GRID", gid, name)
        return gid

    def section(card: RawCard, pid: int, kinds: tuple[str, ...]) -> BdfSection:
        if pid not in props or props[pid][0].name not in kinds:
            raise card.error(f"no {' or '.join(kinds)} of that id", pid, "PID")
        pcard, v = props[pid]
        if v[1] not in mats:
            raise pcard.error("no MAT1 of that id", v[1], "MID")
        if pcard.name == "PROD":
            return BdfSection(v[2], 0.0, 0.0, v[3], v[4], mats[v[1]], False)
        shear = pcard.name in ("PBEAM", "PBARL", "PBEAML")
        kshear = (0.9, 0.9) if pcard.name in ("PBARL", "PBEAML") else (1.0, 1.0)  # ROD's
        if pcard.name == "PBEAM":
            kshear = (v[7], v[8])
        sec = BdfSection(v[2], v[3], v[4], v[5], v[6], mats[v[1]], shear, kshear,
                         card.name == "CBEAM")
        if sec.shear and max(kshear) > 0 and sec.mat.G == 0 and sec.A > 0:
            raise pcard.error(f"shear flexibility (K1, K2 = {kshear[0]}, {kshear[1]}) needs "
                              "G > 0 in the material", v[1], "MID")
        return sec

    for card, rod in by.get("CROD", []):
        for k, name in enumerate(("G1", "G2")):
            grid(card, rod.nodes[k], name)
        out.rods.append((rod, section(card, rod.pid, ("PROD",))))
    for kind in ("CBAR", "CBEAM"):
        for card, bar in by.get(kind, []):
            for k, name in enumerate(("GA", "GB")):
                grid(card, bar.nodes[k], name)
            if bar.g0 is not None:
                grid(card, bar.g0, "G0")
            prop = ("PBAR", "PBARL") if kind == "CBAR" else ("PBEAM", "PBEAML")
            out.bars.append((_bar_in_basic(bar, out.frames), section(card, bar.pid, prop)))
    for card, m in by.get("CONM2", []):
        grid(card, m.g, "G")
        if m.cid not in systems and m.cid != -1:
            raise card.error("no such coordinate system", m.cid, "CID")
        if m.cid == -1:
            x, inertia = m.x - out.grids[m.g], m.inertia
        else:
            R = _rectangular(card, systems[m.cid], m.cid, "CID")
            x, inertia = R.T @ m.x, R.T @ m.inertia @ R
        out.masses.append(Conm2(m.id, m.g, 0, m.m, x, inertia, m.line))
    for card, s in by.get("CELAS1", []) + by.get("CELAS2", []):
        grid(card, s.a[0], "G1")
        if s.b is not None:
            grid(card, s.b[0], "G2")
        if s.pid is not None and s.pid not in pelas:
            raise card.error("no PELAS of that id", s.pid, "PID")
        stiff = pelas[s.pid] if s.pid is not None else s.k
        assert stiff is not None
        out.springs.append((s.id, stiff, s.a, s.b))
    for kind in ("CQUAD4", "CTRIA3"):
        for card, plate in by.get(kind, []):
            for k, g in enumerate(plate.nodes):
                grid(card, g, f"G{k + 1}")
            out.plates.append((plate, _shell_section(card, plate.pid, cards)))
    for kind in ("CHEXA", "CPENTA", "CTETRA"):
        for card, cell in by.get(kind, []):
            for k, g in enumerate(cell.nodes):
                grid(card, g, f"G{k + 1}")
            mat = _solid_material(card, cell.pid, cards, systems)
            pcard, psolid = cards.psolid[cell.pid]
            wrong = quadratic_integration_error(cell, psolid)
            if wrong is not None:
                raise pcard.error(wrong[0], wrong[1], wrong[2])
            bubble = cell.kind in ("CHEXA", "CPENTA") and psolid.bubble and \
                len(cell.nodes) == SOLID_CORNERS[cell.kind][0]
            out.solids.append((replace(cell, bubble=bubble), mat))
    for card, b in by.get("CBUSH", []):
        grid(card, b.ga, "GA")
        if b.gb is not None:
            grid(card, b.gb, "GB")
        if b.pid not in cards.pbush:
            raise card.error("no PBUSH of that id", b.pid, "PID")
        axes = v = None
        if b.cid is not None:
            if b.cid not in systems:
                raise card.error("no such coordinate system", b.cid, "CID")
            axes = _rectangular(card, systems[b.cid], b.cid, "CID")
        else:
            assert b.gb is not None
            v = out.frames.get(b.ga, np.eye(3)) @ np.asarray(b.v) if b.g0 is None else \
                out.grids[grid(card, b.g0, "GO")] - out.grids[b.ga]
            if np.linalg.norm(out.grids[b.gb] - out.grids[b.ga]) == 0:
                raise card.error("GA and GB are at the same place: give CID for the axes",
                                 b.gb, "GB")
        out.bushes.append(BushSpring(b, cards.pbush[b.pid][1], axes, v))
    for card, r in by.get("RBE2", []):
        grid(card, r.gn, "GN")
        for g in r.gm:
            grid(card, g, "GM")
        out.rbe2.append(r)
    for card, r3 in by.get("RBE3", []):
        grid(card, r3.ref, "REFGRID")
        for _, _, gl in r3.groups:
            for g in gl:
                grid(card, g, "G")
        out.rbe3.append(r3)
    for card, rb in by.get("RBAR", []):
        grid(card, rb.ga, "GA")
        grid(card, rb.gb, "GB")
        out.rbar.append(rb)
    mpc_sets: dict[int, RawCard] = {}
    for card, m in by.get("MPC", []):
        mpc_sets.setdefault(m.sid, card)
    use = select_sets(source, control, "MPC", mpc_sets)
    for card, m in by.get("MPC", []):
        if m.sid in use:
            for k, (g, _, _) in enumerate(m.terms):
                grid(card, g, f"G{k + 1}")
            out.mpcs.append(m)
    use = _spc_sets(cards)
    for sid in use:
        for card, gid, comp in spc_sets.get(sid, []):
            out.spc.setdefault(grid(card, gid, "G1"), set()).update(int(c) - 1 for c in comp)
    for card, sid, comp, gl in spc1:
        if sid not in use:
            continue
        if isinstance(gl, range):
            ids = [gid for gid in grids if gid in gl]
        else:
            ids = [grid(card, gid, "G") for gid in gl]
        for gid in ids:
            out.spc.setdefault(gid, set()).update(int(c) - 1 for c in comp)
    eigs = [e for _, e in by.get("EIGRL", [])]
    if "METHOD" in control:
        found = [e for e in eigs if e.sid == control["METHOD"]]
        if not found:
            raise BdfError(source, "the case control's METHOD names no EIGRL of the bulk data",
                           control["METHOD"], line=control["lines"]["METHOD"], card="METHOD")
        out.eigrl = found[0]
    elif len(eigs) > 1:
        raise by["EIGRL"][1][0].error("several EIGRL and no case control METHOD choosing one",
                                      [e.sid for e in eigs])
    elif eigs:
        out.eigrl = eigs[0]
    out.wtmass = float(param(params, "WTMASS", "real", 1.0))
    if not out.wtmass > 0:
        raise params["WTMASS"][0].error("must be positive", out.wtmass, "V1")
    out.coupled = param(params, "COUPMASS", "int", -1) > 0
    check_solid_shapes([cell for cell, _ in out.solids], out.grids, source)
    quadratic = [cell for cell, _ in out.solids
                 if len(cell.nodes) > SOLID_CORNERS[cell.kind][0]]
    if quadratic and not out.coupled:
        q = quadratic[0]
        raise BdfError(source, f"the {len(q.nodes)}-grid {q.kind} needs coupled mass "
                       "(PARAM,COUPMASS,1): Nastran's lumped mass of quadratic solids is not "
                       "reproduced", "no COUPMASS", line=q.line, card=q.kind, ident=q.id)
    out.autospc = param(params, "AUTOSPC", "yes", True)
    if "AUTOSPC" in control:  # the case control's AUTOSPC = YES/NO, the same meaning
        if "AUTOSPC" in params and out.autospc != control["AUTOSPC"]:
            raise params["AUTOSPC"][0].error(
                f"PARAM,AUTOSPC and the case control's AUTOSPC = "
                f"{'YES' if control['AUTOSPC'] else 'NO'} (line "
                f"{control['lines']['AUTOSPC']}) disagree", params["AUTOSPC"][1], "V1")
        out.autospc = control["AUTOSPC"]
    return out


def _bar_in_basic(bar: Bar, frames: dict[int, np.ndarray]) -> Bar:
    """``bar`` with its orientation vector and offsets in basic: OFFT's ``G`` puts them in
    the displacement system (GRID CD) of GA (the vector, the offset at A) and GB (the offset
    at B), :math:`w_{basic} = F w`."""
    if not frames or not (bar.nodes[0] in frames or bar.nodes[1] in frames):
        return bar
    ga, gb = (frames.get(g, np.eye(3)) for g in bar.nodes)

    def turn(F: np.ndarray, w: Any, letter: str) -> Any:
        return w if w is None or letter == "B" else tuple(float(a) for a in F @ np.asarray(w))

    return replace(bar, v=turn(ga, bar.v, bar.offt[0]), wa=turn(ga, bar.wa, bar.offt[1]),
                   wb=turn(gb, bar.wb, bar.offt[2]))


def _rectangular(card: RawCard, system: CoordSystem, cid: int, name: str) -> np.ndarray:
    """The axes (rows, basic) of a rectangular system; a cylindrical or spherical one is
    refused (offsets and axes in them are not supported)."""
    if system.kind != "R":
        raise card.error("the system must be rectangular (offsets and axes in cylindrical or "
                         "spherical systems are not supported)", cid, name)
    return system.axes


def _spc_sets(cards: Cards) -> set[int]:
    """The SPC/SPC1 set ids in use: the case control's ``SPC`` choice (an SPCADD's sets when
    it names one), or every set of a file of bulk data only."""
    first = dict(cards.spc_first)
    sets = set(first)
    for sid, (card, members) in cards.spcadd.items():
        if sid in sets:
            raise card.error("an SPCADD id must differ from the SPC and SPC1 set ids", sid,
                             "SID")
        for n, m in enumerate(members):
            if m not in sets:
                raise card.error("no SPC or SPC1 set of that id", m, f"S{n + 1}")
    chosen = cards.control.get("SPC")
    if chosen in cards.spcadd:
        card, members = cards.spcadd[chosen]
        rest = sorted((sets | set(cards.spcadd)) - set(members) - {chosen})
        first.update({sid: c for sid, (c, _) in cards.spcadd.items()})
        if rest:
            raise first[rest[0]].error(f"SPC set {rest[0]} is not in the chosen SPCADD "
                                       f"{chosen} and would be unused", rest[0])
        return set(members)
    if cards.spcadd and not cards.control["case_control"]:  # bulk data only: every set
        return sets
    first.update({sid: c for sid, (c, _) in cards.spcadd.items()})
    return select_sets(cards.source, cards.control, "SPC", first)


def _shell_material(pcard: RawCard, mid: int, name: str, cards: Cards) -> Mat1:
    if mid not in cards.mats:
        raise pcard.error("no MAT1 of that id", mid, name)
    mat = cards.mats[mid]
    if not (mat.E > 0 and mat.G > 0 and -1 < mat.nu < 0.5):
        raise pcard.error("a shell's MAT1 needs E > 0, G > 0 and -1 < NU < 0.5", mid, name)
    return mat


def _pcomp_section(pid: int, cards: Cards) -> ShellSection:
    """The equivalent PSHELL of a PCOMP (:mod:`substruct.case.bdf_pcomp`)."""
    pcard, p = cards.pcomp[pid]
    mats = [_shell_material(pcard, mid, f"MID{(i - 8) // 4 + 1}", cards)
            for mid, _, i in p.plies]
    T, (em, num), (eb, nub), rho, coupling, shear = laminate(p, mats)
    if coupling > COUPLING_TOLERANCE:
        raise pcard.error(f"the laminate couples membrane and bending (|B| = {coupling:.3g} "
                          "A11 T: an offset Z0 or an unsymmetric stack), which is not "
                          "supported", pcard.text(1) or "blank", "Z0")
    membrane = Mat1(pid, em, em / (2 * (1 + num)), rho, pcard.line)
    bending = Mat1(pid, eb, eb / (2 * (1 + nub)), rho, pcard.line)
    return ShellSection(T, membrane, bending, 1.0, p.nsm, shear)


def _shell_section(card: RawCard, pid: int, cards: Cards) -> ShellSection:
    if pid in cards.pcomp:
        return _pcomp_section(pid, cards)
    if pid not in cards.pshell:
        raise card.error("no PSHELL or PCOMP of that id", pid, "PID")
    pcard, p = cards.pshell[pid]
    if p.mid3 is not None and p.mid3 not in cards.mats:
        raise pcard.error("no MAT1 of that id", p.mid3, "MID3")
    found = []
    for mid, name in ((p.mid1, "MID1"), (p.mid2, "MID2")):
        if mid is not None and mid not in cards.mats:
            raise pcard.error("no MAT1 of that id", mid, name)
        mat = cards.mats[mid] if mid is not None else None
        if mat is not None and not (mat.E > 0 and mat.G > 0 and
                                    -1 < mat.nu < 0.5):
            raise pcard.error("a shell's MAT1 needs E > 0, G > 0 and -1 < NU < 0.5", mid, name)
        found.append(mat)
    shear = None
    if p.mid3 is not None:
        g3 = cards.mats[p.mid3].G
        if not g3 > 0:
            raise pcard.error("the transverse shear material (MID3) needs G > 0", p.mid3,
                              "MID3")
        shear = p.ts * p.t * g3
    return ShellSection(p.t, found[0], found[1], p.bend, p.nsm, shear)


def _solid_material(card: RawCard, pid: int, cards: Cards, systems: dict) -> Mat1:
    if pid not in cards.psolid:
        raise card.error("no PSOLID of that id", pid, "PID")
    pcard, p = cards.psolid[pid]
    if p.cordm not in systems and p.cordm != -1:
        raise pcard.error("no such coordinate system", p.cordm, "CORDM")
    if p.mid not in cards.mats:
        raise pcard.error("no MAT1 of that id", p.mid, "MID")
    mat = cards.mats[p.mid]
    if not (mat.E > 0 and mat.G > 0 and -1 < mat.nu < 0.5):
        raise pcard.error("a solid's MAT1 needs E > 0, G > 0 and -1 < NU < 0.5", p.mid, "MID")
    return mat
