"""Mode shapes to ParaView (VTU or XDMF) through meshio.

All drawings of a model become one mesh: their points are stacked and their cells offset.  The
nodal displacement of mode ``k`` is ``interp @ shapes[:, k - 1]`` reshaped to ``(N, 3)``, where
``interp`` stacks the drawings' interpolation matrices; its real and imaginary parts are written
as point data ``mode_<k>_real`` and ``mode_<k>_imag`` (mode numbers are 1-based, as printed by
``substruct run``).  In ParaView, *Warp By Vector* with ``mode_<k>_real`` shows the mode.

- ``fmt="vtu"``: one file ``<case>_modes.vtu`` holding every selected mode, with field data
  ``mode_numbers``, ``omega`` (rad/s), ``freq_hz`` and ``damping_ratio``; with
  ``per_mode=True`` also ``<case>_mode_<k>.vtu`` files holding ``shape_real``/``shape_imag``.
- ``fmt="xdmf"``: a time series ``<case>_modes.xdmf`` (+ its ``<case>_modes.h5``) with one step
  per mode, time = mode number, fields ``shape_real``/``shape_imag``: ParaView's time slider
  then steps through the modes.

Every file is written under a temporary name in the target directory and renamed when
complete.  The cell data ``drawing`` numbers the drawing (substructure) each cell belongs to.
"""

from __future__ import annotations

import os
import re
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Sequence

import numpy as np
import scipy.sparse as sp

from substruct.analysis.results import Modes
from substruct.builder.drawing import Drawing
from substruct.io.hdf5 import atomic_path
from substruct.run.result import ModelInfo, Result

__all__ = ["CombinedMesh", "combined_mesh", "select_modes", "parse_modes", "export_modes",
           "EXPORT_FORMATS"]

EXPORT_FORMATS: tuple[str, ...] = ("vtu", "xdmf")


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

    def displacement(self, u: np.ndarray) -> np.ndarray:
        """Nodal displacements ``(N, 3)`` (complex if ``u`` is) of the coordinate vector ``u``."""
        return np.asarray(self.interp @ np.asarray(u)).reshape(-1, 3)


def combined_mesh(model: ModelInfo | Sequence[Drawing]) -> CombinedMesh:
    """Stack the drawings of ``model`` (or a list of drawings) into one mesh.

    Raises:
        ValueError: there are no drawings.
    """
    drawings = list(model.drawings if isinstance(model, ModelInfo) else model)
    if not drawings:
        raise ValueError("the model has no drawings (nothing to draw or export)")
    points, cells, owner, interps, offsets = [], [], [], [], [0]
    for i, d in enumerate(drawings):
        p = np.asarray(d.points, dtype=float).reshape(-1, 3)
        for cell_type, conn in d.cells:
            cells.append((str(cell_type), np.asarray(conn, dtype=np.int64) + offsets[-1]))
            owner.append(i)
        points.append(p)
        interps.append(sp.csr_array(d.interp))
        offsets.append(offsets[-1] + len(p))
    return CombinedMesh(points=np.vstack(points), cells=cells, cell_drawing=owner,
                        interp=sp.csr_array(sp.vstack(interps, format="csr")),
                        point_offsets=np.asarray(offsets))


def parse_modes(text: str) -> list[int]:
    """Mode numbers from a command-line spec such as ``"1-6"``, ``"2,4,7-9"`` or ``"3"``.

    Raises:
        ValueError: the text is not a comma-separated list of numbers and ranges.
    """
    numbers: list[int] = []
    for part in str(text).split(","):
        m = re.fullmatch(r"\s*(\d+)\s*(?:-\s*(\d+)\s*)?", part)
        if not m:
            raise ValueError(f"modes: expected numbers and ranges such as '1-6' or '1,3,5', "
                             f"got {text!r}")
        lo, hi = int(m.group(1)), int(m.group(2) or m.group(1))
        if hi < lo:
            raise ValueError(f"modes: range {part.strip()!r} runs backwards")
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
        numbers = parse_modes(numbers)
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


def _target(result: Result, out: str | os.PathLike, fmt: str) -> Path:
    out = Path(out)
    if out.suffix.lower() in (".vtu", ".xdmf"):
        if out.suffix.lower() != f".{fmt}":
            raise ValueError(f"export path {str(out)!r} does not end in .{fmt} (format {fmt!r})")
        return out
    return out / f"{_safe(result.case_name)}_modes.{fmt}"


def _safe(name: str) -> str:
    """A file-name-safe version of a case name."""
    return re.sub(r"[^\w.+-]+", "_", name).strip("._") or "case"


