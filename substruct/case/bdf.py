"""Nastran bulk data files read into a :class:`BulkData`: grids in basic coordinates, elements
with their properties and materials, masses, springs, rigid elements, constraints and the
eigenvalue request, checked and cross-referenced.

**Why our own parser.** pyNastran is the field's reader, but its release on the registry
(1.4.1) cannot be used here: its metadata requires ``numpy<2`` and ``scipy<2``, so it cannot
be a dependency of a project on NumPy 2 (pip would refuse it or downgrade NumPy), and its
reader class does not even import under NumPy 2.4 (``pyNastran.bdf.bdf`` binds ``np.in1d`` at
import, removed from NumPy; measured with ``pip install --no-deps pyNastran==1.4.1``).  Its
per-card classes do import and parse single cards, but the file-level reader (continuations,
sections, includes) is in the modules that do not import (``pybdf`` also needs ``cpylog``).
Free, small and large field bulk data is a fixed, well-specified format
(:mod:`substruct.case.bdf_fields`), read here in a few hundred lines, and every card's fields
are read or refused by :mod:`substruct.case.bdf_cards`.

**Sets.** The case control's ``METHOD``, ``SPC`` and ``MPC`` choose the EIGRL, SPC/SPC1 and
MPC sets, as in Nastran.  A set in the file that the case control does not choose is refused
(it would be silently unused); a file of bulk data only uses all its SPC and MPC cards and its
one EIGRL.

**Semantics** (Nastran's): lumped mass unless ``PARAM,COUPMASS,1`` (a positive value);
``PARAM,WTMASS`` multiplies every mass (structure, non-structural and CONM2);
``PARAM,AUTOSPC,NO`` keeps coordinates without stiffness, which are otherwise removed
(:mod:`substruct.models.nastran`).  An unsupported card, case control command or parameter is
an error naming it, never skipped.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

from substruct.case.bdf_cards import (
    Bar, Conm2, Eigrl, Grid, Mat1, Mpc, Rbe2, Rbe3, Rod, Spring, read_bar, read_celas,
    read_conm2, read_cord2r, read_eigrl, read_grid, read_mat1, read_mpc, read_pbar,
    read_pbeam, read_pelas, read_prod, read_rbe2, read_rbe3, read_rod, read_spc, read_spc1,
)
from substruct.case.bdf_fields import BdfError, BdfText, RawCard, read_bdf_text, split_bdf
from substruct.case.fields import MAX_ELEMENTS, MAX_MATRIX_SIZE

__all__ = ["BulkData", "Section", "read_bulk", "parse_bulk", "CARDS", "PARAMS",
           "CASE_CONTROL"]

#: Bulk data cards read (docs/structures.md has what is read of each).
CARDS = ("GRID", "CORD2R", "CROD", "PROD", "CBAR", "PBAR", "CBEAM", "PBEAM", "CONM2",
         "CELAS1", "CELAS2", "PELAS", "RBE2", "RBE3", "MPC", "SPC", "SPC1", "MAT1", "EIGRL",
         "PARAM")
#: PARAM names read.
PARAMS = ("WTMASS", "COUPMASS", "AUTOSPC")
#: Case control commands read (titles and the displacement request have no effect: the mode
#: shapes are always written).
CASE_CONTROL = ("METHOD", "SPC", "MPC", "SUBCASE", "TITLE", "SUBTITLE", "LABEL", "ECHO",
                "DISPLACEMENT", "DISP", "VECTOR")
_EXECUTIVE = ("SOL", "ID", "TIME", "DIAG")
_ELEMENTS = ("CROD", "CBAR", "CBEAM", "CONM2", "CELAS1", "CELAS2", "RBE2", "RBE3")
_PROPERTIES = ("PROD", "PBAR", "PBEAM", "PELAS")


@dataclass(frozen=True)
class Section:
    """A line element's property with its material: ``A, I1, I2, J, nsm`` and ``E, G, rho``
    (``I1``, ``I2`` zero for a rod); ``shear``: CBEAM's shear factors ``K1 = K2 = 1``."""

    A: float
    I1: float
    I2: float
    J: float
    nsm: float
    mat: Mat1
    shear: bool


