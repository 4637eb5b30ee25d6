"""The files a mesh file names, checked before meshio opens them: an XDMF file's HDF5 data
files and an Abaqus ``.inp`` file's ``*INCLUDE`` files must be regular files inside the
directory of the file that names them (no absolute path, ``..`` or link leading out), of at
most :data:`MAX_MESH_FILE` bytes; an XDMF ``Binary`` item (a raw file meshio opens from the
working directory: a device or FIFO there is read without end) is refused, as is an
``*INCLUDE`` name meshio would take from the working directory, a file including itself or
includes nested more than :data:`MAX_MESH_INCLUDE_DEPTH` deep (:mod:`substruct.case.mesh_files`).
"""

from __future__ import annotations

import re
from pathlib import Path, PurePosixPath

__all__ = ["MAX_MESH_FILE", "MAX_MESH_INCLUDE_DEPTH", "referenced_file_problem"]

#: Largest mesh file read (bytes): the largest solid accepted (4 GB, about 100k coordinates in
#: 3D, 600k in 2D) comes from a Gmsh file of a few tens of MB.
MAX_MESH_FILE = 200_000_000


def _inside(folder: Path, name: str) -> str | None:
    """What keeps the file ``name``, read from a mesh file in ``folder``, from being a regular
    file inside that folder (``None`` when it is one)."""
    parts = PurePosixPath(name.replace("\\", "/")).parts
    if not name or any(ord(ch) < 32 for ch in name) or name.startswith(("/", "\\", "~")) or \
            re.match(r"^[A-Za-z]:", name) or ".." in parts:
        return "a file named by a mesh file is named relative to it, inside its directory " \
               "(no absolute path, drive or '..')"
    base = folder.resolve()
    try:
        (base / name).resolve().relative_to(base)
    except (OSError, ValueError):
        return "a file named by a mesh file stays inside its directory (a link leads out of it)"
    if not (base / name).is_file():
        return "no such regular file beside the mesh file"
    if (base / name).stat().st_size > MAX_MESH_FILE:
        return f"more than the {MAX_MESH_FILE} bytes of a mesh file"
    return None


#: Deepest nesting of ``*INCLUDE`` in an Abaqus mesh file.
MAX_MESH_INCLUDE_DEPTH = 8
_ABAQUS_INCLUDE = re.compile(rb"^\s*\*\s*INCLUDE\b", re.IGNORECASE)


def _abaqus_problem(path: Path, chain: tuple[Path, ...] = ()) -> str | None:
    """An ``*INCLUDE, INPUT=name`` of an Abaqus mesh file (or of a file it includes) that
    meshio may not read: a name outside the including file's directory (:func:`_inside`),
    one that meshio would take from the working directory instead (it looks there first), a
    file that includes itself, or includes nested more than :data:`MAX_MESH_INCLUDE_DEPTH`
    deep."""
    here = path.resolve()
    if here in chain:
        return f"{path.name} includes itself (through its *INCLUDE lines)"
    if len(chain) >= MAX_MESH_INCLUDE_DEPTH:
        return f"*INCLUDE lines nest more than {MAX_MESH_INCLUDE_DEPTH} deep"
    with open(path, "rb") as fp:
        for k, raw in enumerate(fp, start=1):
            if not _ABAQUS_INCLUDE.match(raw):
                continue
            name = raw.decode("latin-1").split("=")[-1].strip()
            where = f"{path.name}: line {k}: *INCLUDE names {name[:80]!r}"
            problem = _inside(path.parent, name)
            if problem is None and Path(name).exists() and \
                    Path(name).resolve() != (path.parent / name).resolve():
                problem = "meshio would read the file of that name in the working directory"
            if problem is not None:
                return f"{where}: {problem}"
            problem = _abaqus_problem(path.parent / name, chain + (here,))
            if problem is not None:
                return problem
    return None


def _xdmf_problem(path: Path) -> str | None:
    """A data item of an XDMF file that reads from a file it may not name: HDF items name an
    HDF5 file that must lie beside the XDMF file (:func:`_inside`); Binary items are refused
    (meshio opens their raw file from the working directory, not beside the XDMF file, and
    a device or FIFO named there would be read without end)."""
    import xml.etree.ElementTree as ET

    try:
        for _, item in ET.iterparse(path):
            if item.tag.rsplit("}", 1)[-1] != "DataItem":
                continue
            fmt = item.attrib.get("Format", "XML")
            if fmt == "XML":
                continue
            text = " ".join((item.text or "").split())[:80]
            if fmt != "HDF":
                return (f"an XDMF data item of format {fmt!r} ({text!r}): only XML and HDF "
                        f"data items are read")
            problem = _inside(path.parent, text.split(":", 1)[0])
            if problem is not None:
                return f"an XDMF data item names {text!r}: {problem}"
    except ET.ParseError as err:
        return f"not an XDMF file: its XML cannot be read ({err})"
    return None


def referenced_file_problem(path: Path, fmt: str) -> str | None:
    """What makes a file named by the mesh file ``path`` of meshio format ``fmt``
    (``"xdmf"``, ``"abaqus"``; others name no file) one that may not be read, or ``None``."""
    if fmt == "xdmf":
        return _xdmf_problem(path)
    if fmt == "abaqus":
        return _abaqus_problem(path)
    return None
