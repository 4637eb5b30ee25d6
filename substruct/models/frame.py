r"""Frame substructures: 3D beams and flat shells joining nodes with six coordinates each.

Every node carries the translations and rotations ``(ux, uy, uz, rx, ry, rz)`` in global axes;
its coordinates are labelled ``"<node>:<component>"`` (``"12:uy"``, ``"12:rz"``).  The stiffness
and mass are sums of the element matrices of :mod:`substruct.models.beam` (each member may be
divided into several elements along its length), of the shell elements of
:mod:`substruct.models.shell` (plates between nodes, divided by
:mod:`substruct.models.shell_mesh`) and of concentrated node masses (a 6 x 6 mass
matrix about the node, or a mass on the translations):

.. math::  K = \sum_e L_e^T K_e L_e, \qquad M = \sum_e L_e^T M_e L_e + \sum_n L_n^T M_n L_n

assembled as sparse COO triplets converted to CSR.  Supported coordinates are removed
(Dirichlet condensation, as for the other finite-element substructures); a point on one of them
has an all-zero row.

Points of a frame are a node and a component, written ``"12:uy"``, ``{"node": 12,
"component": "ry"}`` or, by position, ``{"at": [x, y, z], "component": "rz"}`` (the node at
that place within :data:`~substruct.models.selection.NODE_TOL` times the frame size; a
position between nodes is refused).  Components are ``ux uy uz rx ry rz`` (also ``x y z``, any
case) or Nastran's digits ``1`` - ``6``.  Since positions with ``x y z`` are understood as by
the solids, the interface ties of :mod:`substruct.assembly.interfaces` work on frames too.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np
import scipy.sparse as sp

from substruct.models.beam import MASSES, THEORIES, Material, Section, beam_matrices
from substruct.models.beam_batch import BeamBatch, beam_matrices_batch
from substruct.models.selection import node_tolerance
from substruct.models.shell_mesh import Shell, shell_mesh
from substruct.substructure import Geometry, PointError, Substructure, as_csr

__all__ = ["FRAME_COMPONENTS", "Beam", "frame", "frame_component", "frame_components"]

#: The six coordinates of a frame node, in order (Nastran's components 1 - 6).
FRAME_COMPONENTS = ("ux", "uy", "uz", "rx", "ry", "rz")


def frame_component(c: Any, owner: str = "frame") -> int:
    """Index 0-5 of a node component: ``"ux"``/``"x"``/``"1"`` ... ``"rz"``/``"6"``.

    Raises:
        PointError: anything else (the message starts with ``owner``).
    """
    if isinstance(c, str):
        name = c.strip().lower()
        if name in ("x", "y", "z"):
            name = "u" + name
        if name in FRAME_COMPONENTS:
            return FRAME_COMPONENTS.index(name)
        if len(name) == 1 and name in "123456":
            return int(name) - 1
    raise PointError(f"{owner}: no node component {c!r} (use one of {list(FRAME_COMPONENTS)} "
                     f"or Nastran's digits '1' - '6')")


def frame_components(spec: Any, owner: str = "frame") -> list[int]:
    """Indices of a component set: a digit string ``"123456"`` (Nastran), one name, a list of
    names, or ``None`` / ``"all"`` for all six (in ascending order, no repeats).

    Raises:
        PointError: an unknown component, a repeated one, or an empty set.
    """
    if spec is None or (isinstance(spec, str) and spec.strip().lower() == "all"):
        return list(range(6))
    if isinstance(spec, (int, np.integer)) and not isinstance(spec, bool):
        spec = str(spec)
    if isinstance(spec, str):
        s = spec.strip()
        items: list[Any] = list(s) if s.isdigit() else [s]
    elif isinstance(spec, (list, tuple)):
        items = list(spec)
    else:
        raise PointError(f"{owner}: components are a digit string such as '123' or a list such "
                         f"as ['ux', 'rz'], got {spec!r}")
    idx = [frame_component(c, owner) for c in items]
    if not idx or len(set(idx)) != len(idx):
        raise PointError(f"{owner}: components must be a non-empty set without repeats, "
                         f"got {spec!r}")
    return sorted(idx)


@dataclass(frozen=True)
class Beam:
    """A member between two nodes.

    Attributes:
        nodes: ids of its end nodes ``(a, b)``.
        section, material: its properties.
        orientation: the vector that, with the axis, spans the local ``x-y`` plane
            (:func:`substruct.models.beam.rotation`).
        theory: ``"euler-bernoulli"`` or ``"timoshenko"``.
        divisions: number of equal elements along the member (new nodes are numbered after the
            largest node id, in member order).
        pin_a, pin_b: local coordinates released at end ``a`` / ``b`` as Nastran pin flags (a
            digit string, e.g. ``"56"`` for a hinge about ``y`` and ``z``).
        name: for messages.
    """

    nodes: tuple[int, int]
    section: Section
    material: Material
    orientation: tuple[float, float, float]
    theory: str = "euler-bernoulli"
    divisions: int = 1
    pin_a: str = ""
    pin_b: str = ""
    name: str = ""


def _node_table(name: str, nodes: Mapping[int, Sequence[float]]
                ) -> tuple[list[int], np.ndarray]:
    ids = list(nodes)
    for i in ids:
        if not isinstance(i, (int, np.integer)) or isinstance(i, bool):
            raise ValueError(f"{name}: node ids are integers, got {i!r}")
    xyz = np.asarray([np.asarray(nodes[i], dtype=float).ravel() for i in ids], dtype=float)
    if xyz.size == 0:
        raise ValueError(f"{name}: a frame needs at least one node")
    if xyz.ndim != 2 or xyz.shape[1] != 3 or not np.all(np.isfinite(xyz)):
        raise ValueError(f"{name}: node positions are three finite numbers each")
    return [int(i) for i in ids], xyz


def _pins(name: str, beam: Beam) -> tuple[list[int], list[int]]:
    out = []
    for end in (beam.pin_a, beam.pin_b):
        out.append(frame_components(end, f"{name}: member {beam.name or beam.nodes}")
                   if str(end).strip() else [])
    return out[0], out[1]


def _node_mass(name: str, node: int, value: Any) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0:
        if not (np.isfinite(arr) and arr > 0):
            raise ValueError(f"{name}: mass at node {node} must be finite and positive, "
                             f"got {float(arr)!r}")
        return np.diag([float(arr)] * 3 + [0.0] * 3)
    if arr.shape != (6, 6) or not np.all(np.isfinite(arr)) or \
            np.abs(arr - arr.T).max() > 1e-12 * np.abs(arr).max():
        raise ValueError(f"{name}: mass at node {node} must be a number or a symmetric 6 x 6 "
                         f"matrix")
    if np.linalg.eigvalsh(arr).min() < -1e-12 * np.abs(arr).max():
        raise ValueError(f"{name}: the 6 x 6 mass at node {node} is not positive semi-definite")
    return (arr + arr.T) / 2


def _batch_matrices(items: list[tuple[int, int, Beam, str]], points: list[Any],
                    mass: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The coordinates ``(n, 12)`` and global ``K``, ``M`` ``(n, 12, 12)`` of the unreleased
    elements ``(i, j, member, label)``, all at once (:mod:`substruct.models.beam_batch`).

    Raises:
        ValueError: an element :func:`~substruct.models.beam.beam_matrices` refuses (the first
            in order), with its message.
    """
    def prop(get: Any) -> np.ndarray:
        return np.array([float(get(m)) for _, _, m, _ in items])

    ia = np.array([i for i, _, _, _ in items], dtype=np.int64)
    ib = np.array([j for _, j, _, _ in items], dtype=np.int64)
    pts = np.asarray(points, dtype=float)
    b = BeamBatch(pts[ia], pts[ib], np.array([m.orientation for _, _, m, _ in items], float),
                  prop(lambda m: m.material.E), prop(lambda m: m.material.G),
                  prop(lambda m: m.material.rho), prop(lambda m: m.section.A),
                  prop(lambda m: m.section.Iy), prop(lambda m: m.section.Iz),
                  prop(lambda m: m.section.J), prop(lambda m: m.section.polar),
                  prop(lambda m: m.section.ky), prop(lambda m: m.section.kz),
                  np.array([m.theory == "timoshenko" for _, _, m, _ in items]))
    K, M, ok = beam_matrices_batch(b, mass)
    if not ok.all():
        i, j, m, label = items[int(np.flatnonzero(~ok)[0])]
        try:
            beam_matrices(points[i], points[j], m.orientation, m.section, m.material,
                          m.theory, mass)
        except ValueError as err:
            raise ValueError(f"{label}: {err}") from None
        raise AssertionError(f"{label}: the element is refused all at once, not alone")
    dofs = np.concatenate([6 * ia[:, None] + np.arange(6), 6 * ib[:, None] + np.arange(6)],
                          axis=1)
    return dofs, K, M


