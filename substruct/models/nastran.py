r"""Substructures made from Nastran bulk data (:class:`~substruct.case.bdf.BulkData`): grids
with six coordinates each, labelled ``"<grid>:<component>"`` with Nastran's components
``1`` - ``6`` (``"12:3"`` is grid 12's ``T3``, ``"12:4"`` its ``R1``), in basic axes, or in
the grid's displacement system for a GRID ``CD`` (:mod:`substruct.models.nastran_cd`).

.. math::  K = \sum_e E_e^T T_e^T K_e T_e E_e + \sum_s k_s\, d_s d_s^T, \qquad
           M = w \Bigl(\sum_e E_e^T T_e^T M_e T_e E_e + \sum_c E_c^T M_c E_c\Bigr)

with ``w`` = ``PARAM,WTMASS``, ``T_e`` the element's rotation to basic and ``E_e`` the rigid
offsets of its ends (:math:`u_{end} = u_{grid} + \theta \times w`).

* **CROD**: axial ``EA/L`` and torsion ``GJ/L``.  Mass :math:`\mu L` with
  :math:`\mu = \rho A + nsm`: lumped, :math:`\mu L/2` on the translations of each end; coupled
  (``PARAM,COUPMASS,1``), :math:`\mu L/6\,[2, 1; 1, 2]` on each translation.
* **CBAR / CBEAM** (:mod:`substruct.models.nastran_bars`, all elements at once): the beam of
  :mod:`substruct.models.beam` with ``I1`` bending in the plane
  of the orientation vector (local ``x-y``) and ``I2`` in the other; CBAR is Euler-Bernoulli
  (PBAR's ``K1``, ``K2`` blank), CBEAM has PBEAM's shear factors ``K1`` (plane 1, with
  ``I1``) and ``K2`` (plane 2), 1 when blank (:math:`\phi_i = 12 E I_i / (K_i G A L^2)`; a
  factor 0 leaves its plane without shear flexibility); a PBARL/PBEAML ``ROD`` has Nastran's
  ``K = 0.9`` on either.  Pin flags ``PA``, ``PB`` are condensed out
  (:func:`~substruct.models.beam.release`), offsets ``WA``, ``WB`` are rigid.  Lumped mass is
  :math:`\mu L/2` on the translations of each end, no rotary inertia, and for CBEAM the
  torsional inertia :math:`\rho (I_1 + I_2) L/2` at each end; coupled mass is the
  element's consistent mass (axial ``[2, 1; 1, 2]/6``, bending with the element's own shape
  functions, torsion :math:`\rho (I_1 + I_2) L/6\,[2, 1; 1, 2]`, no rotary inertia of bending),
  equal to a ``type: frame`` Euler-Bernoulli member with consistent mass for CBAR.
* **CONM2**: mass ``m`` with offset ``r`` and inertia ``J`` about its centre of gravity,
  :math:`M_c = E^T \mathrm{diag}(m I, J) E`, :math:`E = [I, -[r]_\times; 0, I]`.
* **CELAS1/2**: a spring on one coordinate, or between two, or grounded.
* **CHEXA / CPENTA / CTETRA**: linear solids on the translations
  (:mod:`substruct.models.nastran_solids`).

**Supports**: the SPC set and GRID ``PS`` are removed (a point on them has an all-zero row);
with AUTOSPC (Nastran's default) so are the coordinates that no element, spring or mass
stiffens (their column of ``K`` is empty) unless a link, MPC or point of the case names them.
This is the structural part of Nastran's AUTOSPC: a coordinate singular only through a
combination of stiff terms (a rod's transverse direction at an angle) is not removed.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Collection, Mapping

import numpy as np
import scipy.sparse as sp

from substruct.case.bdf import BulkData, BdfSection
from substruct.case.bdf_fields import BdfError
from substruct.models.frame import frame_component
from substruct.models.nastran_bars import bar_blocks, bar_matrices
from substruct.models.nastran_cd import grid_transform
from substruct.models.nastran_bounds import check_element, check_elements, check_solid_block
from substruct.models.nastran_shells import bush_matrices, plate_matrices
from substruct.models.selection import node_tolerance
from substruct.substructure import Geometry, PointError, Substructure, as_csr

__all__ = ["NastranMatrices", "nastran_matrices", "nastran_substructure", "conm2_matrix",
           "bar_matrices"]


def _skew(r: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


def conm2_matrix(m: float, r: np.ndarray, J: np.ndarray) -> np.ndarray:
    r"""6 x 6 mass about a grid of a mass ``m`` whose centre of gravity is at offset ``r``, with
    inertia ``J`` about it: :math:`E^T \mathrm{diag}(m I, J) E`, :math:`E = [I, -[r]_\times;
    0, I]` (:math:`u_{cg} = u + \theta \times r`)."""
    E = np.eye(6)
    E[:3, 3:] = -_skew(np.asarray(r, float))
    D = np.zeros((6, 6))
    D[:3, :3] = m * np.eye(3)
    D[3:, 3:] = J
    out = E.T @ D @ E
    return (out + out.T) / 2


def _rod(xa: np.ndarray, xb: np.ndarray, s: BdfSection, coupled: bool
         ) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness and mass (12 x 12, basic) of a CROD (module docstring)."""
    d = xb - xa
    L = float(np.linalg.norm(d))
    if not L > 0:
        raise ValueError("the rod has no length")
    e = np.outer(d, d) / L**2
    bar = np.array([[1.0, -1.0], [-1.0, 1.0]])
    K = np.zeros((12, 12))
    for start, stiff in ((0, s.mat.E * s.A / L), (3, s.mat.G * s.J / L)):
        for i in range(2):
            for j in range(2):
                K[6 * i + start:6 * i + start + 3, 6 * j + start:6 * j + start + 3] = \
                    stiff * bar[i, j] * e
    mass = (s.mat.rho * s.A + s.nsm) * L
    pair = np.array([[2.0, 1.0], [1.0, 2.0]]) / 6.0 if coupled else np.eye(2) / 2
    return K, mass * np.kron(pair, np.diag([1.0, 1.0, 1.0, 0.0, 0.0, 0.0]))


