r"""The nodes of a face of a meshed part, chosen by a region, and their tributary areas: the
node sets of beam-to-solid and shell-to-solid links (:mod:`substruct.assembly.links`).

A **region** is a box ``[[xmin, ymin, zmin], [xmax, ymax, zmax]]`` (widened by the part's
node tolerance :math:`\tau`, :mod:`substruct.models.selection`), a plane ``{point: p,
normal: n}`` (the nodes with :math:`|(x - p) \cdot n / |n|| \le t`, ``t`` the region's
``tolerance`` or :math:`\tau`), or both (the nodes in the box and on the plane).

The **tributary area** of a node is the sum over the cell faces whose corners all lie in the
region of the face's area shared equally among its corners,

.. math::  a_j = \sum_{f \ni j} \frac{A_f}{n_f}, \qquad
           A_f = \tfrac12 \bigl|(x_3 - x_1) \times (x_4 - x_2)\bigr| \ \text{(quadrilateral)},
           \quad \tfrac12 \bigl|(x_2 - x_1) \times (x_3 - x_1)\bigr| \ \text{(triangle)},

each face counted once (a face shared by two cells inside a cut plane is one face).  These
are the consistent nodal loads of a uniform pressure on bilinear faces of parallelogram shape
and on linear triangles, so an interpolation link weighted by them spreads a force as a
uniform traction would.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from substruct.assembly.links import NodeRef
from substruct.models.selection import node_tolerance, nodes_in_box, parse_box
from substruct.substructure import Substructure

__all__ = ["FaceRegion", "face_nodes", "tributary_areas", "region_of", "face_node_refs",
           "CELL_FACES"]

#: The faces of each meshio cell type, as corner indices in order around the face.
CELL_FACES: dict[str, tuple[tuple[int, ...], ...]] = {
    "hexahedron": ((0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6),
                   (3, 0, 4, 7)),
    "tetra": ((0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2)),
    "wedge": ((0, 2, 1), (3, 4, 5), (0, 1, 4, 3), (1, 2, 5, 4), (2, 0, 3, 5)),
    "quad": ((0, 1, 2, 3),),
    "triangle": ((0, 1, 2),),
}


@dataclass(frozen=True)
class FaceRegion:
    """A box, a plane with a tolerance, or both (module docstring)."""

    box: Any = None
    point: Any = None
    normal: Any = None
    tolerance: float | None = None

    def __str__(self) -> str:
        parts = []
        if self.box is not None:
            parts.append(f"box {[list(map(float, b)) for b in self.box]}")
        if self.point is not None:
            parts.append(f"plane through {list(map(float, self.point))} normal "
                         f"{list(map(float, self.normal))}")
        return " and ".join(parts)


def face_nodes(sub: Substructure, region: FaceRegion) -> np.ndarray:
    """Indices into ``sub.geometry.points`` of the nodes in ``region``.

    Raises:
        ValueError: a part without a mesh, a region with neither box nor plane, a zero normal,
            a negative tolerance.
    """
    if sub.geometry is None:
        raise ValueError(f"{sub.name} has no mesh to take a face from")
    xyz = np.asarray(sub.geometry.points, dtype=float)
    tau = node_tolerance(xyz)
    keep = np.ones(len(xyz), dtype=bool)
    if region.box is None and region.point is None:
        raise ValueError("a face region needs a box or a plane")
    if region.box is not None:
        lo, hi = parse_box(region.box, 3, sub.name)
        inside = np.zeros(len(xyz), dtype=bool)
        inside[nodes_in_box(xyz, lo, hi, tau)] = True
        keep &= inside
    if region.point is not None:
        p = np.asarray(region.point, dtype=float).ravel()
        n = np.asarray(region.normal, dtype=float).ravel()
        if p.shape != (3,) or n.shape != (3,) or not np.all(np.isfinite(np.r_[p, n])):
            raise ValueError(f"a plane is a point and a normal of 3 finite numbers, got "
                             f"{region.point!r}, {region.normal!r}")
        if not np.linalg.norm(n) > 0:
            raise ValueError(f"the normal of a plane must not be zero, got {region.normal!r}")
        t = tau if region.tolerance is None else float(region.tolerance)
        if not (np.isfinite(t) and t >= 0):
            raise ValueError(f"a tolerance is a finite number >= 0, got {region.tolerance!r}")
        keep &= np.abs((xyz - p) @ (n / np.linalg.norm(n))) <= t
    return np.flatnonzero(keep)


def _area(x: np.ndarray) -> float:
    if len(x) == 3:
        return 0.5 * float(np.linalg.norm(np.cross(x[1] - x[0], x[2] - x[0])))
    return 0.5 * float(np.linalg.norm(np.cross(x[2] - x[0], x[3] - x[1])))


def tributary_areas(sub: Substructure, picked: np.ndarray) -> np.ndarray:
    """The tributary area of each node ``picked`` (module docstring), from the faces of the
    cells of ``sub.geometry`` whose corners are all picked.

    Raises:
        ValueError: a picked node on no such face (a node inside an element side of a
            quadratic mesh, or a region that holds no whole face).
    """
    assert sub.geometry is not None
    xyz = np.asarray(sub.geometry.points, dtype=float)
    member = np.zeros(len(xyz), dtype=bool)
    member[picked] = True
    seen: dict[tuple[int, ...], tuple[int, ...]] = {}
    for kind, conn in sub.geometry.cells:
        conn = np.asarray(conn)
        for face in CELL_FACES.get(kind, ()):
            corners = conn[:, list(face)]
            for row in corners[member[corners].all(axis=1)]:
                seen.setdefault(tuple(sorted(row.tolist())), tuple(row.tolist()))
    area = np.zeros(len(xyz))
    for face_corners in seen.values():
        area[list(face_corners)] += _area(xyz[list(face_corners)]) / len(face_corners)
    out = area[picked]
    if picked.size and not np.all(out > 0):
        bad = int(picked[np.flatnonzero(~(out > 0))[0]])
        raise ValueError(f"node at {xyz[bad].tolist()} lies on no element face inside the "
                         f"region, so it has no tributary area (area weights need the corner "
                         f"nodes of whole faces; use weights: uniform)")
    return out


def region_of(spec: Mapping[str, Any]) -> FaceRegion:
    """A :class:`FaceRegion` from ``{box, plane: {point, normal}, tolerance}``."""
    plane = spec.get("plane") or {}
    return FaceRegion(box=spec.get("box"), point=plane.get("point"), normal=plane.get("normal"),
                      tolerance=spec.get("tolerance"))


def face_node_refs(sub: Substructure, picked: np.ndarray) -> list[NodeRef]:
    """The link nodes of ``picked`` (indices into ``sub.geometry.points``): ``{"node": k}`` of a
    solid, ``{"node": grid id}`` of a Nastran model.

    Raises:
        ValueError: a part of another kind (its drawing points are not its nodes).
    """
    if sub.kind.startswith("solid/"):
        return [NodeRef(sub.name, {"node": int(k)}) for k in picked]
    if sub.kind == "nastran":
        ids = sub.meta["node_ids"]
        return [NodeRef(sub.name, {"node": int(ids[k])}) for k in picked]
    raise ValueError(f"faces are taken from unreduced solids and Nastran models, and "
                     f"{sub.name} is a {sub.kind} substructure")
