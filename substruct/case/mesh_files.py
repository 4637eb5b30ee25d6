"""Mesh files named by a case: checked before they are read, read in one guarded call.

A solid's ``mesh:`` is any file that meshio reads.  Before a byte of its data is parsed,
:func:`mesh_file_problem` refuses what cannot be a mesh of a solid the program accepts:

* anything but a regular file (a directory, a FIFO, a device such as ``/dev/zero``);
* a file larger than :data:`MAX_MESH_FILE`, or empty;
* a name whose extension meshio does not know;
* a header that declares more than :data:`MAX_MESH_POINTS` points or :data:`MAX_MESH_CELLS`
  cells (Gmsh ``.msh``, VTK XML ``.vtu``, legacy ``.vtk``: the counts are read from the
  first :data:`MESH_HEADER` bytes, with at most 12 digits each, before anything is
  allocated);
* an Abaqus ``.inp`` file whose ``*INCLUDE`` names a file outside its directory (or one
  meshio would take from the working directory), includes itself or nests too deep;
* an XDMF file whose data items name files outside its directory: an HDF5 file by an absolute
  path, ``..`` or a link leading out, or a raw ``Binary`` file (meshio opens it from the
  working directory, and a device or FIFO named there is read without end).

:func:`read_mesh_file` then reads it with meshio: with its printing silenced, its
``sys.exit(1)`` on a file it cannot read (an empty or malformed VTU) turned into the error,
its memory capped at :data:`MESH_READ_MEMORY` beyond what the process already uses (a
compressed data block that inflates, an XDMF data set that is huge), and the mesh it returns
checked: coordinates finite and within ``1e30`` in magnitude, every cell index pointing at a
point, and no cell of the solid collapsed (a zero Jacobian at a corner, relative to its size)
or folded (Jacobians of both signs), before anything is assembled.  Every problem is a
:class:`MeshFileError`, one line, naming the cell.
"""

from __future__ import annotations

import contextlib
import io
import os
import re
import stat
import struct
import warnings
from pathlib import Path
from typing import Any, Iterator

import numpy as np

from substruct.case.fields import gigabytes
from substruct.case.mesh_references import MAX_MESH_FILE, referenced_file_problem
from substruct.case.numbers import array_problem

__all__ = ["MAX_MESH_FILE", "MAX_MESH_POINTS", "MAX_MESH_CELLS", "MESH_HEADER",

           "MESH_READ_MEMORY", "DEGENERATE", "MeshFileError", "mesh_file_problem",
           "read_mesh_file", "mesh_format"]

#: Most points a mesh file may declare (far above the largest solid accepted).
MAX_MESH_POINTS = 2_000_000
#: Most cells (of every dimension, boundary faces included) a mesh file may declare.
MAX_MESH_CELLS = 4_000_000
#: Bytes at the start of a mesh file searched for the counts its header declares.
MESH_HEADER = 1_000_000
#: Memory a mesh read may take beyond what the process used before it (bytes).
MESH_READ_MEMORY = 3_000_000_000


class MeshFileError(ValueError):
    """A mesh file that cannot be read, in one line."""


def mesh_format(path: Path) -> str | None:
    """The meshio format of ``path`` from its name (``gmsh`` for ``.msh``), or ``None``."""
    import meshio

    name = path.name.lower()
    if name.endswith(".msh"):
        return "gmsh"  # ".msh" is also ANSYS's: meshio would try that reader first (and print)
    for ext in sorted(meshio.extension_to_filetypes, key=len, reverse=True):
        if name.endswith(ext) and len(name) > len(ext):
            kinds = meshio.extension_to_filetypes[ext]
            return kinds[0] if kinds else None
    return None


def _count(text: bytes) -> int:
    """A count written in a header: at most 12 digits, or a :class:`MeshFileError`."""
    if not re.fullmatch(rb"\s*\d{1,12}\s*", text):
        shown = text.strip()[:24].decode("latin-1")
        raise MeshFileError(f"the header declares a count that is not an integer of at most "
                            f"12 digits: {shown!r}")
    return int(text)


