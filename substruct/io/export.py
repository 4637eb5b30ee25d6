"""Mode shapes to ParaView (VTU or XDMF) through meshio.

All drawings of a model become one mesh: their points are stacked and their cells offset.  The
nodal displacement of mode ``k`` is ``interp @ shapes[:, k - 1]`` reshaped to ``(N, 3)``, where
``interp`` stacks the drawings' interpolation matrices; its real and imaginary parts are written
as point data ``mode_<k>_real`` and ``mode_<k>_imag`` (mode numbers are 1-based, as printed by
``substruct run``).  In ParaView, *Warp By Vector* with ``mode_<k>_real`` shows the mode.  When
a drawing has rotations (frames, shells, Nastran models), the nodal rotations
``rotations @ shapes[:, k - 1]`` (radians, global axes) are point data of their own,
``mode_<k>_rotation_real`` and ``mode_<k>_rotation_imag`` (``rotation_real``/``rotation_imag``
in the per-mode and XDMF files), zero on the points of parts without rotations; they are never
added to the displacements.

- ``fmt="vtu"``: one file ``<case>_modes.vtu`` (``<case>_modes_<variant>.vtu`` for the modes
  of a variant) holding every selected mode, with field data
  ``mode_numbers``, ``omega`` (rad/s), ``freq_hz`` and ``damping_ratio``; with
  ``per_mode=True`` also ``<case>_mode_<k>.vtu`` files holding ``shape_real``/``shape_imag``.
- ``fmt="xdmf"``: a time series ``<case>_modes.xdmf`` (+ its ``<case>_modes.h5``) with one step
  per mode, time = mode number, fields ``shape_real``/``shape_imag``: ParaView's time slider
  then steps through the modes.

The files of one export are one set (:mod:`substruct.io.file_set`): written into a staging
folder in the target directory under the directory's lock, read back and checked (points,
cells, steps), then moved into place together.  An export never replaces a file unless
``force=True``.  The mesh is checked first: known cell types with their number of nodes, no
cell pointing past the points.  The cell data ``drawing`` numbers the drawing (substructure)
each cell belongs to.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Sequence

import numpy as np
import scipy.sparse as sp

from substruct.analysis.results import Modes
from substruct.builder.drawing import Drawing
from substruct.io.file_set import OutputDir
from substruct.io.paths import safe_stem, write_errors
from substruct.io.hdf5 import atomic_path
from substruct.io.result_reader import CELL_NODES
from substruct.io.xdmf_export import check_xdmf, write_xdmf
from substruct.run.result import ModelInfo, Result

__all__ = ["CombinedMesh", "combined_mesh", "select_modes", "parse_modes", "export_modes",
           "export_paths", "EXPORT_FORMATS", "MAX_MODE_NUMBER"]

EXPORT_FORMATS: tuple[str, ...] = ("vtu", "xdmf")
#: Mode numbers above this are refused by :func:`parse_modes` before any list is built.
MAX_MODE_NUMBER = 1_000_000


@dataclass
class CombinedMesh:
    """All drawings of a model as one mesh.

    Attributes:
        points: ``(N, 3)`` stacked drawing points.
        cells: meshio-style ``(cell_type, connectivity)`` blocks, indices into ``points``.
        cell_drawing: for each block, the index of the drawing it came from.
        interp: sparse ``(3 N, n_dof)``; ``(interp @ u).reshape(N, 3)`` displaces ``points``.
        point_offsets: drawing ``i`` owns points ``point_offsets[i]:point_offsets[i + 1]``.
    """

    points: np.ndarray
    cells: list[tuple[str, np.ndarray]]
    cell_drawing: list[int]
    interp: sp.csr_array
    point_offsets: np.ndarray
    rotations: sp.csr_array | None = None

    def rotation(self, u: np.ndarray) -> np.ndarray | None:
        """Nodal rotations ``(N, 3)`` of ``u``, or ``None`` when no drawing has rotations."""
        if self.rotations is None:
            return None
        return np.asarray(self.rotations @ np.asarray(u)).reshape(-1, 3)

    def displacement(self, u: np.ndarray) -> np.ndarray:
        """Nodal displacements ``(N, 3)`` (complex if ``u`` is) of the coordinate vector ``u``."""
        return np.asarray(self.interp @ np.asarray(u)).reshape(-1, 3)


def combined_mesh(model: ModelInfo | Sequence[Drawing]) -> CombinedMesh:
    """Stack the drawings of ``model`` (or a list of drawings) into one mesh.

    Raises:
        ValueError: there are no drawings; a cell block of an unknown type, of the wrong
            number of nodes, or pointing past its drawing's points (named).
    """
    drawings = list(model.drawings if isinstance(model, ModelInfo) else model)
    if not drawings:
        raise ValueError("the model has no drawings (nothing to draw or export)")
    points, cells, owner, interps, offsets = [], [], [], [], [0]
    turns: list[sp.csr_array | None] = []
    for i, d in enumerate(drawings):
        p = np.asarray(d.points, dtype=float).reshape(-1, 3)
        for cell_type, conn in d.cells:
            conn = _checked_cells(d, str(cell_type), conn, len(p))
            cells.append((str(cell_type), conn + offsets[-1]))
            owner.append(i)
        points.append(p)
        interp = sp.csr_array(d.interp)
        if interp.shape[0] != 3 * len(p):
            raise ValueError(f"drawing {d.name!r}: interp has {interp.shape[0]} rows for "
                             f"{len(p)} points (expected {3 * len(p)})")
        interps.append(interp)
        rot = getattr(d, "rotations", None)
        if rot is not None and sp.csr_array(rot).shape != interp.shape:
            raise ValueError(f"drawing {d.name!r}: rotations are {sp.csr_array(rot).shape}, "
                             f"expected {interp.shape}")
        turns.append(None if rot is None else sp.csr_array(rot))
        offsets.append(offsets[-1] + len(p))
    rotations = None
    if any(t is not None for t in turns):
        rotations = sp.csr_array(sp.vstack(
            [t if t is not None else sp.csr_array(i.shape) for t, i in zip(turns, interps)],
            format="csr"))
    return CombinedMesh(points=np.vstack(points), cells=cells, cell_drawing=owner,
                        interp=sp.csr_array(sp.vstack(interps, format="csr")),
                        point_offsets=np.asarray(offsets), rotations=rotations)


def _checked_cells(d: Drawing, cell_type: str, conn: object, n_points: int) -> np.ndarray:
    nodes = CELL_NODES.get(cell_type)
    if nodes is None:
        raise ValueError(f"drawing {d.name!r}: unknown cell type {cell_type[:40]!r}")
    a = np.asarray(conn)
    if a.ndim != 2 or a.shape[1] != nodes or (a.size and a.dtype.kind not in "iu"):
        raise ValueError(f"drawing {d.name!r}: {cell_type} cells must be integers of shape "
                         f"(c, {nodes}), got {a.dtype} of shape {a.shape}")
    a = a.astype(np.int64)
    if a.size and (a.min() < 0 or a.max() >= n_points):
        raise ValueError(f"drawing {d.name!r}: a {cell_type} cell points at point "
                         f"{int(a.max() if a.max() >= n_points else a.min())}, of "
                         f"{n_points} points")
    return a


def parse_modes(text: str, limit: int = MAX_MODE_NUMBER) -> list[int]:
    """Mode numbers from a command-line spec such as ``"1-6"``, ``"2,4,7-9"`` or ``"3"``.

    Args:
        text: the spec.
        limit: the highest mode number there is; a higher one is refused before any list
            is built (``1-99999999999999`` costs nothing).

    Raises:
        ValueError: the text is not a comma-separated list of numbers and ranges, or names a
            mode above ``limit``.
    """
    numbers: list[int] = []
    for part in str(text)[:10_000].split(","):
        m = re.fullmatch(r"\s*(\d{1,20})\s*(?:-\s*(\d{1,20})\s*)?", part)
        if not m or len(str(text)) > 10_000:
            shown = text if len(text) <= 40 else text[:37] + "..."
            raise ValueError(f"modes: expected numbers and ranges such as '1-6' or '1,3,5', "
                             f"got {shown!r}")
        lo, hi = int(m.group(1)), int(m.group(2) or m.group(1))
        if hi < lo:
            raise ValueError(f"modes: range {part.strip()!r} runs backwards")
        if hi > limit:
            first = max(lo, limit + 1)
            raise ValueError(f"modes: no mode {first}; the result has {limit} modes "
                             f"(numbered 1 to {limit})" if limit != MAX_MODE_NUMBER else
                             f"modes: no mode {first}; mode numbers go up to {limit}")
        if len(numbers) + hi - lo + 1 > limit:
            raise ValueError(f"modes: more than {limit} mode numbers in {text!r}")
        numbers.extend(range(lo, hi + 1))
    return numbers


def select_modes(modes: Modes, numbers: Iterable[int] | str | None) -> list[int]:
    """Validated 1-based mode numbers (all modes for ``None``), duplicates dropped.

    Raises:
        ValueError: a number that is not an integer or not in ``1..n_modes`` (named).
    """
    n = modes.shapes.shape[1]
    if numbers is None:
        return list(range(1, n + 1))
    if isinstance(numbers, str):
        numbers = parse_modes(numbers, limit=n)
    chosen: list[int] = []
    for k in numbers:
        if isinstance(k, (bool, np.bool_)) or not isinstance(k, (int, np.integer)):
            raise ValueError(f"modes: mode numbers are integers, got {k!r}")
        if not 1 <= k <= n:
            raise ValueError(f"modes: no mode {int(k)}; the result has {n} modes "
                             f"(numbered 1 to {n})")
        if int(k) not in chosen:
            chosen.append(int(k))
    if not chosen:
        raise ValueError("modes: no mode selected")
    return chosen


def _mode_result(result: Result, variant: str | None) -> Modes:
    if variant is not None:
        if variant not in result.variants:
            known = ", ".join(repr(v) for v in result.variants) or "none"
            raise ValueError(f"no variant {variant!r} in this result (variants: {known})")
        return result.variants[variant]
    if result.modes is None:
        raise ValueError(f"result {result.case_name!r} holds no modes")
    return result.modes


def _target(result: Result, out: str | os.PathLike, fmt: str, variant: str | None) -> Path:
    out = Path(out)
    if out.suffix.lower() in (".vtu", ".xdmf"):
        if out.suffix.lower() != f".{fmt}":
            raise ValueError(f"export path {str(out)!r} does not end in .{fmt} (format {fmt!r})")
        return out
    tail = f"_{safe_stem(variant, 'variant')}" if variant is not None else ""
    return out / f"{safe_stem(result.case_name)}_modes{tail}.{fmt}"


def export_paths(result: Result, out: str | os.PathLike, fmt: str = "vtu",
                 modes: Sequence[int] | str | None = None, *, variant: str | None = None,
                 per_mode: bool = False) -> list[Path]:
    """Every file :func:`export_modes` would write with these arguments (nothing is written).

    Raises:
        ValueError: as :func:`export_modes`.
    """
    if fmt not in EXPORT_FORMATS:
        raise ValueError(f"format must be one of {', '.join(EXPORT_FORMATS)}, got {fmt!r}")
    numbers = select_modes(_mode_result(result, variant), modes)
    path = _target(result, out, fmt, variant)
    if fmt == "xdmf":
        return [path, path.with_suffix(".h5")]
    stem = path.stem[: -len("_modes")] if path.stem.endswith("_modes") else path.stem
    return [path] + ([path.with_name(f"{stem}_mode_{k}.vtu") for k in numbers]
                     if per_mode else [])


def export_modes(result: Result, out: str | os.PathLike, fmt: str = "vtu",
                 modes: Sequence[int] | str | None = None, *, variant: str | None = None,
                 per_mode: bool = False, force: bool = False) -> list[Path]:
    """Write mode shapes for ParaView; return the paths written.

    Args:
        result: a result holding modes and drawings.
        out: a directory (created if needed; the file is ``<case>_modes.<fmt>``) or a file path
            ending in ``.vtu`` / ``.xdmf``.
        fmt: ``"vtu"`` or ``"xdmf"``.
        modes: 1-based mode numbers (or a spec such as ``"1-6"``); ``None`` exports all.
        variant: export the modes of ``result.variants[variant]`` instead of ``result.modes``.
        per_mode: with ``"vtu"``, also write one ``<stem>_mode_<k>.vtu`` per mode.
        force: replace files that exist (otherwise they are refused).

    Raises:
        ValueError: unknown format, bad mode number (named), no modes or no drawings, a
            drawing whose cells are of an unknown type or point past its points.
        FileExistsError: a file to write exists (and ``force`` is false).
        substruct.io.file_set.BusyError: another process writes into the directory.
    """
    if fmt not in EXPORT_FORMATS:
        raise ValueError(f"format must be one of {', '.join(EXPORT_FORMATS)}, got {fmt!r}")
    mr = _mode_result(result, variant)
    numbers = select_modes(mr, modes)
    mesh = combined_mesh(result.model)
    if mesh.interp.shape[1] != mr.shapes.shape[0]:
        raise ValueError(f"drawings expect {mesh.interp.shape[1]} coordinates, the mode shapes "
                         f"have {mr.shapes.shape[0]}")
    paths = export_paths(result, out, fmt, numbers, variant=variant, per_mode=per_mode)
    disp = {k: mesh.displacement(mr.shapes[:, k - 1]) for k in numbers}
    rot = {k: r for k in numbers if (r := mesh.rotation(mr.shapes[:, k - 1])) is not None}
    with OutputDir(paths[0].parent) as target:
        for p in paths:  # under the lock: no other writer adds one before the commit
            if p.is_dir() or (p.exists() and not force):
                raise FileExistsError(f"{p} exists; use --force to overwrite it"
                                      if not p.is_dir() else f"{p} is a directory")
        staging = target.stage(paths[0].stem)
        here = staging / paths[0].name
        with write_errors(paths[0].parent):
            if fmt == "vtu":
                written = _write_vtu(here, mesh, mr, numbers, disp, per_mode, rot)
            else:
                written = write_xdmf(here, mesh.points, mesh.cells, numbers, disp, rot)
                check_xdmf(here, len(mesh.points), sum(len(c) for _, c in mesh.cells),
                           len(numbers))
        if sorted(p.name for p in written) != sorted(p.name for p in paths):
            raise RuntimeError(f"export wrote {written}, expected {paths}")
        target.commit(staging)
    return paths


def _cell_data(mesh: CombinedMesh) -> dict[str, list[np.ndarray]]:
    return {"drawing": [np.full(len(conn), i, dtype=np.int32)
                        for (_, conn), i in zip(mesh.cells, mesh.cell_drawing)]}


def _field_data(mr: Modes, numbers: list[int]) -> dict[str, np.ndarray]:
    idx = np.asarray(numbers) - 1
    omega = np.asarray(mr.omega, dtype=float)[idx]
    return {"mode_numbers": np.asarray(numbers, dtype=np.int64), "omega": omega,
            "freq_hz": omega / (2 * np.pi),
            "damping_ratio": np.asarray(mr.damping_ratio, dtype=float)[idx]}


def _write_vtu(path: Path, mesh: CombinedMesh, mr: Modes, numbers: list[int],
               disp: dict[int, np.ndarray], per_mode: bool,
               rot: dict[int, np.ndarray] | None = None) -> list[Path]:
    import meshio

    point_data = {}
    rot = rot or {}
    for k in numbers:
        point_data[f"mode_{k}_real"] = np.ascontiguousarray(disp[k].real, dtype=float)
        point_data[f"mode_{k}_imag"] = np.ascontiguousarray(disp[k].imag, dtype=float)
        if k in rot:
            point_data[f"mode_{k}_rotation_real"] = np.ascontiguousarray(rot[k].real, float)
            point_data[f"mode_{k}_rotation_imag"] = np.ascontiguousarray(rot[k].imag, float)
    written = [_write_mesh(path, meshio.Mesh(mesh.points, mesh.cells, point_data=point_data,
                                             cell_data=_cell_data(mesh),
                                             field_data=_field_data(mr, numbers)))]
    if per_mode:
        stem = path.stem[: -len("_modes")] if path.stem.endswith("_modes") else path.stem
        for k in numbers:
            one = meshio.Mesh(
                mesh.points, mesh.cells,
                point_data={"shape_real": point_data[f"mode_{k}_real"],
                            "shape_imag": point_data[f"mode_{k}_imag"],
                            **({"rotation_real": point_data[f"mode_{k}_rotation_real"],
                                "rotation_imag": point_data[f"mode_{k}_rotation_imag"]}
                               if k in rot else {})},
                cell_data=_cell_data(mesh), field_data=_field_data(mr, [k]))
            written.append(_write_mesh(path.with_name(f"{stem}_mode_{k}.vtu"), one))
    return written


def _write_mesh(path: Path, mesh) -> Path:
    import meshio

    with atomic_path(path, suffix=".vtu.part") as tmp:
        meshio.write(tmp, mesh, file_format="vtu")
        _add_field_data(tmp, mesh.field_data)
    back = meshio.read(path, file_format="vtu")
    n_cells = sum(len(c.data) for c in mesh.cells)
    if len(back.points) != len(mesh.points) or \
            sum(len(c.data) for c in back.cells) != n_cells or \
            any(c.data.size and c.data.max() >= len(back.points) for c in back.cells):
        raise ValueError(f"{path.name} does not read back: {len(back.points)} points, "
                         f"{sum(len(c.data) for c in back.cells)} cells")
    return path


def _add_field_data(path: Path, field_data: dict[str, np.ndarray]) -> None:
    """Insert ``<FieldData>`` into a VTU file (meshio reads it but does not write it)."""
    if not field_data:
        return
    arrays = []
    for name, values in field_data.items():
        values = np.atleast_1d(np.asarray(values))
        vtk_type = "Int64" if values.dtype.kind in "iu" else "Float64"
        text = " ".join(repr(v) for v in values.tolist())
        arrays.append(f'<DataArray type="{vtk_type}" Name="{name}" '
                      f'NumberOfTuples="{values.size}" format="ascii">{text}</DataArray>')
    block = "\n<FieldData>\n" + "\n".join(arrays) + "\n</FieldData>"
    text = path.read_text(encoding="utf-8")
    tag = "<UnstructuredGrid>"
    at = text.index(tag) + len(tag)
    path.write_text(text[:at] + block + text[at:], encoding="utf-8")


