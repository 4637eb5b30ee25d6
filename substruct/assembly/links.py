r"""Links between nodes as rows of the constraint matrix ``A`` (paper eqs 24-26, 52-53).

A link is a set of linear constraints on node components, each one row of ``A`` made of the
substructures' point rows (:class:`~substruct.assembly.stack.LinearConstraint`), so the three
formulations and their checks apply to linked assemblies unchanged.  Nodes are named by
:class:`NodeRef`: a frame node by id (``{"node": 12}``) or any node by position
(``{"at": [x, y, z]}``, understood by frames and solids alike).  Components are Nastran's
digits ``"123456"`` or names ``ux uy uz rx ry rz``.

**Rigid link** (:func:`rigid_link`, Nastran RBE2): each dependent node ``d`` moves with the
rigid-body motion of the independent node ``i``, on the chosen components,

.. math::  u_d = u_i + \theta_i \times (x_d - x_i), \qquad \theta_d = \theta_i .

**Interpolation link** (:func:`interpolation_link`, Nastran RBE3): the reference node's motion
is the weighted least-squares rigid-body fit to the translations of a set of nodes ``j`` (weights
:math:`w_j`, offsets :math:`r_j = x_j - x_r`),

.. math::  \min_{u_r,\theta_r} \sum_j w_j \,\bigl|u_j - u_r - \theta_r \times r_j\bigr|^2
           \;\Rightarrow\; \begin{bmatrix} u_r \\ \theta_r \end{bmatrix}
           = (S^T W S)^{+} S^T W u, \qquad S_j = [\,I \;\; -[r_j]_\times\,]

(rows of ``S_j`` for the components of the nodes that take part).  The rotations are scaled by a
characteristic length :math:`L_c` (the mean distance of the nodes from the reference node)
before the fit is solved, so the rank decision does not depend on the model's units.  A
reference component that the nodes do not determine (a rotation about the line of collinear
nodes, a translation of a reference node off that line) is refused with an error naming it.

**Multi-point constraint** (:func:`mpc`, Nastran MPC): :math:`\sum_k a_k u_k = 0`, the first
term dependent.

:func:`link_constraints` gathers the rows of several links and refuses a coordinate that is
dependent in two of them (its value would be prescribed twice).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np
import scipy.sparse as sp

from substruct.assembly.stack import LinearConstraint, PointRef
from substruct.models.frame import FRAME_COMPONENTS, frame_component, frame_components
from substruct.substructure import PointError, Substructure

__all__ = ["LinkError", "NodeRef", "Link", "rigid_link", "interpolation_link",
           "interpolation_matrix", "mpc", "link_constraints"]

#: Relative size of the eigenvalues of the scaled normal matrix of an interpolation link that
#: count as zero (the matrix is dimensionless, its eigenvalues of order 1 for a spread set).
LINK_RANK_TOL = 1e-9


class LinkError(ValueError):
    """A link that cannot be built: unknown node, missing component, singular set, a
    coordinate dependent twice."""


@dataclass(frozen=True)
class NodeRef:
    """A node of a substructure: ``where`` is ``{"node": id}`` (a frame node) or
    ``{"at": [x, y, z]}`` (a node by position, in a frame or a solid)."""

    substructure: str
    where: Mapping[str, Any]

    def point(self, component: int) -> PointRef:
        """The point of component ``component`` (0-5) of this node."""
        return PointRef(self.substructure, {**self.where, "component": FRAME_COMPONENTS[component]})

    def __str__(self) -> str:
        key = self.where.get("node", self.where.get("at"))
        return f"{self.substructure}@{key}"


@dataclass(frozen=True)
class Link:
    """The rows of one link and the coordinates it makes dependent.

    Attributes:
        name: for messages and constraint labels.
        kind: ``"rigid"``, ``"interpolation"`` or ``"mpc"``.
        constraints: one :class:`LinearConstraint` per row of ``A``.
        dependent: ``(substructure, key)`` of each dependent coordinate, with ``key`` the
            coordinate's column in its substructure (a node component that is one coordinate),
            the row's sparsity pattern otherwise, or ``None`` for a supported coordinate.
        labels: a readable name of each dependent coordinate, in the same order.
    """

    name: str
    kind: str
    constraints: tuple[LinearConstraint, ...]
    dependent: tuple[tuple[str, Any], ...]
    labels: tuple[str, ...]

    @classmethod
    def joined(cls, name: str, kind: str, parts: Sequence["Link"]) -> "Link":
        """One link of the rows of ``parts`` (each a link of a few rows, e.g. one
        :func:`mpc` per dependent component), in order."""
        return cls(name, kind, tuple(c for p in parts for c in p.constraints),
                   tuple(d for p in parts for d in p.dependent),
                   tuple(lab for p in parts for lab in p.labels))


def _subs(substructures: Mapping[str, Substructure] | Sequence[Substructure]
          ) -> Mapping[str, Substructure]:
    if isinstance(substructures, Mapping):
        return substructures
    return {s.name: s for s in substructures}


def _row(subs: Mapping[str, Substructure], p: PointRef, link: str) -> sp.csr_array:
    if p.substructure not in subs:
        raise LinkError(f"{link}: unknown substructure {p.substructure!r}")
    try:
        return subs[p.substructure].row(p.where)
    except PointError as err:
        raise LinkError(f"{link}: {err}") from None


def _position(subs: Mapping[str, Substructure], node: NodeRef, link: str) -> np.ndarray:
    _row(subs, node.point(0), link)  # the node exists
    sub = subs[node.substructure]
    if "at" in node.where:
        return np.asarray(node.where["at"], dtype=float).ravel()
    if sub.position is None:
        raise LinkError(f"{link}: {node.substructure} has no node positions")
    return np.asarray(sub.position(node.point(0).where), dtype=float)


def _key(subs: Mapping[str, Substructure], p: PointRef, link: str) -> Any:
    """The identity of a dependent coordinate: its column, its row's pattern, or ``None`` for
    a supported coordinate (an empty row: no coordinate of the model, so it cannot be
    dependent twice; its rows constrain the other terms only)."""
    r = _row(subs, p, link)
    r.eliminate_zeros()
    if r.nnz == 0:
        return None
    if r.nnz == 1 and r.data[0] == 1.0:
        return int(r.indices[0])
    return (tuple(r.indices.tolist()), tuple(r.data.tolist()))


def _constraint(subs: Mapping[str, Substructure], terms: list[tuple[PointRef, float]],
                label: str, link: str) -> LinearConstraint | None:
    """The constraint of ``terms`` (zero coefficients dropped), or ``None`` when every point is
    supported (the row would be empty)."""
    kept = tuple((p, float(c)) for p, c in terms if c != 0.0)
    if all(_row(subs, p, link).count_nonzero() == 0 for p, _ in kept):
        return None
    return LinearConstraint(terms=kept, name=label)


def _link(subs: Mapping[str, Substructure], name: str, kind: str,
          rows: list[tuple[PointRef, list[tuple[PointRef, float]], str]]) -> Link:
    constraints, dependent, labels = [], [], []
    for dep, terms, label in rows:
        con = _constraint(subs, terms, label, name)
        if con is None:
            continue
        constraints.append(con)
        dependent.append((dep.substructure, _key(subs, dep, name)))
        where = dep.where
        if isinstance(where, dict):  # a node and component: written as in a case file
            where = ":".join(str(v) for v in where.values())
        labels.append(f"{dep.substructure}@{where}")
    return Link(name, kind, tuple(constraints), tuple(dependent), tuple(labels))


def rigid_link(substructures: Mapping[str, Substructure] | Sequence[Substructure],
               independent: NodeRef, dependents: Sequence[NodeRef], components: Any = "123456",
               name: str = "rigid link") -> Link:
    r"""A rigid link (RBE2): for each dependent node ``d`` and chosen component,

    .. math::  u_{d} - u_{i} - \theta_i \times (x_d - x_i) = 0 \ \ \text{(translations)},
               \qquad \theta_{d} - \theta_{i} = 0 \ \ \text{(rotations)},

    i.e. ``u_dx - u_ix - r_z th_iy + r_y th_iz = 0`` and cyclic, ``r = x_d - x_i``.  A term
    with a zero offset is left out, so a solid node (no rotations) can be the independent node of
    dependents at its own position.

    Raises:
        LinkError: no dependents, a dependent equal to the independent node, a component a node
            does not have.
    """
    subs = _subs(substructures)
    if not dependents:
        raise LinkError(f"{name}: a rigid link needs at least one dependent node")
    try:
        comps = frame_components(components, name)
    except PointError as err:
        raise LinkError(str(err)) from None
    xi = _position(subs, independent, name)
    rows = []
    for dep in dependents:
        r = _position(subs, dep, name) - xi
        if dep == independent:
            raise LinkError(f"{name}: node {dep} is both independent and dependent")
        for c in comps:
            terms = [(dep.point(c), 1.0), (independent.point(c), -1.0)]
            if c < 3:  # - (theta x r)_c = - theta_{c+1} r_{c+2} + theta_{c+2} r_{c+1}
                a, b = (c + 1) % 3, (c + 2) % 3
                terms += [(independent.point(3 + a), -r[b]), (independent.point(3 + b), r[a])]
            rows.append((dep.point(c), terms,
                         f"{name}: {dep} {FRAME_COMPONENTS[c]} rigid with {independent}"))
    return _link(subs, name, "rigid", rows)


def _skew(r: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


def interpolation_link(substructures: Mapping[str, Substructure] | Sequence[Substructure],
                       reference: NodeRef, nodes: Sequence[NodeRef],
                       weights: Sequence[float] | None = None, components: Any = "123456",
                       node_components: Any = "123", name: str = "interpolation link"
                       ) -> Link:
    r"""An interpolation link (RBE3): the reference node's chosen components are the weighted
    least-squares rigid-body fit of the nodes' translations (module docstring),

    .. math::  u_{r,c} - e_c^T\, (S^T W S)^{+} S^T W\, u = 0, \qquad c \in \text{components}

    with ``W = diag(w_j)`` on the ``node_components`` (a subset of ``"123"``) of each node.

    Raises:
        LinkError: no nodes, weights not positive or of the wrong count, rotations among
            ``node_components``, the reference node among the nodes, or a reference component
            the nodes do not determine (collinear nodes for a rotation about their line, ...).
    """
    subs = _subs(substructures)
    if not nodes:
        raise LinkError(f"{name}: an interpolation link needs at least one node")
    if reference in nodes:
        raise LinkError(f"{name}: the reference node {reference} is also one of its nodes")
    try:
        comps = frame_components(components, name)
        own = frame_components(node_components, name)
    except PointError as err:
        raise LinkError(str(err)) from None
    if max(own) > 2:
        raise LinkError(f"{name}: node components are translations ('123'), got "
                        f"{node_components!r}")
    w = np.ones(len(nodes)) if weights is None else np.asarray(weights, dtype=float).ravel()
    if w.shape != (len(nodes),) or not np.all(np.isfinite(w) & (w > 0)):
        raise LinkError(f"{name}: weights must be {len(nodes)} finite positive numbers, "
                        f"got {weights!r}")
    xr = _position(subs, reference, name)
    offsets = np.array([_position(subs, nd, name) - xr for nd in nodes])
    G = interpolation_matrix(offsets, w, own, comps, f"{name}: ", f" {reference}")
    rows = []
    for c in comps:
        terms = [(reference.point(c), 1.0)]
        terms += [(nd.point(k), -G[c, j * len(own) + m])
                  for j, nd in enumerate(nodes) for m, k in enumerate(own)]
        rows.append((reference.point(c), terms,
                     f"{name}: {reference} {FRAME_COMPONENTS[c]} interpolated"))
    return _link(subs, name, "interpolation", rows)


def interpolation_matrix(offsets: np.ndarray, w: np.ndarray, own: Sequence[int],
                         comps: Sequence[int], name: str = "", reference: str = ""
                         ) -> np.ndarray:
    r"""``G`` (6 x ``len(own) n``): the reference node's motion
    :math:`(u_r, \theta_r) = G u` fitted to the components ``own`` of ``n`` nodes at
    ``offsets`` (n x 3) from it with weights ``w`` (:func:`interpolation_link`).

    Raises:
        LinkError: a component of ``comps`` the nodes do not determine.
    """
    dist = np.linalg.norm(offsets, axis=1)
    Lc = float(dist.mean()) if dist.max() > 0 else 1.0
    S = np.vstack([np.hstack([np.eye(3), -_skew(r / Lc)])[own] for r in offsets])
    Wd = np.repeat(w / w.sum(), len(own))
    N = S.T @ (Wd[:, None] * S)
    lam, V = np.linalg.eigh(N)
    null = V[:, lam <= LINK_RANK_TOL * lam.max()]
    for c in comps:
        if np.abs(null[c]).max(initial=0.0) > 1e-6:
            raise LinkError(
                f"{name}the nodes do not determine component {FRAME_COMPONENTS[c]} of the "
                f"reference node{reference} (collinear or too few nodes for it), got "
                f"{len(offsets)} nodes")
    rank = lam > LINK_RANK_TOL * lam.max()
    G = (V[:, rank] / lam[rank]) @ V[:, rank].T @ (S.T * Wd)  # (6, len(own) * len(nodes))
    G[3:] /= Lc
    return G


def mpc(substructures: Mapping[str, Substructure] | Sequence[Substructure],
        terms: Sequence[tuple[NodeRef, Any, float]], name: str = "mpc") -> Link:
    r"""A multi-point constraint :math:`\sum_k a_k u_k = 0` on node components
    ``(node, component, a_k)``; the first term is the dependent coordinate.

    Raises:
        LinkError: no terms, a zero first coefficient, a non-finite coefficient, an unknown
            node or component.
    """
    subs = _subs(substructures)
    if not terms:
        raise LinkError(f"{name}: a multi-point constraint needs at least one term")
    rows: list[tuple[PointRef, float]] = []
    for node, comp, coef in terms:
        try:
            c = frame_component(str(comp), name)
        except PointError as err:
            raise LinkError(str(err)) from None
        a = float(coef)
        if not np.isfinite(a):
            raise LinkError(f"{name}: coefficients must be finite, got {coef!r}")
        rows.append((node.point(c), a))
    if rows[0][1] == 0.0:
        raise LinkError(f"{name}: the first (dependent) coefficient must not be zero")
    return _link(subs, name, "mpc", [(rows[0][0], rows, name)])


def link_constraints(links: Sequence[Link]) -> list[LinearConstraint]:
    """The rows of all ``links``, in order.

    A supported dependent coordinate (an empty point row) is not a coordinate of the model:
    its rows only constrain the other terms, so two links may both name it.

    Raises:
        LinkError: a coordinate that is dependent in two links (or twice in one).
    """
    seen: dict[tuple[str, Any], str] = {}
    out: list[LinearConstraint] = []
    for link in links:
        for dep, label in zip(link.dependent, link.labels):
            if dep[1] is None:  # a supported coordinate: not a coordinate of the model
                continue
            if dep in seen:
                raise LinkError(f"{link.name}: {label} is already dependent in {seen[dep]}")
            seen[dep] = link.name
        out.extend(link.constraints)
    return out