def _gmsh_counts(head: bytes) -> tuple[int | None, int | None]:
    """``(nodes, elements)`` declared by a Gmsh file (versions 2 and 4, ASCII or binary)."""
    fmt = re.search(rb"\$MeshFormat\r?\n\s*([0-9.]+)\s+(\d+)\s+(\d+)", head)
    version, binary, size_t = 2.2, False, 8
    if fmt is not None:
        if re.fullmatch(rb"\d{1,3}(\.\d{1,3})?", fmt.group(1)):
            version = float(fmt.group(1))
        binary = fmt.group(2) == b"1"
        size_t = 4 if fmt.group(3) == b"4" else 8
    counts: list[int | None] = []
    for section in (b"$Nodes", b"$Elements"):
        m = re.search(re.escape(section) + rb"\r?\n", head)
        if m is None:
            counts.append(None)
            continue
        rest = head[m.end():]
        if version >= 4 and binary:
            if len(rest) < 2 * size_t:
                counts.append(None)
                continue
            code = "<Q" if size_t == 8 else "<I"
            counts.append(struct.unpack(code, rest[size_t:2 * size_t])[0])
            continue
        line = rest.split(b"\n", 1)[0]
        fields = line.split()
        if version >= 4:
            if len(fields) < 2:
                raise MeshFileError(f"the {section.decode()} header must be 4 counts, got "
                                    f"{line[:40].decode('latin-1')!r}")
            counts.append(_count(fields[1]))
        else:
            counts.append(_count(line))
    return counts[0], counts[1]


def _vtu_counts(head: bytes) -> tuple[int | None, int | None]:
    """``(points, cells)`` declared by the pieces of a VTK XML file."""
    points = [_count(v) for v in re.findall(rb'NumberOfPoints\s*=\s*"([^"]{0,40})"', head)]
    cells = [_count(v) for v in re.findall(rb'NumberOfCells\s*=\s*"([^"]{0,40})"', head)]
    return (sum(points) if points else None), (sum(cells) if cells else None)


def _vtk_counts(head: bytes) -> tuple[int | None, int | None]:
    """``(points, cells)`` declared by a legacy VTK file."""
    p = re.search(rb"(?m)^\s*POINTS\s+(\S{1,40})", head)
    c = re.search(rb"(?m)^\s*CELLS\s+(\S{1,40})", head)
    return (_count(p.group(1)) if p else None), (_count(c.group(1)) if c else None)


_COUNTERS = {"gmsh": _gmsh_counts, "vtu": _vtu_counts, "vtk": _vtk_counts}


def mesh_file_problem(path: Path) -> str | None:
    """What makes ``path`` unreadable as a mesh file, found without reading its data; ``None``
    when it may be read.  The message does not name the file (the caller does)."""
    try:
        info = path.stat()
    except FileNotFoundError:
        return "no such mesh file"
    except OSError as err:
        return f"cannot read mesh file ({err.strerror or err})"
    if stat.S_ISDIR(info.st_mode):
        return "is a directory, not a mesh file"
    if not stat.S_ISREG(info.st_mode):
        return "is a FIFO, a device or a socket, not a mesh file (a mesh is read from a " \
               "regular file)"
    if info.st_size > MAX_MESH_FILE:
        return (f"a mesh file of {info.st_size} bytes, more than the {MAX_MESH_FILE} read "
                f"(the largest solid accepted comes from a few tens of MB)")
    if info.st_size == 0:
        return "the mesh file is empty"
    fmt = mesh_format(path)
    if fmt is None:
        return (f"unknown mesh format {path.suffix or '(no extension)'!r}: a mesh file is one "
                f"that meshio reads (.msh, .vtu, .vtk, .xdmf, .mesh, .inp, ...)")
    if fmt in ("xdmf", "abaqus"):
        return referenced_file_problem(path, fmt)
    counter = _COUNTERS.get(fmt)
    if counter is None:
        return None
    try:
        with open(path, "rb") as fp:
            head = fp.read(MESH_HEADER)
        points, cells = counter(head)
    except MeshFileError as err:
        return str(err)
    except OSError as err:
        return f"cannot read mesh file ({err.strerror or err})"
    if points is not None and points > MAX_MESH_POINTS:
        return (f"the header declares {points} points, more than the {MAX_MESH_POINTS} "
                f"accepted")
    if cells is not None and cells > MAX_MESH_CELLS:
        return f"the header declares {cells} cells, more than the {MAX_MESH_CELLS} accepted"
    return None