def export_modes(result: Result, out: str | os.PathLike, fmt: str = "vtu",
                 modes: Sequence[int] | str | None = None, *, variant: str | None = None,
                 per_mode: bool = False) -> list[Path]:
    """Write mode shapes for ParaView; return the paths written.

    Args:
        result: a result holding modes and drawings.
        out: a directory (created if needed; the file is ``<case>_modes.<fmt>``) or a file path
            ending in ``.vtu`` / ``.xdmf``.
        fmt: ``"vtu"`` or ``"xdmf"``.
        modes: 1-based mode numbers (or a spec such as ``"1-6"``); ``None`` exports all.
        variant: export the modes of ``result.variants[variant]`` instead of ``result.modes``.
        per_mode: with ``"vtu"``, also write one ``<stem>_mode_<k>.vtu`` per mode.

    Raises:
        ValueError: unknown format, bad mode number (named), no modes or no drawings.
    """
    if fmt not in EXPORT_FORMATS:
        raise ValueError(f"format must be one of {', '.join(EXPORT_FORMATS)}, got {fmt!r}")
    mr = _mode_result(result, variant)
    numbers = select_modes(mr, modes)
    mesh = combined_mesh(result.model)
    if mesh.interp.shape[1] != mr.shapes.shape[0]:
        raise ValueError(f"drawings expect {mesh.interp.shape[1]} coordinates, the mode shapes "
                         f"have {mr.shapes.shape[0]}")
    disp = {k: mesh.displacement(mr.shapes[:, k - 1]) for k in numbers}
    path = _target(result, out, fmt)
    if fmt == "vtu":
        return _write_vtu(path, mesh, mr, numbers, disp, per_mode)
    return _write_xdmf(path, mesh, numbers, disp)


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
               disp: dict[int, np.ndarray], per_mode: bool) -> list[Path]:
    import meshio

    point_data = {}
    for k in numbers:
        point_data[f"mode_{k}_real"] = np.ascontiguousarray(disp[k].real, dtype=float)
        point_data[f"mode_{k}_imag"] = np.ascontiguousarray(disp[k].imag, dtype=float)
    written = [_write_mesh(path, meshio.Mesh(mesh.points, mesh.cells, point_data=point_data,
                                             cell_data=_cell_data(mesh),
                                             field_data=_field_data(mr, numbers)))]
    if per_mode:
        stem = path.stem[: -len("_modes")] if path.stem.endswith("_modes") else path.stem
        for k in numbers:
            one = meshio.Mesh(
                mesh.points, mesh.cells,
                point_data={"shape_real": point_data[f"mode_{k}_real"],
                            "shape_imag": point_data[f"mode_{k}_imag"]},
                cell_data=_cell_data(mesh), field_data=_field_data(mr, [k]))
            written.append(_write_mesh(path.with_name(f"{stem}_mode_{k}.vtu"), one))
    return written


def _write_mesh(path: Path, mesh) -> Path:
    import meshio

    with atomic_path(path, suffix=".vtu.part") as tmp:
        meshio.write(tmp, mesh, file_format="vtu")
        _add_field_data(tmp, mesh.field_data)
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


def _by_type(cells: list[tuple[str, np.ndarray]]) -> list[tuple[str, np.ndarray]]:
    """Cell blocks merged by type (first-seen order)."""
    merged: dict[str, list[np.ndarray]] = {}
    for cell_type, conn in cells:
        merged.setdefault(cell_type, []).append(conn)
    return [(t, np.vstack(blocks)) for t, blocks in merged.items()]


def _xdmf_writer():
    import xml.etree.ElementTree as ET

    import h5py
    from meshio.xdmf import TimeSeriesWriter
    from meshio.xdmf.common import meshio_type_to_xdmf_index

    class Writer(TimeSeriesWriter):
        """meshio's writer with two fixes.

        meshio opens ``<stem>.h5`` in the *working* directory; this one keeps it beside the
        ``.xdmf`` (which refers to it by base name).  meshio's mixed topology fails on line
        cells (it writes the polyline node count into a 2-column array); this one builds the
        mixed connectivity itself.
        """

        def __enter__(self):
            self.h5_filename = str(self.filename.with_suffix(".h5"))
            self.h5_file = h5py.File(self.h5_filename, "w")
            return self

        def cells(self, cells, grid):
            if len(cells) == 1:
                return super().cells(cells, grid)
            parts = []
            for cell_type, conn in cells:
                conn = np.asarray(conn, dtype=np.int64)
                prefix = [meshio_type_to_xdmf_index[cell_type]]
                if cell_type == "line":
                    prefix.append(2)
                head = np.tile(np.asarray(prefix, dtype=np.int64), (len(conn), 1))
                parts.append(np.hstack([head, conn]).ravel())
            data = np.concatenate(parts)
            topo = ET.SubElement(grid, "Topology", TopologyType="Mixed",
                                 NumberOfElements=str(sum(len(c) for _, c in cells)))
            item = ET.SubElement(topo, "DataItem", DataType="Int", Dimensions=str(data.size),
                                 Format=self.data_format, Precision="8")
            item.text = self.numpy_to_xml_string(data)

    return Writer


def _write_xdmf(path: Path, mesh: CombinedMesh, numbers: list[int],
                disp: dict[int, np.ndarray]) -> list[Path]:
    path.parent.mkdir(parents=True, exist_ok=True)
    h5_path = path.with_suffix(".h5")
    staging = Path(tempfile.mkdtemp(dir=path.parent, prefix=f".{path.name}.", suffix=".part"))
    try:
        with _xdmf_writer()(staging / path.name) as writer:
            writer.write_points_cells(mesh.points, _by_type(mesh.cells))
            for k in numbers:
                writer.write_data(k, point_data={
                    "shape_real": np.ascontiguousarray(disp[k].real, dtype=float),
                    "shape_imag": np.ascontiguousarray(disp[k].imag, dtype=float)})
        os.replace(staging / h5_path.name, h5_path)
        os.replace(staging / path.name, path)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return [path, h5_path]