def frame(name: str, nodes: Mapping[int, Sequence[float]], beams: Sequence[Beam],
          supports: Mapping[int, Any] | None = None, mass: str = "consistent",
          node_masses: Mapping[int, Any] | None = None, shells: Sequence[Shell] = ()
          ) -> Substructure:
    r"""A frame of beams and shells (module docstring), as a :class:`Substructure`.

    Args:
        name: substructure name.
        nodes: node id -> ``(x, y, z)``.
        beams: the members.
        supports: node id -> components held (``"123456"``, ``["ux", "rz"]``, ``None``: all).
        mass: ``"consistent"`` or ``"lumped"`` (:mod:`substruct.models.beam`).
        node_masses: node id -> a mass (on the three translations) or a symmetric positive
            semi-definite 6 x 6 mass matrix about the node, in global axes.
        shells: flat plates between nodes (:mod:`substruct.models.shell_mesh`), with the
            frame's ``mass``; their nodes are made after the members'.

    Returns:
        A substructure with coordinates ``"<node>:<component>"`` of the unsupported
        coordinates, node by node (the nodes as given, then those made by ``divisions``);
        ``meta`` holds ``node_ids``, ``node_xyz``, ``n_elements``, ``elements`` (pairs of node
        indices), ``faces`` (shell elements by kind), ``h_max`` and ``dim = 3``.

    Raises:
        ValueError: unknown nodes, a bad property, a degenerate element or orientation.
    """
    if mass not in MASSES:
        raise ValueError(f"{name}: mass must be one of {list(MASSES)}, got {mass!r}")
    ids, xyz = _node_table(name, nodes)
    if len(set(ids)) != len(ids):
        raise ValueError(f"{name}: duplicate node ids")
    index = {i: k for k, i in enumerate(ids)}
    points = [p for p in xyz]
    next_id = max(ids) + 1
    rows, cols, kv, mv = [], [], [], []
    pairs: list[tuple[int, int]] = []
    lengths = []
    batch: list[tuple[int, int, Beam, str]] = []
    for beam in beams:
        label = f"{name}: member {beam.name or beam.nodes}"
        if beam.theory not in THEORIES:
            raise ValueError(f"{label}: theory must be one of {list(THEORIES)}, "
                             f"got {beam.theory!r}")
        a, b = beam.nodes
        if a not in index or b not in index or a == b:
            raise ValueError(f"{label}: end nodes {beam.nodes!r} must be two different nodes "
                             f"of the frame")
        n_div = beam.divisions
        if not isinstance(n_div, (int, np.integer)) or isinstance(n_div, bool) or n_div < 1:
            raise ValueError(f"{label}: divisions must be a positive integer, got {n_div!r}")
        pin_a, pin_b = _pins(name, beam)
        ends = [index[a]]
        for k in range(1, n_div):
            points.append(xyz[index[a]] + (xyz[index[b]] - xyz[index[a]]) * k / n_div)
            ids.append(next_id)
            index[next_id] = len(points) - 1
            ends.append(len(points) - 1)
            next_id += 1
        ends.append(index[b])
        for k in range(n_div):
            i, j = ends[k], ends[k + 1]
            released = (pin_a if k == 0 else []) + \
                [6 + c for c in (pin_b if k == n_div - 1 else [])]
            pairs.append((i, j))
            lengths.append(float(np.linalg.norm(points[j] - points[i])))
            if not released:  # computed with the others, all at once
                batch.append((i, j, beam, label))
                continue
            try:
                Ke, Me = beam_matrices(points[i], points[j], beam.orientation, beam.section,
                                       beam.material, beam.theory, mass, released)
            except ValueError as err:
                raise ValueError(f"{label}: {err}") from None
            dofs = np.concatenate([6 * i + np.arange(6), 6 * j + np.arange(6)])
            rows.append(np.repeat(dofs, 12))
            cols.append(np.tile(dofs, 12))
            kv.append(Ke.ravel())
            mv.append(Me.ravel())
    if batch:
        dofs, Kb, Mb = _batch_matrices(batch, points, mass)
        rows.append(np.repeat(dofs, 12, axis=1).ravel())
        cols.append(np.tile(dofs, (1, 12)).ravel())
        kv.append(Kb.ravel())
        mv.append(Mb.ravel())
    mesh = shell_mesh(list(shells), points, ids, index, node_tolerance(xyz), mass,
                      lambda k: f"{name}: shell {shells[k].name or k}")
    rows, cols, kv, mv = rows + mesh.rows, cols + mesh.cols, kv + mesh.kv, mv + mesh.mv
    for node, value in (node_masses or {}).items():
        if node not in index:
            raise ValueError(f"{name}: mass at unknown node {node!r}")
        dofs = 6 * index[node] + np.arange(6)
        rows.append(np.repeat(dofs, 6))
        cols.append(np.tile(dofs, 6))
        kv.append(np.zeros(36))
        mv.append(_node_mass(name, node, value).ravel())
    all_xyz = np.asarray(points)
    N = 6 * len(all_xyz)

    def coo(values: list[np.ndarray]) -> sp.csr_array:
        if not values:
            return sp.csr_array((N, N))
        mat = sp.coo_array((np.concatenate(values), (np.concatenate(rows),
                            np.concatenate(cols))), shape=(N, N)).tocsr()
        return sp.csr_array((mat + mat.T) / 2)

    K_all, M_all = coo(kv), coo(mv)
    fixed = np.zeros(N, dtype=bool)
    for node, comps in (supports or {}).items():
        if node not in index:
            raise ValueError(f"{name}: support at unknown node {node!r}")
        for c in frame_components(comps, f"{name}: support at node {node}"):
            fixed[6 * index[node] + c] = True
    free = np.flatnonzero(~fixed)
    col = -np.ones(N, dtype=np.int64)
    col[free] = np.arange(free.size)
    n = int(free.size)
    labels = [f"{i}:{c}" for i in ids for c in FRAME_COMPONENTS]
    tol = node_tolerance(all_xyz)
    from scipy.spatial import cKDTree  # here, not at import: scipy.spatial is 0.1 s

    tree = cKDTree(all_xyz)

    def parse(where: Any) -> tuple[int, int | None]:
        """(node index, component index or None) of a point reference."""
        comp: Any = None
        if isinstance(where, str) and ":" in where:
            node_s, comp = where.split(":", 1)
            try:
                node: Any = int(node_s)
            except ValueError:
                raise PointError(f"{name}: no node {node_s!r}") from None
        elif isinstance(where, Mapping) and ("node" in where) != ("at" in where):
            comp = where.get("component")
            if "node" in where:
                node = where["node"]
            else:
                try:
                    x = np.asarray(where["at"], dtype=float).ravel()
                except (TypeError, ValueError):
                    x = np.zeros(0)
                if x.shape != (3,):
                    raise PointError(f"{name}: a position is [x, y, z], got {where['at']!r}")
                dist, k = tree.query(x)
                if dist > tol:
                    raise PointError(f"{name}: no node at {x.tolist()} (nearest at distance "
                                     f"{dist:.3g}); frame points are nodes")
                return int(k), None if comp is None else frame_component(comp, name)
        else:
            raise PointError(f"{name}: a frame point is 'node:component', {{'node': id, "
                             f"'component': c}} or {{'at': [x, y, z], 'component': c}}, "
                             f"got {where!r}")
        if isinstance(node, bool) or node not in index:
            raise PointError(f"{name}: no node {node!r}")
        return index[node], None if comp is None else frame_component(comp, name)

    def locate(where: Any) -> sp.csr_array:
        k, c = parse(where)
        if c is None:
            raise PointError(f"{name}: a frame point needs a component, got {where!r}")
        j = col[6 * k + c]
        if j < 0:
            return sp.csr_array((1, n))
        return sp.csr_array(([1.0], ([0], [int(j)])), shape=(1, n))

    def position(where: Any) -> np.ndarray:
        return all_xyz[parse(where)[0]].copy()

    drawn = np.arange(3 * len(all_xyz))
    translation = (drawn // 3) * 6 + drawn % 3
    keep = col[translation] >= 0
    interp = sp.csr_array((np.ones(int(keep.sum())), (drawn[keep], col[translation][keep])),
                          shape=(3 * len(all_xyz), n))
    cells = [("line", np.asarray(pairs, dtype=np.int64).reshape(-1, 2))] if pairs else []
    cells += [(kind, np.asarray(f, dtype=np.int64)) for kind, f in mesh.faces.items()]
    if not cells:
        cells = [("vertex", np.arange(len(all_xyz)).reshape(-1, 1))]
    turn = translation + 3
    keep = col[turn] >= 0
    rotations = sp.csr_array((np.ones(int(keep.sum())), (drawn[keep], col[turn][keep])),
                             shape=(3 * len(all_xyz), n))
    geometry = Geometry(points=all_xyz, cells=cells, interp=interp, rotations=rotations)
    n_faces = sum(len(f) for f in mesh.faces.values())
    meta = {"dim": 3, "node_ids": list(ids), "node_xyz": all_xyz, "elements": pairs,
            "faces": mesh.faces, "n_nodes": len(ids), "n_elements": len(pairs) + n_faces,
            "mass": mass, "h_max": max(lengths + [mesh.h_max]), "n_fixed": int(fixed.sum())}
    return Substructure(
        name=name, M=as_csr(M_all[free][:, free]), K=as_csr(K_all[free][:, free]),
        C=as_csr(None, n), dof_labels=tuple(labels[d] for d in free), locate=locate,
        kind=f"frame/{mass}", geometry=geometry, meta=meta, position=position)
