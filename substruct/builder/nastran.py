"""Nastran models of a case (``type: nastran``, :mod:`substruct.case.nastran`): their
substructures (:mod:`substruct.models.nastran`), their rigid elements and MPC set as links
(:mod:`substruct.assembly.links`; an RBAR by :mod:`substruct.builder.nastran_rbar`), and
AUTOSPC once every link is known."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Collection, Mapping

import numpy as np
import scipy.sparse as sp
from scipy.linalg import block_diag

from substruct.assembly.links import (
    Link, LinkError, NodeRef, interpolation_link, mpc, rigid_link,
)
from substruct.builder.nastran_cd_links import has_frames, rbe2_cd_link, rbe3_cd_link
from substruct.builder.nastran_rbar import rbar_link
from substruct.case.bdf import BulkData
from substruct.case.bdf_fields import BdfError
from substruct.case.errors import CaseError
from substruct.case.nastran import BDF_SUFFIXES, NastranSpec
from substruct.models.nastran import nastran_matrices, nastran_substructure
from substruct.models.nastran_cd import grid_frames6
from substruct.substructure import Substructure

__all__ = ["build_nastran", "bulk_error", "bulk_links", "rigid_element_grids", "autospc"]


def bulk_error(case: Any, spec: NastranSpec, err: BdfError) -> CaseError:
    """A problem of a bulk data file found while the model is built, reported as those found
    when the case is read: ``<case file>: substructures.<name>.file: <file as written>: line
    <n>: <CARD> <id>: ...``.  For a bulk data file run directly (``substruct run MODEL.bdf``)
    the error itself, which names the file as given on the command line."""
    if Path(case.source).suffix.lower() in BDF_SUFFIXES:
        return err
    k = next(k for k, s in enumerate(case.substructures) if s is spec)
    return case.error(("substructures", k, "file"), str(err))


def build_nastran(case: Any, spec: NastranSpec) -> Substructure:
    """The substructure of a ``type: nastran`` item of ``case``, its SPC set and GRID PS
    removed (AUTOSPC comes later, :func:`autospc`).

    Raises:
        CaseError: an element that cannot be made, naming the case's field, then the file,
            line, card and id (:func:`bulk_error`).
    """
    try:
        return nastran_substructure(spec.name, nastran_matrices(spec.bulk), autospc=False)
    except BdfError as err:
        raise bulk_error(case, spec, err) from None


def bulk_links(name: str, bulk: BulkData, subs: Mapping[str, Substructure]
               ) -> list[tuple[Link, int, str, int]]:
    """The RBE2, RBE3, RBAR and MPC cards of ``bulk`` (substructure ``name``) as links, each
    with its card's ``(line, card name, id)`` (a link's name holds its card's name, so an RBE2
    and a CONM2 or CQUAD4 of one id, which Nastran keeps in separate tables, do not meet).

    RBE3: the groups of one card must use the same components (translations); a grid in two
    groups is refused.

    Raises:
        BdfError: a link that cannot be made (a component a grid does not have, an RBE3 whose
            grids do not determine a reference component), naming the card.
    """
    out: list[tuple[Link, int, str, int]] = []

    def node(g: int) -> NodeRef:
        return NodeRef(name, {"node": g})

    def fail(err: Exception, line: int, card: str, ident: int, field: str = "") -> BdfError:
        text = str(err).split(": ", 1)[-1] if str(err).startswith(name) else str(err)
        return BdfError(bulk.source, text.split(": ", 1)[-1], line=line, card=card,
                        ident=ident, name=field)

    for r in bulk.rbe2:
        if r.gn in r.gm:
            raise BdfError(bulk.source, "GN is also a dependent grid", r.gn, r.line, "RBE2",
                           r.id, "GM")
        try:
            if has_frames(bulk, (r.gn, *r.gm)):  # GRID CD (substruct.builder.nastran_cd_links)
                link = rbe2_cd_link(subs, name, bulk, r, f"{name}: RBE2 {r.id}")
            else:
                link = rigid_link(subs, node(r.gn), [node(g) for g in r.gm], r.cm,
                                  name=f"{name}: RBE2 {r.id}")
        except LinkError as err:
            raise fail(err, r.line, "RBE2", r.id) from None
        out.append((link, r.line, "RBE2", r.id))
    for r3 in bulk.rbe3:
        comps = {c for _, c, _ in r3.groups}
        if len(comps) > 1 or any(ch > "3" for ch in next(iter(comps))):
            raise BdfError(bulk.source, "the groups of an RBE3 use the same translational "
                           "components (rotations and mixed components are not supported)",
                           sorted(comps), r3.line, "RBE3", r3.id, "C1")
        grids = [g for _, _, gl in r3.groups for g in gl]
        weights = [w for w, _, gl in r3.groups for _ in gl]
        if len(set(grids)) != len(grids) or r3.ref in grids:
            raise BdfError(bulk.source, "a grid appears twice (or is the reference grid)",
                           grids, r3.line, "RBE3", r3.id, "G")
        try:
            if has_frames(bulk, (r3.ref, *grids)):
                link = rbe3_cd_link(subs, name, bulk, r3, grids, weights, next(iter(comps)),
                                    f"{name}: RBE3 {r3.id}")
            else:
                link = interpolation_link(subs, node(r3.ref), [node(g) for g in grids],
                                          weights, r3.refc, next(iter(comps)),
                                          name=f"{name}: RBE3 {r3.id}")
        except LinkError as err:
            raise fail(err, r3.line, "RBE3", r3.id, "REFC") from None
        out.append((link, r3.line, "RBE3", r3.id))
    for rb in bulk.rbar:
        try:
            frames = block_diag(grid_frames6(bulk.frames, rb.ga),
                                grid_frames6(bulk.frames, rb.gb)) \
                if has_frames(bulk, (rb.ga, rb.gb)) else None
            link = rbar_link(subs, name, rb, np.array([bulk.grids[rb.ga], bulk.grids[rb.gb]]),
                             f"{name}: RBAR {rb.id}", frames)
        except LinkError as err:
            raise fail(err, rb.line, "RBAR", rb.id, "CNA") from None
        out.append((link, rb.line, "RBAR", rb.id))
    for m in bulk.mpcs:
        try:
            link = mpc(subs, [(node(g), str(c + 1), a) for g, c, a in m.terms],
                       name=f"{name}: MPC {m.sid} (line {m.line})")
        except LinkError as err:
            raise fail(err, m.line, "MPC", m.sid) from None
        out.append((link, m.line, "MPC", m.sid))
    return out


def rigid_element_grids(bulk: BulkData) -> list[tuple[str, int | str, int, list[int]]]:
    """The grids of each RBE2, RBE3, RBAR and MPC card of ``bulk``, in card order: ``(card
    name, id, centre, others)``, the centre the RBE2's GN, the RBE3's REFGRID, the RBAR's GA
    or the MPC's first (dependent) grid, the others the RBE2's GMi, the RBAR's GB, the RBE3's
    Gi,j (group by group, as
    :func:`bulk_links` takes them) or the MPC's other grids, each once; an MPC's id is
    ``"<SID> (line <n>)"`` (cards of one set share the SID).  An MPC whose terms are all on
    one grid has nothing to draw and is left out."""
    out: list[tuple[str, int | str, int, list[int]]] = [("RBE2", r.id, r.gn, list(r.gm))
                                                        for r in bulk.rbe2]
    out += [("RBE3", r3.id, r3.ref, [g for _, _, gl in r3.groups for g in gl])
            for r3 in bulk.rbe3]
    out += [("RBAR", rb.id, rb.ga, [rb.gb]) for rb in bulk.rbar]
    for m in bulk.mpcs:
        first = m.terms[0][0]
        others = list(dict.fromkeys(g for g, _, _ in m.terms[1:] if g != first))
        if others:
            out.append(("MPC", f"{m.sid} (line {m.line})", first, others))
    return out


def autospc(sub: Substructure, used: Collection[int]) -> Substructure:
    """Nastran's AUTOSPC on ``sub``: the coordinates whose column of ``K`` is empty and that
    are not ``used`` (named by a link, an MPC or a point of the case) are removed
    (``q = T p``, ``T`` the columns of the identity kept).  Returns ``sub`` when none is."""
    K = sp.csc_array(sub.K)
    empty = np.asarray(abs(K).sum(axis=0)).ravel() == 0
    empty[np.asarray(list(used), dtype=np.int64)] = False
    if not empty.any():
        return sub
    keep = np.flatnonzero(~empty)
    T = sp.csr_array((np.ones(keep.size), (keep, np.arange(keep.size))),
                     shape=(sub.n_dof, keep.size))
    return sub.transformed(T, tuple(sub.dof_labels[k] for k in keep), sub.kind,
                           autospc=int(empty.sum()))


def used_columns(sub: Substructure, refs: Any) -> set[int]:
    """Columns of ``sub`` that the point references ``refs`` (``(substructure, where)``
    pairs) touch."""
    out: set[int] = set()
    for name, where in refs:
        if name == sub.name:
            out.update(int(j) for j in sub.row(where).indices)
    return out