def _vm_size() -> int | None:
    """Virtual memory of this process (bytes), where the system tells it."""
    try:
        with open("/proc/self/statm", "rb") as f:
            pages = int(f.read().split()[0])
        return pages * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError, AttributeError):
        return None


@contextlib.contextmanager
def _memory_cap(extra: int) -> Iterator[None]:
    """Cap the address space of the process at its current size plus ``extra`` bytes, for the
    duration of the block (an allocation beyond raises :class:`MemoryError`); a no-op where
    the system has no such limit."""
    try:
        import resource
    except ImportError:  # not on this system
        yield
        return
    used = _vm_size()
    try:
        soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    except (OSError, ValueError):
        used = None
    if used is None:
        yield
        return
    cap = used + extra
    if hard != resource.RLIM_INFINITY:
        cap = min(cap, hard)
    if soft != resource.RLIM_INFINITY and soft <= cap:
        yield
        return
    try:
        resource.setrlimit(resource.RLIMIT_AS, (cap, hard))
    except (OSError, ValueError):
        yield
        return
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


#: Cells whose shape is checked (the cells a solid is made of), by vertex count.
_VOLUME = {"hexahedron": 8, "hexahedron20": 8, "hexahedron27": 8, "tetra": 4, "tetra10": 4}
_PLANAR = {"quad": 4, "quad8": 4, "quad9": 4, "triangle": 3, "triangle6": 3}
#: The edges at each corner of a quadrilateral / hexahedron (VTK and Gmsh vertex order), in
#: the order that gives a positive Jacobian for a positively oriented cell.
_QUAD_CORNERS = np.array([[0, 1, 3], [1, 2, 0], [2, 3, 1], [3, 0, 2]])
_HEX_CORNERS = np.array([[0, 1, 3, 4], [1, 2, 0, 5], [2, 3, 1, 6], [3, 0, 2, 7],
                         [4, 7, 5, 0], [5, 4, 6, 1], [6, 5, 7, 2], [7, 6, 4, 3]])
#: A corner Jacobian below this fraction of the cell's size (its diameter to the power of the
#: dimension) is zero: the cell is collapsed.
DEGENERATE = 1e-12


def _corner_jacobians(xyz: np.ndarray, conn: np.ndarray, nv: int, dim: int) -> np.ndarray:
    """The Jacobian determinant at each corner of each cell, ``(cells, corners)``; one per
    simplex (its volume or area, times ``dim!``)."""
    p = xyz[conn]  # (cells, nv, dim)
    if nv == dim + 1:  # a simplex: one affine map
        return np.linalg.det(p[:, 1:, :] - p[:, :1, :])[:, None]
    corners = _HEX_CORNERS if dim == 3 else _QUAD_CORNERS
    edges = p[:, corners[:, 1:], :] - p[:, corners[:, :1], :]  # (cells, corners, dim, dim)
    return np.linalg.det(edges)