@dataclass
class BulkData:
    """A bulk data file read and cross-referenced.

    Attributes:
        grids: grid id -> position in basic coordinates.
        rods, bars: elements with their :class:`Section`.
        masses: CONM2 with offset and inertia in basic coordinates.
        springs: ``(id, k, (grid, component), (grid, component) or None)``, components 0-5.
        rbe2, rbe3, mpcs: rigid elements and the chosen MPC set.
        spc: grid id -> components held (0-5): the chosen SPC set and GRID PS.
        eigrl: the chosen EIGRL (``None`` if the file has none).
        wtmass, coupled, autospc: PARAM WTMASS, COUPMASS > 0, AUTOSPC.
    """

    source: str
    grids: dict[int, np.ndarray] = field(default_factory=dict)
    rods: list[tuple[Rod, Section]] = field(default_factory=list)
    bars: list[tuple[Bar, Section]] = field(default_factory=list)
    masses: list[Conm2] = field(default_factory=list)
    springs: list[tuple[int, float, tuple[int, int], tuple[int, int] | None]] = \
        field(default_factory=list)
    rbe2: list[Rbe2] = field(default_factory=list)
    rbe3: list[Rbe3] = field(default_factory=list)
    mpcs: list[Mpc] = field(default_factory=list)
    spc: dict[int, set[int]] = field(default_factory=dict)
    eigrl: Eigrl | None = None
    wtmass: float = 1.0
    coupled: bool = False
    autospc: bool = True
    title: str = ""


def _control(text: BdfText) -> dict[str, Any]:
    """The choices of the executive and case control (``METHOD``, ``SPC``, ``MPC``)."""
    src = text.source
    for line, t in text.executive:
        word = t.split()[0].split(",")[0]
        if word not in _EXECUTIVE:
            raise BdfError(src, f"executive control {word} is not supported (read: "
                           f"{', '.join(_EXECUTIVE)}, CEND)", t, line=line)
        if word == "SOL" and t.split()[1:2] not in (["103"], ["SEMODES"]):
            raise BdfError(src, "only normal modes, SOL 103, are run", t, line=line)
    chosen: dict[str, Any] = {}
    subcases = 0
    for line, t in text.case_control:
        m = re.match(r"^([A-Z]+)\s*(\([^)]*\))?\s*(?:=\s*(.*))?$", t)
        word = m.group(1) if m else t.split()[0]
        if not m or word not in CASE_CONTROL:
            raise BdfError(src, f"case control {word} is not supported (read: "
                           f"{', '.join(CASE_CONTROL)})", t, line=line)
        if word == "SUBCASE":
            subcases += 1
            if subcases > 1:
                raise BdfError(src, "one subcase is run", t, line=line)
        if word in ("METHOD", "SPC", "MPC"):
            value = (m.group(3) or "").strip()
            if not value.isdigit():
                raise BdfError(src, f"{word} names a set id", value, line=line, card=word)
            chosen[word] = int(value)
    chosen["case_control"] = bool(text.case_control or text.executive)
    return chosen


class _Reader:
    """Cards by kind, with their ids checked for duplicates."""

    def __init__(self, source: str):
        self.source = source
        self.seen: dict[str, dict[int, RawCard]] = {}

    def unique(self, space: str, ident: int, card: RawCard) -> None:
        table = self.seen.setdefault(space, {})
        if ident in table:
            first = table[ident]
            raise card.error(f"duplicate {space} id (also {first.name} on line {first.line})",
                             ident)
        table[ident] = card