@dataclass
class NastranMatrices:
    """The full matrices of a bulk data model (every grid, six coordinates each, basic axes),
    before supports: ``K``, ``M`` (WTMASS applied), grid ``ids`` in order, positions ``xyz``,
    ``held`` (coordinates of the SPC set and GRID PS), ``unstiffened`` (empty columns of
    ``K``), the line ``elements`` (pairs of grid indices), the ``bulk`` data and the shell
    ``faces`` by kind (grid indices)."""

    K: sp.csr_array
    M: sp.csr_array
    ids: list[int]
    xyz: np.ndarray
    held: np.ndarray
    unstiffened: np.ndarray
    elements: list[tuple[int, int]]
    bulk: BulkData
    faces: dict[str, list[tuple[int, ...]]] = field(default_factory=dict)


def nastran_matrices(bulk: BulkData) -> NastranMatrices:
    """Assemble the matrices of ``bulk`` (module docstring).

    Raises:
        BdfError: an element that cannot be made (no length, an orientation along its axis,
            releases leaving a mechanism), naming its card.
    """
    ids = sorted(bulk.grids)
    index = {g: k for k, g in enumerate(ids)}
    xyz = np.array([bulk.grids[g] for g in ids])
    N = 6 * len(ids)
    rows: list[np.ndarray] = []
    cols: list[np.ndarray] = []
    kv: list[np.ndarray] = []
    mv: list[np.ndarray] = []
    pairs: list[tuple[int, int]] = []

    def add(dofs: np.ndarray, K: np.ndarray, M: np.ndarray) -> None:
        rows.append(np.repeat(dofs, dofs.size))
        cols.append(np.tile(dofs, dofs.size))
        kv.append(K.ravel())
        mv.append(M.ravel())

    def dofs2(a: int, b: int) -> np.ndarray:
        return np.concatenate([6 * index[a] + np.arange(6), 6 * index[b] + np.arange(6)])

    for rod, s in bulk.rods:
        a, b = rod.nodes
        try:
            Kr, Mr = _rod(bulk.grids[a], bulk.grids[b], s, bulk.coupled)
        except ValueError as err:
            raise BdfError(bulk.source, str(err), line=rod.line, card="CROD",
                           ident=rod.id) from None
        check_element(bulk, "CROD", rod.id, rod.line, Kr, Mr)
        add(dofs2(a, b), Kr, Mr)
        pairs.append((index[a], index[b]))
    if bulk.bars:  # all at once: 12 coordinates of each element
        Kbars, Mbars = bar_blocks(bulk)
        check_elements(bulk, [(bar.kind, bar.id, bar.line) for bar, _ in bulk.bars],
                       Kbars, Mbars)
        ends = np.array([[index[g] for g in bar.nodes] for bar, _ in bulk.bars])
        bar_dofs = (6 * ends[:, :, None] + np.arange(6)).reshape(len(ends), 12)
        rows.append(np.repeat(bar_dofs, 12, axis=1).ravel())
        cols.append(np.tile(bar_dofs, (1, 12)).ravel())
        kv.append(Kbars.ravel())
        mv.append(Mbars.ravel())
        pairs += [(int(a), int(b)) for a, b in ends]
    faces: dict[str, list[tuple[int, ...]]] = {}
    for (kind, nodes, Ke, Me), (plate, _) in zip(plate_matrices(bulk, index), bulk.plates):
        check_element(bulk, plate.kind, plate.id, plate.line, Ke, Me)
        add((6 * np.asarray(nodes)[:, None] + np.arange(6)).ravel(), Ke, Me)
        faces.setdefault(kind, []).append(nodes)
    if bulk.solids:  # scikit-fem and meshio loaded only for solid elements (start-up time)
        from substruct.models.nastran_solids import solid_blocks

        blocks = list(solid_blocks(bulk, index))
    else:
        blocks = []
    for kind, conn, Ks, Ms in blocks:
        check_solid_block(bulk, index, conn, Ks, Ms)
        rows += [Ks.row, Ms.row]
        cols += [Ks.col, Ms.col]
        kv += [Ks.data, np.zeros_like(Ms.data)]
        mv += [np.zeros_like(Ks.data), Ms.data]
        faces.setdefault(kind, []).extend(tuple(int(i) for i in c) for c in conn)
    for bush in bulk.bushes:
        grids, Kb = bush_matrices(bulk, bush)
        check_element(bulk, "CBUSH", bush.bush.id, bush.bush.line, Kb, None)
        dofs = (6 * np.array([index[g] for g in grids])[:, None] + np.arange(6)).ravel()
        add(dofs, Kb, np.zeros_like(Kb))
    for m in bulk.masses:
        Mm = conm2_matrix(m.m, m.x, m.inertia)
        check_element(bulk, "CONM2", m.id, m.line, None, Mm)
        add(6 * index[m.g] + np.arange(6), np.zeros((6, 6)), Mm)

    def coo(values: list[np.ndarray]) -> sp.csr_array:
        if not values:
            return sp.csr_array((N, N))
        mat = sp.coo_array((np.concatenate(values), (np.concatenate(rows),
                            np.concatenate(cols))), shape=(N, N)).tocsr()
        mat.eliminate_zeros()
        return sp.csr_array((mat + mat.T) / 2)

    K, M = coo(kv), coo(mv) * bulk.wtmass
    if bulk.frames:  # GRID CD: K and M in the grids' CD systems (substruct.models.nastran_cd)
        T = grid_transform(ids, bulk.frames)
        K, M = (sp.csr_array(T.T @ X @ T) for X in (K, M))
        K, M = (sp.csr_array((X + X.T) / 2) for X in (K, M))
    if bulk.springs:  # CELAS: on the grids' coordinates (in CD)
        rows, cols, kv = [], [], []
        for _, k, ea, eb in bulk.springs:
            if eb is None:
                add(np.array([6 * index[ea[0]] + ea[1]]), np.array([[k]]), np.zeros((1, 1)))
            else:
                d = np.array([6 * index[ea[0]] + ea[1], 6 * index[eb[0]] + eb[1]])
                add(d, k * np.array([[1.0, -1.0], [-1.0, 1.0]]), np.zeros((2, 2)))
        K = sp.csr_array(K + coo(kv))
    held = np.zeros(N, dtype=bool)
    for g, comps in bulk.spc.items():
        held[6 * index[g] + np.asarray(sorted(comps), dtype=int)] = True
    unstiffened = np.diff(sp.csc_array(K).indptr) == 0
    return NastranMatrices(sp.csr_array(K), sp.csr_array(M), ids, xyz, held, unstiffened,
                           pairs, bulk, faces)


