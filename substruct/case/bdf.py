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

The reading is in steps, one module each: the text and its ``INCLUDE`` files
(:mod:`substruct.case.bdf_include`), the cards' fields (:mod:`substruct.case.bdf_fields`),
each card's record (:mod:`substruct.case.bdf_cards`, :mod:`substruct.case.bdf_shells`,
:mod:`substruct.case.bdf_springs`, :mod:`substruct.case.bdf_constraints`,
:mod:`substruct.case.bdf_control`), and the cross-reference (:mod:`substruct.case.bdf_xref`)
into the :class:`~substruct.case.bdf_model.BulkData` of the model.

**Semantics** (Nastran's): lumped mass unless ``PARAM,COUPMASS,1`` (a positive value);
``PARAM,WTMASS`` multiplies every mass (structure, non-structural and CONM2);
``PARAM,AUTOSPC,NO`` (or the case control's ``AUTOSPC = NO``) keeps coordinates without
stiffness, which are otherwise removed (:mod:`substruct.models.nastran`).  Element ids are
unique within Nastran's three id tables, structural, mass (CONM2) and rigid elements (RBE2,
RBE3, RBAR), and may repeat across them.  An unsupported card, case control command or
parameter is an error naming it, never skipped.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable

from substruct.case.bdf_cards import (
    read_bar, read_conm2, read_grid, read_mat1, read_pbar, read_pbarl, read_prod,
    read_rod,
)
from substruct.case.bdf_constraints import read_mpc, read_rbar, read_rbe2, read_rbe3, \
    read_spc, read_spc1, read_spcadd
from substruct.case.bdf_control import CASE_CONTROL, OUTPUT_PARAMS, PARAM_TABLE, PARAMS, \
    read_control, read_eigrl, read_static_load, read_uset
from substruct.case.bdf_coords import COORD_CARDS, read_cord1, read_cord2
from substruct.case.bdf_fields import RawCard, split_bdf
from substruct.case.bdf_include import bdf_lines
from substruct.case.bdf_model import BulkData, BdfSection
from substruct.case.bdf_pbeam import read_pbeam
from substruct.case.bdf_pcomp import read_pcomp
from substruct.case.bdf_shells import read_cquad4, read_ctria3, read_pshell
from substruct.case.bdf_solids import read_psolid, read_solid
from substruct.case.bdf_springs import read_cbush, read_celas, read_pbush, read_pelas
from substruct.case.bdf_xref import ELEMENT_TABLES, Cards, cross_reference

__all__ = ["BulkData", "BdfSection", "read_bulk", "parse_bulk", "CARDS", "PARAMS",
           "CASE_CONTROL"]

#: Bulk data cards read (docs/structures.md has what is read of each).
CARDS = ("GRID", *COORD_CARDS, "CROD", "PROD", "CBAR", "PBAR", "PBARL", "CBEAM", "PBEAM",
         "PBEAML", "USET", "CQUAD4", "CTRIA3", "PSHELL", "PCOMP", "CHEXA", "CPENTA", "CTETRA",
         "PSOLID", "CONM2", "CELAS1", "CELAS2", "PELAS", "CBUSH", "PBUSH", "RBE2", "RBE3",
         "RBAR", "MPC", "SPC", "SPC1", "SPCADD", "MAT1", "EIGRL", "PARAM", "LOAD", "FORCE")


#: Why some PARAMs that change the results are refused (the message of the others lists
#: those read).
_REFUSED = {"G": ": the structural damping G is not used by normal modes and the undamped "
                 "responses of a substructure (damp in the case file's analysis)"}


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


def parse_bulk(text: str | list[tuple[str, int, str]], source: str) -> BulkData:
    """Read bulk data text, or the lines ``(file, line number, text)`` of a file and its
    includes (see :func:`read_bulk`)."""
    split = split_bdf(text, source)
    rd = _Reader(source)
    cards = Cards(source, read_control(split))
    by, grids, coords, props, mats = cards.by, cards.grids, cards.coords, cards.props, \
        cards.mats
    pelas, params, spc_sets, spc1 = cards.pelas, cards.params, cards.spc_sets, cards.spc1
    readers: dict[str, Callable[[RawCard], Any]] = {
        "CROD": read_rod, "CBAR": read_bar, "CBEAM": read_bar, "CONM2": read_conm2,
        "CELAS1": read_celas, "CELAS2": read_celas, "CBUSH": read_cbush,
        "CQUAD4": read_cquad4, "CTRIA3": read_ctria3, "RBE2": read_rbe2, "RBE3": read_rbe3,
        "RBAR": read_rbar, "MPC": read_mpc, "EIGRL": read_eigrl, "CHEXA": read_solid, "CPENTA": read_solid,
        "CTETRA": read_solid}
    for card in split.cards:
        name = card.name
        if name not in CARDS:
            raise card.error(f"card {name} is not supported (read: {', '.join(CARDS)})")
        if name == "GRID":
            g = read_grid(card)
            rd.unique("grid", g.id, card)
            grids[g.id] = g
        elif name in COORD_CARDS:
            for c in [read_cord2(card)] if name[4] == "2" else read_cord1(card):
                rd.unique("coordinate system", c.id, card)
                coords[c.id] = c
        elif name in ("PROD", "PBAR", "PBEAM", "PBARL", "PBEAML"):
            values: tuple[Any, ...] = {"PROD": read_prod, "PBAR": read_pbar,
                                       "PBEAM": read_pbeam, "PBARL": read_pbarl,
                                       "PBEAML": read_pbarl}[name](card)
            rd.unique("property", int(values[0]), card)
            props[int(values[0])] = (card, values)
        elif name == "PSHELL":
            ps = read_pshell(card)
            rd.unique("property", ps.id, card)
            cards.pshell[ps.id] = (card, ps)
        elif name == "PCOMP":
            pc = read_pcomp(card)
            rd.unique("property", pc.id, card)
            cards.pcomp[pc.id] = (card, pc)
        elif name == "SPCADD":
            sid, members = read_spcadd(card)
            rd.unique("SPCADD", sid, card)
            cards.spcadd[sid] = (card, members)
        elif name in ("LOAD", "FORCE"):  # static loads: checked, no effect on the modes
            read_static_load(card)
        elif name == "PSOLID":
            pso = read_psolid(card)
            rd.unique("property", pso.id, card)
            cards.psolid[pso.id] = (card, pso)
        elif name == "PBUSH":
            pid, kvals = read_pbush(card)
            rd.unique("property", pid, card)
            cards.pbush[pid] = (card, kvals)
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
            cards.spc_first.setdefault(sid, card)
        elif name == "SPC1":
            sid, comp, gl = read_spc1(card)
            spc1.append((card, sid, comp, gl))
            cards.spc_first.setdefault(sid, card)
        elif name == "USET":  # a user set for output or DMAP: read, no effect on the modes
            read_uset(card)
        elif name == "PARAM":
            key = card.text(0)
            if key in OUTPUT_PARAMS:  # printing and output: read, no effect on the modes
                card.blank_after(2, "PARAM has a name and a value")
                continue
            if key not in PARAMS:
                raise card.error(f"PARAM {key} is not supported{_REFUSED.get(key, '')} "
                                 f"(read: {', '.join(PARAM_TABLE)})")
            if key in params:
                raise card.error(f"PARAM {key} given twice (also on line "
                                 f"{params[key][0].line})")
            card.blank_after(2, "PARAM has a name and a value")
            params[key] = (card, card.text(1))
        else:
            item = readers[name](card)
            if name in ELEMENT_TABLES:  # one id table each: elements, masses, rigid ones
                rd.unique(ELEMENT_TABLES[name], item.id, card)
            elif name == "EIGRL":
                rd.unique("EIGRL", item.sid, card)
            by.setdefault(name, []).append((card, item))
    if "K6ROT" in params and (by.get("CQUAD4") or by.get("CTRIA3")):
        raise params["K6ROT"][0].error("K6ROT (the drilling stiffness of CQUAD4 and CTRIA3) is "
                                       "not supported in a model with shells", "K6ROT")
    return cross_reference(cards)


_CACHE: dict[tuple, BulkData] = {}


def read_bulk(path: str | Path, source: str | None = None) -> BulkData:
    """Read and cross-reference a bulk data file and the files it includes (module
    docstring); the last model read is kept, keyed by the paths, sizes and modification times
    of its files, so a case and its run read it once.

    Raises:
        BdfError: one line naming the file, the line, the card, its id and the field.
    """
    src = str(path) if source is None else source
    lines, files = bdf_lines(Path(path), src)
    key: tuple = (src,) + tuple(files)
    if key in _CACHE:
        return _CACHE[key]
    bulk = parse_bulk(lines, src)
    _CACHE.clear()
    _CACHE[key] = bulk
    return bulk