def _check_shapes(points: np.ndarray, cells: Any) -> None:
    """Refuse a collapsed cell (a zero Jacobian somewhere: nodes that coincide, a zero area or
    volume) or a folded one (Jacobians of both signs at its corners), naming the first; an
    inverted cell (every corner negative) is a mirrored numbering and integrates correctly."""
    types = [c.type for c in cells]
    table = _VOLUME if any(t in _VOLUME for t in types) else _PLANAR
    dim = 3 if table is _VOLUME else 2
    xyz = np.asarray(points, dtype=float)[:, :dim] if points.shape[1] >= dim else None
    if xyz is None:
        return
    for block in cells:
        if block.type not in table or len(block.data) == 0:
            continue
        nv = table[block.type]
        conn = np.asarray(block.data)[:, :nv]
        for start in range(0, len(conn), 200_000):
            part = conn[start:start + 200_000]
            with np.errstate(all="ignore"):
                jac = _corner_jacobians(xyz, part, nv, dim)
                ext = np.ptp(xyz[part], axis=1).max(axis=1) ** dim
            small = np.abs(jac) <= DEGENERATE * ext[:, None]
            mixed = (jac.max(axis=1) > 0) & (jac.min(axis=1) < 0)
            bad = small.any(axis=1) | mixed
            if bad.any():
                k = int(np.argmax(bad))
                what = "folded (its corners have Jacobians of both signs)" if mixed[k] and \
                    not small[k].any() else "collapsed (a zero Jacobian: coinciding nodes or " \
                    "no area or volume)"
                nodes = [int(v) for v in part[k]]
                raise MeshFileError(f"{block.type} cell {start + k} is {what}: nodes {nodes}")


def _check_mesh(mesh: Any) -> None:
    """Coordinates in range, cell indices that point at points, cells that are not degenerate."""
    points = np.asarray(mesh.points)
    if points.ndim != 2 or points.shape[1] not in (2, 3):
        raise MeshFileError(f"points must be 2 or 3 coordinates each, got an array of shape "
                            f"{points.shape}")
    if len(points) > MAX_MESH_POINTS:
        raise MeshFileError(f"{len(points)} points, more than the {MAX_MESH_POINTS} accepted")
    problem = array_problem(points)
    if problem is not None and "largest entry" not in problem:  # tiny meshes are fine
        raise MeshFileError(f"the point coordinates: {problem}")
    n = len(points)
    total = 0
    for block in mesh.cells:
        data = np.asarray(block.data)
        total += len(data)
        if data.size == 0:
            continue
        if data.dtype.kind not in "iu":
            raise MeshFileError(f"{block.type} cells: indices of type {data.dtype}, not "
                                f"integers")
        lo, hi = int(data.min()), int(data.max())
        if lo < 0 or hi >= n:
            bad = lo if lo < 0 else hi
            raise MeshFileError(f"{block.type} cells point at point {bad}, but the mesh has "
                                f"{n} points (0..{n - 1})")
    if total > MAX_MESH_CELLS:
        raise MeshFileError(f"{total} cells, more than the {MAX_MESH_CELLS} accepted")
    _check_shapes(points, mesh.cells)


def read_mesh_file(path: str | os.PathLike) -> Any:
    """A meshio mesh from ``path``, checked before and after it is read.

    Raises:
        MeshFileError: anything :func:`mesh_file_problem` refuses, anything meshio cannot read
            (including its ``sys.exit``), a read beyond :data:`MESH_READ_MEMORY`, points out
            of range or cells pointing past them; one line.
    """
    import meshio

    p = Path(path)
    problem = mesh_file_problem(p)
    if problem is not None:
        raise MeshFileError(problem)
    fmt = mesh_format(p)
    said = io.StringIO()
    try:
        with contextlib.redirect_stdout(said), contextlib.redirect_stderr(said), \
                warnings.catch_warnings(), _memory_cap(MESH_READ_MEMORY), \
                np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            mesh = meshio.read(p, file_format=fmt)
    except MemoryError:
        raise MeshFileError(f"cannot read mesh file {p}: reading it would take more than the "
                            f"{gigabytes(MESH_READ_MEMORY)} of memory allowed for a mesh"
                            ) from None
    except SystemExit:  # meshio gives up on a file with sys.exit(1), after printing why
        raise MeshFileError(f"cannot read mesh file {p} (not a readable {fmt} file)") from None
    except Exception as exc:  # meshio raises many kinds for a corrupt file
        detail = " ".join(str(exc).split()) or type(exc).__name__
        raise MeshFileError(f"cannot read mesh file {p} ({type(exc).__name__}: "
                            f"{detail[:200]})") from None
    _check_mesh(mesh)
    return mesh