def _rotations(col: np.ndarray, n_grids: int, n: int) -> sp.csr_array:
    """``(3 N, n)``: the rotations of the grids from the free coordinates."""
    drawn = np.arange(3 * n_grids)
    turn = (drawn // 3) * 6 + 3 + drawn % 3
    ok = col[turn] >= 0
    return sp.csr_array((np.ones(int(ok.sum())), (drawn[ok], col[turn][ok])),
                        shape=(drawn.size, n))


def nastran_substructure(name: str, mats: NastranMatrices,
                         keep: Collection[tuple[int, int]] = (), autospc: bool | None = None
                         ) -> Substructure:
    """The substructure of a bulk data model: the held coordinates removed and, with AUTOSPC,
    the unstiffened ones not in ``keep`` (``(grid, component 0-5)`` pairs).

    Points are ``"12:3"`` (grid 12, component 3; ``1`` - ``6`` or ``ux`` ... ``rz``),
    ``{"node": 12, "component": c}`` or ``{"at": [x, y, z], "component": c}``.
    """
    auto = mats.bulk.autospc if autospc is None else autospc
    index = {g: k for k, g in enumerate(mats.ids)}
    fixed = mats.held.copy()
    if auto:
        kept = np.zeros_like(fixed)
        for g, c in keep:
            if g in index:
                kept[6 * index[g] + c] = True
        fixed |= mats.unstiffened & ~kept
    free = np.flatnonzero(~fixed)
    n = int(free.size)
    col = -np.ones(fixed.size, dtype=np.int64)
    col[free] = np.arange(n)
    tol = node_tolerance(mats.xyz)
    from scipy.spatial import cKDTree

    tree = cKDTree(mats.xyz)

    def parse(where: Any) -> tuple[int, int | None]:
        comp: Any = None
        if isinstance(where, str) and ":" in where:
            node_s, comp = where.split(":", 1)
            node: Any = int(node_s) if node_s.strip().isdigit() else node_s
        elif isinstance(where, Mapping) and ("node" in where) != ("at" in where):
            comp = where.get("component")
            if "at" in where:
                x = np.asarray(where["at"], dtype=float).ravel()
                dist, k = tree.query(x) if x.shape == (3,) else (np.inf, 0)
                if dist > tol:
                    raise PointError(f"{name}: no grid at {where['at']!r}")
                return int(k), None if comp is None else frame_component(str(comp), name)
            node = where["node"]
        else:
            raise PointError(f"{name}: a point of a Nastran model is 'grid:component' "
                             f"(component 1-6), got {where!r}")
        if isinstance(node, bool) or node not in index:
            raise PointError(f"{name}: no grid {node!r}")
        return index[node], None if comp is None else frame_component(str(comp), name)

    def locate(where: Any) -> sp.csr_array:
        k, c = parse(where)
        if c is None:
            raise PointError(f"{name}: a point needs a component 1-6, got {where!r}")
        j = col[6 * k + c]
        if j < 0:
            return sp.csr_array((1, n))
        return sp.csr_array(([1.0], ([0], [int(j)])), shape=(1, n))

    def position(where: Any) -> np.ndarray:
        return mats.xyz[parse(where)[0]].copy()

    labels = [f"{g}:{c}" for g in mats.ids for c in range(1, 7)]
    drawn = np.arange(3 * len(mats.ids))
    trans = (drawn // 3) * 6 + drawn % 3
    ok = col[trans] >= 0
    interp = sp.csr_array((np.ones(int(ok.sum())), (drawn[ok], col[trans][ok])),
                          shape=(drawn.size, n))
    rotations = _rotations(col, len(mats.ids), n)
    if mats.bulk.frames:  # drawn in basic: u_basic = T u_CD (substruct.models.nastran_cd)
        T = grid_transform(mats.ids, mats.bulk.frames)
        interp = sp.csr_array(T[trans][:, free])
        rotations = sp.csr_array(T[trans + 3][:, free])
    cells = [("line", np.asarray(mats.elements, dtype=np.int64).reshape(-1, 2))] \
        if mats.elements else []
    cells += [(kind, np.asarray(f, dtype=np.int64)) for kind, f in mats.faces.items()]
    if not cells:
        cells = [("vertex", np.arange(len(mats.ids)).reshape(-1, 1))]
    meta = {"dim": 3, "node_ids": list(mats.ids), "node_xyz": mats.xyz,
            "elements": mats.elements, "n_nodes": len(mats.ids),
            "n_elements": len(mats.elements) + sum(len(f) for f in mats.faces.values()),
            "n_fixed": int(fixed.sum()),
            "mass": "coupled" if mats.bulk.coupled else "lumped", "source": mats.bulk.source}
    return Substructure(
        name=name, M=as_csr(mats.M[free][:, free]), K=as_csr(mats.K[free][:, free]),
        C=as_csr(None, n), dof_labels=tuple(labels[d] for d in free), locate=locate,
        kind="nastran", geometry=Geometry(points=mats.xyz, cells=cells, interp=interp,
                                          rotations=rotations),
        meta=meta, position=position)
