"""Write the meshes of the solid cases (Gmsh 2.2 files with physical groups), at any refinement.

    python meshes/make_meshes.py                 # the small files kept in the repository
    python meshes/make_meshes.py --refine 4 --out build/meshes   # larger ones

Meshes:

* ``box_beam_left.msh`` and ``box_beam_right.msh``: the two halves of a hollow square box beam
  (length ``L = 1``, outer side ``0.1``, wall ``0.02``), hexahedra, split at ``x = L/2`` with
  matching nodes.  Physical groups: volume ``solid``; faces ``clamp`` (``x = 0``, left half),
  ``interface`` (``x = L/2``, both halves), ``tip`` (``x = L``, right half).
* ``box_beam_right_fine.msh``: the right half meshed twice as finely across and more coarsely
  along ``x`` (a non-matching interface: tie it with ``tie_nonmatching``, the finer right
  half as the slave whose nodes follow the left half).
* ``plate.msh``: a 2D cantilever plate ``1.0 x 0.2`` of triangles; physical groups: surface
  ``plate``, lines ``clamp`` (``x = 0``) and ``tip`` (``x = 1``).

At ``--refine r`` every element is split ``r`` times along each axis.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import meshio
import numpy as np
from skfem import MeshHex, MeshTri
from skfem.io.meshio import to_meshio

L, SIDE, WALL = 1.0, 0.1, 0.02


def _faces(cells: np.ndarray, points: np.ndarray, axis: int, value: float) -> np.ndarray:
    """The quadrilateral faces of hexahedra (VTK order) lying in the plane ``x_axis = value``."""
    local = np.array([[0, 1, 2, 3], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6],
                      [3, 0, 4, 7]])
    faces = cells[:, local].reshape(-1, 4)
    on = np.all(np.isclose(points[faces, axis], value, atol=1e-12), axis=1)
    faces = faces[on]
    _, first = np.unique(np.sort(faces, axis=1), axis=0, return_index=True)
    return faces[np.sort(first)]


def _lines(cells: np.ndarray, points: np.ndarray, axis: int, value: float) -> np.ndarray:
    """The edges of triangles lying on the line ``x_axis = value``."""
    edges = cells[:, [[0, 1], [1, 2], [2, 0]]].reshape(-1, 2)
    edges = edges[np.all(np.isclose(points[edges, axis], value, atol=1e-12), axis=1)]
    _, first = np.unique(np.sort(edges, axis=1), axis=0, return_index=True)
    return edges[np.sort(first)]


def _write(path: Path, points: np.ndarray, volume: tuple[str, np.ndarray],
           groups: dict[str, tuple[str, np.ndarray]], volume_name: str) -> None:
    """A Gmsh 2.2 file with one physical group per named cell block."""
    dim = 3 if volume[0] == "hexahedron" else 2
    cells, physical = [volume], [np.full(len(volume[1]), 1)]
    field_data = {volume_name: np.array([1, dim])}
    for tag, (name, (kind, conn)) in enumerate(groups.items(), start=2):
        cells.append((kind, conn))
        physical.append(np.full(len(conn), tag))
        field_data[name] = np.array([tag, dim - 1])
    mesh = meshio.Mesh(points, cells, cell_data={"gmsh:physical": physical,
                                                 "gmsh:geometrical": physical},
                       field_data=field_data)
    meshio.write(str(path), mesh, file_format="gmsh22", binary=False)


def box_beam_half(x0: float, x1: float, nx: int, nside: int) -> tuple[np.ndarray, np.ndarray]:
    """Points and VTK hexahedra of a hollow square tube ``x0 <= x <= x1``."""
    mesh = MeshHex.init_tensor(np.linspace(x0, x1, nx + 1), np.linspace(0, SIDE, nside + 1),
                               np.linspace(0, SIDE, nside + 1))
    mid = mesh.p[:, mesh.t].mean(axis=1)
    hole = np.all((mid[1:] > WALL) & (mid[1:] < SIDE - WALL), axis=0)
    mesh = mesh.remove_elements(np.flatnonzero(hole))
    m = to_meshio(mesh)
    used = np.unique(m.cells[0].data)
    remap = np.full(len(m.points), -1)
    remap[used] = np.arange(used.size)
    return m.points[used], remap[m.cells[0].data]


def write_box_beam(out: Path, refine: int) -> list[Path]:
    nside = 5 * refine
    paths = []
    for name, x0, x1, nx, ns, faces in (
            ("box_beam_left", 0.0, L / 2, 25 * refine, nside, {"clamp": 0.0, "interface": L / 2}),
            ("box_beam_right", L / 2, L, 25 * refine, nside, {"interface": L / 2, "tip": L}),
            ("box_beam_right_fine", L / 2, L, 15 * refine, 2 * nside, {"interface": L / 2,
                                                                      "tip": L})):
        pts, hexes = box_beam_half(x0, x1, nx, ns)
        groups = {g: ("quad", _faces(hexes, pts, 0, v)) for g, v in faces.items()}
        path = out / f"{name}.msh"
        _write(path, pts, ("hexahedron", hexes), groups, "solid")
        paths.append(path)
    return paths


def write_plate(out: Path, refine: int) -> Path:
    mesh = MeshTri.init_tensor(np.linspace(0, 1.0, 20 * refine + 1),
                               np.linspace(0, 0.2, 4 * refine + 1))
    m = to_meshio(mesh)
    pts = np.column_stack([m.points[:, :2], np.zeros(len(m.points))])
    tris = m.cells[0].data
    groups = {"clamp": ("line", _lines(tris, pts, 0, 0.0)),
              "tip": ("line", _lines(tris, pts, 0, 1.0))}
    path = out / "plate.msh"
    _write(path, pts, ("triangle", tris), groups, "plate")
    return path


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--refine", type=int, default=1, help="split every element r times")
    parser.add_argument("--out", type=Path, default=Path(__file__).resolve().parent)
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    for path in write_box_beam(args.out, args.refine) + [write_plate(args.out, args.refine)]:
        print(f"{path} ({path.stat().st_size / 1024:.0f} kB)")


if __name__ == "__main__":
    main()
