r"""Rigid elements (RBE2, RBE3, RBAR) of Nastran whose grids have a displacement coordinate
system (GRID ``CD``, :mod:`substruct.models.nastran_cd`).

Each element relates the six basic coordinates of a dependent grid ``d`` to the basic
coordinates ``v`` of its independent grids, :math:`u_{d,basic} = G\, v_{basic}` (RBE2: the
rigid motion of ``GN``, :math:`G = [I, -[r]_\times; 0, I]`, :math:`r = x_d - x_{GN}`; RBE3:
the weighted fit :func:`~substruct.assembly.links.interpolation_matrix` of the grids'
translations).  The coordinates are in the grids' ``CD`` systems, :math:`u_{basic} = F u`
(``F`` block diagonal of the grids' frames), so the rows are

.. math::  u_{d,c} - \bigl(F_d^T\, G\, F_v\bigr)_{c,:}\, v = 0, \qquad
           c \in \text{the dependent components (in } d\text{'s CD)},

each one multi-point constraint whose first term, ``d``'s component ``c``, is dependent (as
the rows of :func:`~substruct.assembly.links.rigid_link` make it).  The independent
components of an RBE3 (``Ci``) are in their grids' ``CD``: with a ``CD`` at such a grid they
must be all three translations (``123``, which the fit treats alike in any axes); others are
refused.
"""

from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np
from scipy.linalg import block_diag

from substruct.assembly.links import Link, LinkError, NodeRef, interpolation_matrix, mpc
from substruct.builder.nastran_rbar import rbar_rows
from substruct.case.bdf import BulkData
from substruct.case.bdf_constraints import Rbe2, Rbe3
from substruct.models.nastran_cd import grid_frames6
from substruct.substructure import Substructure

__all__ = ["has_frames", "relation_link", "rbe2_cd_link", "rbe3_cd_link"]

#: Coefficients below this fraction of a row's largest are dropped (rounding of ``F^T G F``).
DROP = 1e-14


def has_frames(bulk: BulkData, grids: Sequence[int]) -> bool:
    """Whether any of ``grids`` has a ``CD`` system."""
    return any(g in bulk.frames for g in grids)


def relation_link(subs: Mapping[str, Substructure], name: str, link_name: str, kind: str,
                  dep: int, comps: str, indep: Sequence[tuple[int, Sequence[int]]],
                  G: np.ndarray, frames: Mapping[int, np.ndarray]) -> Link:
    """The rows of :math:`u_{dep,basic} = G v_{basic}` (module docstring) on the components
    ``comps`` (digits, ``dep``'s CD) of grid ``dep``; ``indep``: ``(grid, components 0-5)``
    in the order of ``G``'s columns (basic), each grid's components all translations or all
    six."""
    blocks = []
    for g, own in indep:
        F6 = grid_frames6(frames, g)
        blocks.append(F6[np.ix_(list(own), list(own))])
    Gcd = grid_frames6(frames, dep).T @ G @ block_diag(*blocks)
    cols = [(g, k) for g, own in indep for k in own]
    node = {g: NodeRef(name, {"node": g}) for g in [dep] + [g for g, _ in indep]}
    parts = []
    for ch in comps:
        c = int(ch) - 1
        row = Gcd[c]
        top = max(float(np.abs(row).max(initial=0.0)), 1.0)
        terms = [(node[dep], ch, 1.0)]
        terms += [(node[g], str(k + 1), -float(a)) for (g, k), a in zip(cols, row)
                  if abs(a) > DROP * top]
        parts.append(mpc(subs, terms, name=link_name))
    return Link.joined(link_name, kind, parts)


def rbe2_cd_link(subs: Mapping[str, Substructure], name: str, bulk: BulkData, r: Rbe2,
                 link_name: str) -> Link:
    """An RBE2 with grids in ``CD`` systems: each ``GMi``'s components ``CM`` (its CD) move
    with ``GN``'s rigid motion."""
    parts = []
    for g in r.gm:
        G = rbar_rows(bulk.grids[g] - bulk.grids[r.gn])[6:]
        parts.append(relation_link(subs, name, link_name, "rigid", g, r.cm,
                                   [(r.gn, range(6))], G, bulk.frames))
    return Link.joined(link_name, "rigid", parts)


def rbe3_cd_link(subs: Mapping[str, Substructure], name: str, bulk: BulkData, r3: Rbe3,
                 grids: Sequence[int], weights: Sequence[float], comps: str,
                 link_name: str) -> Link:
    """An RBE3 with grids in ``CD`` systems: ``REFC`` (the reference grid's CD) from the
    weighted fit of the grids' components ``comps`` (module docstring).

    Raises:
        LinkError: components other than ``123`` at a grid with a CD system, or reference
            components the grids do not determine.
    """
    own = [int(ch) - 1 for ch in comps]
    if own != [0, 1, 2] and any(g in bulk.frames for g in grids):
        raise LinkError(f"{link_name}: components {comps} at grids with a CD system are not "
                        "supported (all three translations, 123, are)")
    offsets = np.array([bulk.grids[g] - bulk.grids[r3.ref] for g in grids])
    G = interpolation_matrix(offsets, np.asarray(weights, dtype=float), own,
                             [int(ch) - 1 for ch in r3.refc], f"{link_name}: ",
                             f" {name}@{r3.ref}")
    return relation_link(subs, name, link_name, "interpolation", r3.ref, r3.refc,
                         [(g, own) for g in grids], G, bulk.frames)
