"""Meshes for solids: a scikit-fem mesh and its named vertex sets from a file (through meshio),
a meshio mesh or a scikit-fem mesh.

The cells of highest dimension are used (hexahedra or tetrahedra, else quadrilaterals or
triangles; second-order cells through their vertices, i.e. straight-sided); points that no
such cell uses are dropped.  A cell of that dimension of another type (a wedge, a pyramid, a
cubic cell) is refused, never left out of the solid.  Named sets (meshio ``cell_sets`` and
``point_sets``, Gmsh physical groups through ``field_data``, scikit-fem ``boundaries`` and
``subdomains``) become sets of vertex indices.
"""

from __future__ import annotations

import os
from typing import Any

import meshio
import numpy as np
from skfem import Mesh
from skfem.io.meshio import from_meshio

from substruct.case.mesh_files import MeshFileError, read_mesh_file

__all__ = ["read_mesh", "mesh_label"]

# meshio cell types we read (higher-order cells are read through their vertices)
_VOLUME = {"hexahedron": 8, "hexahedron20": 8, "hexahedron27": 8, "tetra": 4, "tetra10": 4}
_PLANAR = {"quad": 4, "quad8": 4, "quad9": 4, "triangle": 3, "triangle6": 3}


def mesh_label(source: Any) -> str:
    """How a mesh source is named in messages and results: its path, or its type."""
    return os.fspath(source) if isinstance(source, (str, os.PathLike)) else type(source).__name__


def read_mesh(source: str | os.PathLike | meshio.Mesh | Mesh
              ) -> tuple[Mesh, dict[str, np.ndarray]]:
    """A scikit-fem mesh and its named vertex sets from a file, a meshio mesh or a skfem mesh.

    Raises:
        ValueError: a missing or unreadable file (the message names the path), or a mesh with
            no supported cells or with mixed cell types.
    """
    if isinstance(source, Mesh):
        return source, _skfem_sets(source)
    label = mesh_label(source)
    if isinstance(source, (str, os.PathLike)):
        path = os.fspath(source)
        if not os.path.isfile(path):
            raise ValueError(f"mesh file {path!r} does not exist")
        try:  # sizes checked before reading; meshio's sys.exit and printing caught
            source = read_mesh_file(path)
        except MeshFileError as err:
            raise ValueError(str(err) if path in str(err) else f"mesh file {path!r}: {err}"
                             ) from None
    if not isinstance(source, meshio.Mesh):
        raise ValueError(f"a mesh must be a file path, a meshio.Mesh or a skfem Mesh, "
                         f"got {type(source).__name__}")
    return _from_meshio(source, label)


def _dimension(cell_type: str) -> int:
    """The dimension of a meshio cell type: 3 for volumes, 2 for faces, else 1 or less."""
    name = cell_type.lower()
    if any(k in name for k in ("tetra", "hexahedron", "wedge", "pyramid", "polyhedron")):
        return 3
    if any(k in name for k in ("triangle", "quad", "polygon")):
        return 2
    return 1


def _from_meshio(m: meshio.Mesh, label: str) -> tuple[Mesh, dict[str, np.ndarray]]:
    types = [c.type for c in m.cells]
    top = max((_dimension(t) for t in types), default=0)
    table = _VOLUME if top == 3 else _PLANAR
    blocks = [(i, c) for i, c in enumerate(m.cells) if c.type in table]
    if not blocks:
        raise ValueError(f"mesh {label}: no supported cells (found {sorted(set(types))}; "
                         f"supported: {sorted(_VOLUME) + sorted(_PLANAR)})")
    # cells of the solid's dimension that are not read (wedges, pyramids, cubic cells...)
    # would leave a part of the solid out: refused, never dropped
    other = sorted({t for t in types if _dimension(t) == top and t not in table})
    if other:
        count = sum(len(c.data) for c in m.cells if c.type in other)
        raise ValueError(f"mesh {label}: {count} cell(s) of type {', '.join(other)} beside the "
                         f"{' and '.join(sorted({c.type for _, c in blocks}))} cells are not "
                         f"read (supported: {sorted(table)}); a solid is meshed in one of them")
    kinds = {table[c.type] for _, c in blocks}
    if len(kinds) > 1:
        raise ValueError(f"mesh {label}: mixed cell types {sorted({c.type for _, c in blocks})}"
                         " are not supported")
    nv = kinds.pop()
    conn = np.vstack([np.asarray(c.data)[:, :nv] for _, c in blocks])
    used = np.unique(conn)
    remap = np.full(len(m.points), -1, dtype=np.int64)
    remap[used] = np.arange(used.size)
    base = {8: "hexahedron", 4: "tetra" if table is _VOLUME else "quad", 3: "triangle"}[nv]
    points = np.asarray(m.points, dtype=float)[used]
    if table is _PLANAR and points.shape[1] == 3:
        if np.ptp(points[:, 2]) > 1e-12 * max(np.ptp(points[:, :2]), 1e-300):
            raise ValueError(f"mesh {label}: a planar mesh must lie in a plane z = const")
    try:
        mesh = from_meshio(meshio.Mesh(points, [(base, remap[conn])]))
    except Exception as exc:
        raise ValueError(f"mesh {label}: scikit-fem cannot use it: {exc}") from None
    return mesh, _meshio_sets(m, remap)


def _meshio_sets(m: meshio.Mesh, remap: np.ndarray) -> dict[str, np.ndarray]:
    """Named vertex sets of a meshio mesh, in the renumbered vertices."""
    sets: dict[str, list[np.ndarray]] = {}

    def add(name: str, pts: np.ndarray) -> None:
        sets.setdefault(str(name), []).append(np.asarray(pts, dtype=np.int64).ravel())

    for name, per_block in (m.cell_sets or {}).items():
        if str(name).startswith("gmsh:"):
            continue
        for block, idx in zip(m.cells, per_block):
            if idx is not None and len(idx):
                add(name, np.asarray(block.data)[np.asarray(idx, dtype=np.int64)])
    for name, idx in (m.point_sets or {}).items():
        add(name, idx)
    tags = m.cell_data.get("gmsh:physical") if m.cell_data else None
    if tags is not None and m.field_data:
        names = {int(v[0]): k for k, v in m.field_data.items()}
        for block, tag in zip(m.cells, tags):
            tag = np.asarray(tag)
            for t in np.unique(tag):
                if int(t) in names:
                    add(names[int(t)], np.asarray(block.data)[tag == t])
    out = {}
    for name, parts in sets.items():
        v = remap[np.unique(np.concatenate(parts))]
        out[name] = np.unique(v[v >= 0])
    return out


def _skfem_sets(mesh: Mesh) -> dict[str, np.ndarray]:
    out: dict[str, np.ndarray] = {}
    for name, facets in (mesh.boundaries or {}).items():
        out[name] = np.unique(mesh.facets[:, np.asarray(facets)])
    for name, cells in (mesh.subdomains or {}).items():
        out[name] = np.unique(mesh.t[:, np.asarray(cells)])
    return out