def _coords(coords: dict[int, Any], src: str) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """Coordinate system id -> ``(origin, R)`` in basic, ``R`` rows the axes (CORD2R)."""
    done: dict[int, tuple[np.ndarray, np.ndarray]] = {0: (np.zeros(3), np.eye(3))}

    def resolve(cid: int, chain: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
        if cid in done:
            return done[cid]
        if cid not in coords:
            raise BdfError(src, "no such coordinate system", cid, coords[chain[-1]].line,
                           "CORD2R", chain[-1], "RID")
        if cid in chain:
            raise BdfError(src, "coordinate systems refer to each other in a loop",
                           list(chain), coords[cid].line, "CORD2R", cid, "RID")
        c = coords[cid]
        o, R = resolve(c.rid, chain + (cid,))
        a, b, p = (o + R.T @ v for v in (c.a, c.b, c.c))
        ez = b - a
        ey = np.cross(ez, p - a)
        if float(np.linalg.norm(ez)) == 0 or float(np.linalg.norm(ey)) <= \
                1e-12 * float(np.linalg.norm(ez)) * max(float(np.linalg.norm(p - a)), 1e-300):
            raise BdfError(src, "A, B and C do not define axes (coincident or collinear)",
                           line=c.line, card="CORD2R", ident=cid)
        ez, ey = ez / np.linalg.norm(ez), ey / np.linalg.norm(ey)
        done[cid] = (a, np.vstack([np.cross(ey, ez), ey, ez]))
        return done[cid]

    for cid in coords:
        resolve(cid, ())
    return done


def parse_bulk(text: str, source: str) -> BulkData:
    """Read bulk data text (see :func:`read_bulk`)."""
    split = split_bdf(text, source)
    control = _control(split)
    rd = _Reader(source)
    by: dict[str, list[Any]] = {}
    grids: dict[int, Grid] = {}
    coords: dict[int, Any] = {}
    props: dict[int, tuple[RawCard, tuple[Any, ...]]] = {}
    mats: dict[int, Mat1] = {}
    pelas: dict[int, float] = {}
    params: dict[str, tuple[RawCard, str]] = {}
    spc_sets: dict[int, list[tuple[RawCard, int, str]]] = {}
    spc1: list[tuple[RawCard, int, str, Any]] = []
    readers: dict[str, Callable[[RawCard], Any]] = {
        "CROD": read_rod, "CBAR": read_bar, "CBEAM": read_bar, "CONM2": read_conm2,
        "CELAS1": read_celas, "CELAS2": read_celas, "RBE2": read_rbe2, "RBE3": read_rbe3,
        "MPC": read_mpc, "EIGRL": read_eigrl}
    for card in split.cards:
        name = card.name
        if name not in CARDS:
            raise card.error(f"card {name} is not supported (read: {', '.join(CARDS)})")
        if name == "GRID":
            g = read_grid(card)
            rd.unique("grid", g.id, card)
            grids[g.id] = g
        elif name == "CORD2R":
            c = read_cord2r(card)
            rd.unique("coordinate system", c.id, card)
            coords[c.id] = c
        elif name in ("PROD", "PBAR", "PBEAM"):
            values: tuple[Any, ...] = {"PROD": read_prod, "PBAR": read_pbar,
                                       "PBEAM": read_pbeam}[name](card)
            rd.unique("property", int(values[0]), card)
            props[int(values[0])] = (card, values)
        elif name == "PELAS":
            for pid, k in read_pelas(card):
                rd.unique("property", pid, card)
                pelas[pid] = k
        elif name == "MAT1":
            m = read_mat1(card)
            rd.unique("material", m.id, card)
            mats[m.id] = m
        elif name == "SPC":
            sid, pairs = read_spc(card)
            spc_sets.setdefault(sid, []).extend((card, g, c) for g, c in pairs)
        elif name == "SPC1":
            sid, comp, gl = read_spc1(card)
            spc1.append((card, sid, comp, gl))
        elif name == "PARAM":
            key = card.text(0)
            if key not in PARAMS:
                raise card.error(f"PARAM {key} is not supported (read: {', '.join(PARAMS)})")
            if key in params:
                raise card.error(f"PARAM {key} given twice (also on line "
                                 f"{params[key][0].line})")
            card.blank_after(2, "PARAM has a name and a value")
            params[key] = (card, card.text(1))
        else:
            item = readers[name](card)
            if name in _ELEMENTS:
                rd.unique("element", item.id, card)
            elif name == "EIGRL":
                rd.unique("EIGRL", item.sid, card)
            by.setdefault(name, []).append((card, item))
    return _assemble(source, control, by, grids, coords, props, mats, pelas, params,
                     spc_sets, spc1)


def _param(params: dict[str, tuple[RawCard, str]], key: str, kind: str, default: Any) -> Any:
    if key not in params:
        return default
    card, text = params[key]
    if kind == "real":
        return card.real(1, "V1")
    if kind == "int":
        return card.integer(1, "V1")
    if text not in ("YES", "NO"):
        raise card.error("must be YES or NO", text, "V1")
    return text == "YES"


def _select(source: str, control: dict[str, Any], word: str, sets: set[int]) -> set[int]:
    """The set ids used: the one the case control chooses, or all of a bulk-only file."""
    if word in control:
        if control[word] not in sets:
            raise BdfError(source, f"the case control chooses {word} set {control[word]}, "
                           f"which the bulk data does not have", control[word], card=word)
        rest = sorted(sets - {control[word]})
        if rest:
            raise BdfError(source, f"{word} set {rest[0]} is not chosen by the case control "
                           f"({word} = {control[word]}) and would be unused", rest[0],
                           card=word)
        return {control[word]}
    if sets and control["case_control"]:
        raise BdfError(source, f"{word} sets {sorted(sets)} are not chosen by the case "
                       f"control (no {word} = ...) and would be unused", sorted(sets)[0],
                       card=word)
    return sets


def _assemble(source: str, control: dict[str, Any], by: dict[str, list[Any]],
              grids: dict[int, Grid], coords: dict[int, Any],
              props: dict[int, tuple[RawCard, tuple]], mats: dict[int, Mat1],
              pelas: dict[int, float], params: dict[str, tuple[RawCard, str]],
              spc_sets: dict[int, list[tuple[RawCard, int, str]]],
              spc1: list[tuple[RawCard, int, str, Any]]) -> BulkData:
    if not grids:
        raise BdfError(source, "the bulk data has no GRID")
    if 6 * len(grids) > MAX_MATRIX_SIZE:
        raise BdfError(source, f"{len(grids)} grids, {6 * len(grids)} coordinates; at most "
                       f"{MAX_MATRIX_SIZE} are accepted", len(grids), card="GRID")
    n_el = sum(len(v) for k, v in by.items() if k in _ELEMENTS)
    if n_el > MAX_ELEMENTS:
        raise BdfError(source, f"{n_el} elements; at most {MAX_ELEMENTS} are accepted", n_el)
    systems = _coords(coords, source)
    out = BulkData(source)
    for gr in grids.values():
        if gr.cp not in systems:
            raise BdfError(source, "no such coordinate system", gr.cp, gr.line, "GRID", gr.id,
                           "CP")
        o, R = systems[gr.cp]
        out.grids[gr.id] = o + R.T @ np.asarray(gr.x)
        if gr.ps:
            out.spc.setdefault(gr.id, set()).update(int(c) - 1 for c in gr.ps)

    def grid(card: RawCard, gid: int, name: str) -> int:
        if gid not in grids:
            raise card.error("no such GRID", gid, name)
        return gid

    def section(card: RawCard, pid: int, kinds: tuple[str, ...]) -> Section:
        if pid not in props or props[pid][0].name not in kinds:
            raise card.error(f"no {' or '.join(kinds)} of that id", pid, "PID")
        pcard, v = props[pid]
        if v[1] not in mats:
            raise pcard.error("no MAT1 of that id", v[1], "MID")
        if pcard.name == "PROD":
            return Section(v[2], 0.0, 0.0, v[3], v[4], mats[v[1]], False)
        sec = Section(v[2], v[3], v[4], v[5], v[6], mats[v[1]], pcard.name == "PBEAM")
        if sec.shear and sec.mat.G == 0 and sec.A > 0:
            raise pcard.error("CBEAM shear flexibility (K1 = K2 = 1) needs G > 0 in the "
                              "material", v[1], "MID")
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
            prop = ("PBAR",) if kind == "CBAR" else ("PBEAM",)
            out.bars.append((bar, section(card, bar.pid, prop)))
    for card, m in by.get("CONM2", []):
        grid(card, m.g, "G")
        if m.cid not in systems and m.cid != -1:
            raise card.error("no such coordinate system", m.cid, "CID")
        if m.cid == -1:
            x, inertia = m.x - out.grids[m.g], m.inertia
        else:
            _, R = systems[m.cid]
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
    mpc_sets = {m.sid for _, m in by.get("MPC", [])}
    use = _select(source, control, "MPC", mpc_sets)
    for card, m in by.get("MPC", []):
        if m.sid in use:
            for k, (g, _, _) in enumerate(m.terms):
                grid(card, g, f"G{k + 1}")
            out.mpcs.append(m)
    sets = set(spc_sets) | {sid for _, sid, _, _ in spc1}
    use = _select(source, control, "SPC", sets)
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
                           control["METHOD"], card="METHOD")
        out.eigrl = found[0]
    elif len(eigs) > 1:
        raise BdfError(source, "several EIGRL and no case control METHOD choosing one",
                       [e.sid for e in eigs], card="EIGRL")
    elif eigs:
        out.eigrl = eigs[0]
    out.wtmass = float(_param(params, "WTMASS", "real", 1.0))
    if not out.wtmass > 0:
        raise params["WTMASS"][0].error("must be positive", out.wtmass, "V1")
    out.coupled = _param(params, "COUPMASS", "int", -1) > 0
    out.autospc = _param(params, "AUTOSPC", "yes", True)
    return out


_CACHE: dict[tuple, BulkData] = {}


def read_bulk(path: str | Path, source: str | None = None) -> BulkData:
    """Read and cross-reference a bulk data file (module docstring); the last file read is
    kept, keyed by its path, size and modification time, so a case and its run read it once.

    Raises:
        BdfError: one line naming the file, the line, the card, its id and the field.
    """
    p = Path(path)
    src = str(path) if source is None else source
    try:
        st = p.stat()
        key: tuple = (str(p.resolve()), st.st_size, st.st_mtime_ns, src)
    except OSError:
        key = ()
    if key and key in _CACHE:
        return _CACHE[key]
    bulk = parse_bulk(read_bdf_text(p, src), src)
    _CACHE.clear()
    if key:
        _CACHE[key] = bulk
    return bulk
