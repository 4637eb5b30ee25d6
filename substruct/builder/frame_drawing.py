r"""How frames are drawn: beams as curves that bend with the end rotations, shells as their
faces, links as spiders.

**Beams.** Each beam element ``i -> j`` (unit axis :math:`e`, length :math:`L`) is drawn as
:data:`BEAM_SEGMENTS` straight pieces through points at :math:`s = k / n` along it, whose
displacement is the Euler-Bernoulli interpolation of the end translations :math:`u_i, u_j`
and rotations :math:`\theta_i, \theta_j`: linear along the axis, Hermite cubic across it,

.. math::  u(s) = \bigl[(1-s) P + H_1 Q\bigr] u_i + \bigl[s P + H_3 Q\bigr] u_j
           + L H_2\, \theta_i \times e + L H_4\, \theta_j \times e

with :math:`P = e e^T`, :math:`Q = I - P`, :math:`H_1 = 1 - 3s^2 + 2s^3`,
:math:`H_2 = s - 2s^2 + s^3`, :math:`H_3 = 3s^2 - 2s^3`, :math:`H_4 = s^3 - s^2` (the slope of
the transverse displacement at an end is :math:`\theta \times e`).  At the nodes the drawing
is the nodes' translations; a rigid motion :math:`u = a + \theta \times x` is drawn exactly
along the element; a released end (pin) or a Timoshenko element bends the drawn curve with
the node's rotation, not the element's own end slope (a picture, not a result).
The rotations of the points inside (exported beside the displacements) are those of the same
interpolation: the twist linear along the axis, the bending rotation :math:`e \times u'(s)/L`,

.. math::  \theta(s) = P\bigl[(1-s)\theta_i + s\theta_j\bigr]
           + e \times (H_1' u_i + H_3' u_j) / L + H_2' Q \theta_i + H_4' Q \theta_j,

so a rigid rotation is carried unchanged along the element.

**Links.** A rigid or interpolation link of a case is drawn as a spider: straight lines from
its independent (reference) node to each of its other nodes, which move with the nodes'
translations.  So is each RBE2 (``GN`` to its ``GMi``), RBE3 (``REFGRID`` to its ``Gi,j``)
and MPC (its first, dependent, grid to the grids of its other terms) of a Nastran model's
bulk data, at the grids' positions in basic coordinates.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp

from substruct.assembly.faces import face_node_refs, face_nodes, region_of
from substruct.assembly.links import NodeRef
from substruct.assembly.stack import Assembly
from substruct.builder.drawing import Drawing
from substruct.builder.links import link_node
from substruct.case.links import InterpolationLinkSpec, RigidLinkSpec
from substruct.case.nastran import NastranSpec
from substruct.substructure import Substructure

__all__ = ["BEAM_SEGMENTS", "beam_curves", "spider_drawing", "link_spiders", "bulk_spiders"]

#: Straight pieces a beam element is drawn with.
BEAM_SEGMENTS = 8
_COMPONENTS = ("ux", "uy", "uz", "rx", "ry", "rz")


def _cross_matrix(e: np.ndarray) -> np.ndarray:
    """``[e]_x`` of each row of ``e`` ``(m, 3)``: ``[e]_x v = e x v``."""
    z = np.zeros(len(e))
    return np.stack([np.stack([z, -e[:, 2], e[:, 1]], axis=1),
                     np.stack([e[:, 2], z, -e[:, 0]], axis=1),
                     np.stack([-e[:, 1], e[:, 0], z], axis=1)], axis=1)


def beam_curves(sub: Substructure, points: np.ndarray, cells: list[tuple[str, np.ndarray]],
                interp: sp.csr_array, rotations: sp.csr_array | None = None
                ) -> tuple[np.ndarray, list[tuple[str, np.ndarray]], sp.csr_array,
                           sp.csr_array | None]:
    """A frame's drawing with each beam element drawn as a curve (module docstring): its
    ``points`` (the nodes, unchanged and first), then :data:`BEAM_SEGMENTS` - 1 points inside
    each element; the ``line`` cells replaced by the pieces; ``interp`` ``(3 p, n)`` over the
    frame's coordinates with the rows of the new points; ``rotations`` (if given) likewise, the
    new points' rows from the interpolation's rotation.  A frame without beams is returned
    as it is."""
    pairs = np.asarray(sub.meta.get("elements") or [], dtype=np.int64).reshape(-1, 2)
    if not len(pairs):
        return points, cells, interp, rotations
    ids = list(sub.meta["node_ids"])
    col = {label: j for j, label in enumerate(sub.dof_labels)}
    cols = np.array([[col.get(f"{i}:{c}", -1) for c in _COMPONENTS] for i in ids],
                    dtype=np.int64)  # (nodes, 6), -1 where supported
    n_seg = BEAM_SEGMENTS
    s = np.arange(1, n_seg) / n_seg  # (k,)
    xi, xj = points[pairs[:, 0]], points[pairs[:, 1]]
    L = np.linalg.norm(xj - xi, axis=1)
    e = (xj - xi) / L[:, None]
    P = np.einsum("ma,mb->mab", e, e)
    Q = np.eye(3) - P
    ex = _cross_matrix(e)
    H1, H2 = 1 - 3 * s**2 + 2 * s**3, s - 2 * s**2 + s**3
    H3, H4 = 3 * s**2 - 2 * s**3, s**3 - s**2
    blocks = [  # (m, k, 3, 3) each, on u_i, theta_i, u_j, theta_j (theta x e = -[e]_x theta)
        (1 - s)[None, :, None, None] * P[:, None] + H1[None, :, None, None] * Q[:, None],
        -(L[:, None] * H2)[:, :, None, None] * ex[:, None],
        s[None, :, None, None] * P[:, None] + H3[None, :, None, None] * Q[:, None],
        -(L[:, None] * H4)[:, :, None, None] * ex[:, None],
    ]
    node_cols = [cols[pairs[:, 0], :3], cols[pairs[:, 0], 3:], cols[pairs[:, 1], :3],
                 cols[pairs[:, 1], 3:]]
    m, k, n0 = len(pairs), n_seg - 1, len(points)
    new = n0 + np.arange(m * k).reshape(m, k)  # the new points, element by element
    extra = _new_rows(blocks, node_cols, new, n0, interp.shape[1])
    if rotations is not None:
        D1, D2, D3, D4 = -6 * s + 6 * s**2, 1 - 4 * s + 3 * s**2, 6 * s - 6 * s**2, 3 * s**2 - 2 * s
        turn = [  # the rotation of the new points, on u_i, theta_i, u_j, theta_j
            (D1[None, :, None, None] / L[:, None, None, None]) * ex[:, None],
            (1 - s)[None, :, None, None] * P[:, None] + D2[None, :, None, None] * Q[:, None],
            (D3[None, :, None, None] / L[:, None, None, None]) * ex[:, None],
            s[None, :, None, None] * P[:, None] + D4[None, :, None, None] * Q[:, None],
        ]
        rotations = sp.csr_array(sp.vstack(
            [sp.csr_array(rotations), _new_rows(turn, node_cols, new, n0, rotations.shape[1])],
            format="csr"))
    pos = xi[:, None] + s[None, :, None] * (xj - xi)[:, None]
    chain = np.concatenate([pairs[:, :1], new, pairs[:, 1:]], axis=1)  # (m, k + 2)
    pieces = np.stack([chain[:, :-1], chain[:, 1:]], axis=2).reshape(-1, 2)
    cells = [("line", pieces)] + [(t, c) for t, c in cells if t != "line"]
    return (np.vstack([points, pos.reshape(-1, 3)]), cells,
            sp.csr_array(sp.vstack([sp.csr_array(interp), extra], format="csr")), rotations)


def _new_rows(blocks: list[np.ndarray], node_cols: list[np.ndarray], new: np.ndarray, n0: int,
              n: int) -> sp.csr_array:
    """The rows ``(3 m k, n)`` of the new points ``new`` ``(m, k)`` from ``blocks``
    ``(m, k, 3, 3)`` on the columns ``node_cols`` ``(m, 3)`` (-1: a held coordinate)."""
    rows, cs, vals = [], [], []
    for block, c in zip(blocks, node_cols):
        r = np.broadcast_to((3 * new)[:, :, None, None] + np.arange(3)[:, None], block.shape)
        cc = np.broadcast_to(c[:, None, None, :], block.shape)
        keep = (cc >= 0) & (block != 0)
        rows.append(r[keep])
        cs.append(cc[keep])
        vals.append(block[keep])
    m, k = new.shape
    return sp.csr_array((np.concatenate(vals), (np.concatenate(rows) - 3 * n0,
                                                 np.concatenate(cs))), shape=(3 * m * k, n))


def spider_drawing(name: str, centre: tuple[np.ndarray, sp.csr_array],
                   legs: list[tuple[np.ndarray, sp.csr_array]]) -> Drawing:
    """A link drawn as lines from its ``centre`` node to each of its ``legs``: each node as
    ``(position, rows)``, ``rows`` ``(3, n_total)`` its stacked translation rows."""
    points = np.vstack([centre[0]] + [p for p, _ in legs])
    interp = sp.csr_array(sp.vstack([centre[1]] + [r for _, r in legs], format="csr"))
    lines = np.column_stack([np.zeros(len(legs), dtype=np.int64),
                             np.arange(1, len(legs) + 1)])
    return Drawing(name=name, kind="link", points=points, cells=[("line", lines)],
                   interp=interp)


def link_spiders(case: Any, asm: Assembly) -> list[Drawing]:
    """The spider of each rigid and interpolation link of ``case`` (its ``links:`` block)
    over the stacked coordinates of ``asm``: the independent (reference) node first, then the
    others, each moving with its translations.  A node without a place in space (a
    substructure without positions) leaves the link undrawn."""
    subs = {s.name: s for s in asm.substructures}
    out = []
    for k, spec in enumerate(case.links):
        if isinstance(spec, RigidLinkSpec):
            centre, others, face = spec.independent, spec.dependents, spec.face
        elif isinstance(spec, InterpolationLinkSpec):
            centre, others, face = spec.reference, spec.nodes, spec.face
        else:
            continue
        refs = [link_node(case, centre, ("links", k, 0))]
        if face is not None and face.part in subs:  # the nodes of a face, as the link took them
            part = subs[face.part]
            refs += face_node_refs(part, face_nodes(part, region_of(face.region())))
        else:
            refs += [link_node(case, text, ("links", k, j + 1))
                     for j, text in enumerate(others or [])]
        nodes = []
        for ref in refs:
            sub = subs.get(ref.substructure)
            if sub is None or sub.position is None:
                break
            nodes.append((np.asarray(sub.position(ref.point(0).where), dtype=float),
                          asm.rows([ref.point(c) for c in range(3)])))
        else:
            out.append(spider_drawing(spec.name or f"link{k + 1}", nodes[0], nodes[1:]))
    return out


def bulk_spiders(case: Any, asm: Assembly) -> list[Drawing]:
    """The spider of each RBE2, RBE3 and MPC card of every ``type: nastran`` substructure of
    ``case`` over the stacked coordinates of ``asm``, named ``"<model>: RBE2 <id>"``
    (``"<model>: MPC <sid> (line <n>)"``): the card's ``GN`` (``REFGRID``, the MPC's
    dependent grid) first, then its ``GMi`` (``Gi,j``, the MPC's other grids), each at its
    grid's position in basic coordinates and moving with the grid's rows ``u_x, u_y, u_z`` of
    the assembly."""
    subs = {s.name: s for s in asm.substructures}
    out = []
    for spec in case.substructures:
        sub = subs.get(spec.name)
        if not isinstance(spec, NastranSpec) or sub is None or sub.position is None:
            continue
        from substruct.builder.nastran import rigid_element_grids  # Nastran: only when used

        for card, ident, centre, others in rigid_element_grids(spec.bulk):
            nodes = []
            for g in [centre, *others]:
                ref = NodeRef(spec.name, {"node": g})
                nodes.append((np.asarray(sub.position(ref.point(0).where), dtype=float),
                              asm.rows([ref.point(c) for c in range(3)])))
            out.append(spider_drawing(f"{spec.name}: {card} {ident}", nodes[0], nodes[1:]))
    return out
