"""The XDMF half of the ParaView export (:mod:`substruct.io.export`): a time series
``<stem>.xdmf`` + ``<stem>.h5`` with one step per mode (time = mode number), or one step per
stored field of a transient run (time = the instant, :mod:`substruct.io.transient_export`),
written by meshio's time-series writer with two fixes, and read back before it is kept."""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["write_xdmf", "check_xdmf", "write_xdmf_series", "check_xdmf_series"]


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


def write_xdmf(path: Path, points: np.ndarray, cells: list[tuple[str, np.ndarray]],
               numbers: list[int], disp: dict[int, np.ndarray],
               rot: dict[int, np.ndarray] | None = None) -> list[Path]:
    """Write ``path`` (``.xdmf``) and its ``.h5`` beside it: the mesh, then one step per mode
    ``k`` of ``numbers`` with point data ``shape_real``/``shape_imag`` of ``disp[k]`` and,
    when ``rot`` has mode ``k``, ``rotation_real``/``rotation_imag`` of ``rot[k]``; return
    both paths."""
    rot = rot or {}
    with _xdmf_writer()(path) as writer:
        writer.write_points_cells(points, _by_type(cells))
        for k in numbers:
            data = {"shape_real": np.ascontiguousarray(disp[k].real, dtype=float),
                    "shape_imag": np.ascontiguousarray(disp[k].imag, dtype=float)}
            if k in rot:
                data["rotation_real"] = np.ascontiguousarray(rot[k].real, dtype=float)
                data["rotation_imag"] = np.ascontiguousarray(rot[k].imag, dtype=float)
            writer.write_data(k, point_data=data)
    return [path, path.with_suffix(".h5")]


def check_xdmf(path: Path, n_points: int, n_cells: int, n_steps: int) -> None:
    """Read ``path`` back with meshio; raise :class:`ValueError` unless it holds
    ``n_points`` points, ``n_cells`` cells and ``n_steps`` steps of ``(n_points, 3)`` data."""
    import meshio

    with meshio.xdmf.TimeSeriesReader(path) as reader:
        points, cells = reader.read_points_cells()
        got_cells = sum(len(c.data) for c in cells)
        if len(points) != n_points or got_cells != n_cells or reader.num_steps != n_steps:
            raise ValueError(f"{path.name} does not read back: {len(points)} points, "
                             f"{got_cells} cells, {reader.num_steps} steps")
        for step in range(n_steps):
            _, data, _ = reader.read_data(step)
            if np.shape(data["shape_real"]) != (n_points, 3):
                raise ValueError(f"{path.name} does not read back: step {step} has data of "
                                 f"shape {np.shape(data['shape_real'])}")


def write_xdmf_series(path: Path, points: np.ndarray, cells: list[tuple[str, np.ndarray]],
                      times: np.ndarray, disp: list[np.ndarray]) -> list[Path]:
    """Write ``path`` (``.xdmf``) and its ``.h5``: the mesh, then one step per instant
    ``times[i]`` with point data ``displacement`` (``(N, 3)``, ``disp[i]``); return both
    paths."""
    with _xdmf_writer()(path) as writer:
        writer.write_points_cells(points, _by_type(cells))
        for t, u in zip(times, disp):
            writer.write_data(float(t), point_data={
                "displacement": np.ascontiguousarray(u, dtype=float)})
    return [path, path.with_suffix(".h5")]


def check_xdmf_series(path: Path, n_points: int, n_cells: int, times: np.ndarray) -> None:
    """Read ``path`` back with meshio; raise :class:`ValueError` unless it holds ``n_points``
    points, ``n_cells`` cells and one step of ``(n_points, 3)`` displacements at each of
    ``times``."""
    import meshio

    with meshio.xdmf.TimeSeriesReader(path) as reader:
        points, cells = reader.read_points_cells()
        got_cells = sum(len(c.data) for c in cells)
        if (len(points) != n_points or got_cells != n_cells
                or reader.num_steps != len(times)):
            raise ValueError(f"{path.name} does not read back: {len(points)} points, "
                             f"{got_cells} cells, {reader.num_steps} steps")
        for step in range(len(times)):
            t, data, _ = reader.read_data(step)
            if float(t) != float(times[step]) or np.shape(data["displacement"]) != (n_points, 3):
                raise ValueError(f"{path.name} does not read back: step {step} at t = {t} "
                                 f"holds data of shape {np.shape(data['displacement'])}")
