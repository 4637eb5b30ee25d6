r"""Universal File Format export: receptances as dataset 58 (written here, binary ``58b``),
modes as 55 and 2414, the nodes of both as 15 (55 and 15 written by ``pyuff``).

* **58** (one function per output/input pair, :func:`uff58_bytes`): abscissa in Hz (uneven
  spacing, the grid as computed, one frequency or more), ordinate complex double
  (``ord_data_type 6``); ``func_type 4`` (frequency response function), ordinate
  displacement, velocity or acceleration over force for receptance, mobility or accelerance
  (spec data types 8, 11, 12 over 13).  Response and reference are nodes of the file's
  dataset 15 (:func:`frf_nodes`): a point that is a coordinate of the model is that
  coordinate's node (``k + 1``, the node of its value in 55 and 2414), direction ``x``; a
  coordinate ``<part>@<node>:<dir>`` of an FRF part one node per part and node, in its
  direction; any other point (a position on a rod) a node of its own after those; the names
  are in the id lines (``id4`` response, ``id5`` reference).
* **55** (one dataset per mode): the complex shape, one node per coordinate of the model
  (node ``k`` = coordinate ``k``, value in ``x``; ``data_ch 2``, 3 values a node), with the
  frequency (Hz), the damping ratio and the eigenvalue; the coordinate labels are listed in
  the id lines of the 15 dataset's header.
* **2414** (one dataset per mode, :func:`uff2414_text`): the same shapes in double precision,
  analysis type 3 (complex eigenvalue), data at nodes, data type 6 (double complex), one value
  a node (``x``), written ``2D25.16`` (50 columns: within the 80 of a record); the eigenvalue
  to 17 digits in record 2 (the dataset name), as records 12-13 hold only ``E13.5``.
* **a virtual-point result** (one with channel geometry, ``/channels``): the header (151),
  the units (164, SI), the nodes (2411) at the virtual points and channels and the channels' coordinate systems
  (2420) first, the 58 functions at those nodes and directions
  (:mod:`substruct.io.uff_channels`); no 15.
* **15**: the nodes ``1 .. N`` of the 55 and 58 datasets at ``x = k`` (the model's
  coordinates are generalized ones, not points in space): integers, exact in ``E13.5`` up to 999,999 nodes;
  above that the double-precision node dataset **2411** (``3D25.16``) is written instead.

Precision (``docs/frf.md``): dataset 58 is written binary (``58b``), exact; 55 and 15 exist
only in ASCII with fixed 13-column fields (``6E13.5``, ``1P3E13.5``), and pyuff reads them by
cutting each line into 13-character slices, so no more than 7 or 8 significant digits can be
carried there; the exact copy of the modes is the 2414 dataset, which pyuff reads by splitting
on blanks (``tests/test_uff.py``: shapes and eigenvalues to 1e-15).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from substruct.analysis.results import Modes
from substruct.case.frf_files import label_node_dir
from substruct.io.hdf5 import atomic_path
from substruct.run.result import Result

__all__ = ["QUANTITY_CODES", "uff58_sets", "uff58_bytes", "uff55_sets", "uff15_set", "uff2411_set",
           "uff2414_text", "modes_from_2414", "write_uff", "read_uff", "frf_nodes", "uff_path",
           "export_uff", "E13_EXACT_NODES"]

#: Node positions ``x = k`` are exact in dataset 15's ``E13.5`` fields up to this many nodes.
E13_EXACT_NODES = 999_999

#: UFF specific data types of the ordinate of each quantity (denominator: force, 13).
QUANTITY_CODES = {"receptance": 8, "mobility": 11, "accelerance": 12}


def frf_nodes(points: Sequence[str], coordinates: Sequence[str] = ()
              ) -> tuple[dict[str, tuple[int, int]], int]:
    """``(node, direction)`` of each point name, and the number of nodes ``N`` (dataset 15
    defines the nodes ``1 .. N``):

    * coordinate ``k`` of the model (``coordinates[k]``, ``"P.q1"``) is node ``k + 1``, the
      node of its value in the 55 and 2414 datasets, so a point that is a coordinate
      (``"P@q1"``) is that node, direction ``x`` (1);
    * a label ``"<node>:<dir>"`` (an FRF file's coordinate, no ``@``) is that node and
      direction;
    * a point ``"<part>@<node>:<dir>"`` (a coordinate of an FRF part) is one new node for each
      ``(part, node)``, in that direction;
    * any other point (a position along a rod) is a new node, direction ``x``.

    New nodes are numbered after the coordinates and the given nodes, in the order of
    ``points``; distinct names never share a node and direction.
    """
    where = {lab: k + 1 for k, lab in enumerate(coordinates)}
    given: dict[str, tuple[int, int]] = {}
    for name in points:
        if "@" not in name:
            try:
                given[name] = label_node_dir(name)
            except ValueError:
                pass
    last = max([len(coordinates), *(n for n, _ in given.values())])
    part_nodes: dict[tuple[str, int], int] = {}
    out: dict[str, tuple[int, int]] = {}
    for name in points:
        if name in out:
            continue
        sub, at, local = name.partition("@")
        if name in given:
            out[name] = given[name]
        elif at and f"{sub}.{local}" in where:
            out[name] = (where[f"{sub}.{local}"], 1)
        else:
            try:
                node, direction = label_node_dir(local) if at else (0, 0)
            except ValueError:
                node, direction = 0, 0
            if node:
                if (sub, node) not in part_nodes:
                    last += 1
                    part_nodes[(sub, node)] = last
                out[name] = (part_nodes[(sub, node)], direction)
            else:
                last += 1
                out[name] = (last, 1)
    return out, last


def uff58_sets(omega: np.ndarray, H: np.ndarray, outputs: Sequence[str],
               inputs: Sequence[str], quantity: str = "receptance",
               nodes: Mapping[str, tuple[int, int]] | None = None) -> list[dict[str, Any]]:
    """The UFF 58 datasets of ``H[k, i, j]`` (output ``i`` per input ``j``) at ``omega``
    (rad/s; written in Hz), the points numbered by ``nodes`` (:func:`frf_nodes` of the points
    alone if ``None``).  Written by :func:`uff58_bytes` (``pyuff`` cannot write a function of
    one point)."""
    if nodes is None:
        nodes = frf_nodes([*outputs, *inputs])[0]
    x = np.asarray(omega, dtype=float) / (2 * np.pi)
    sets: list[dict[str, Any]] = []
    for i, out in enumerate(outputs):
        for j, inp in enumerate(inputs):
            rsp, ref = nodes[out], nodes[inp]
            sets.append({
                "type": 58, "binary": 1, "func_type": 4, "func_id": len(sets) + 1,
                "ver_num": 0, "load_case_id": 0, "id1": "substruct FRF", "id2": quantity,
                "id3": "NONE", "id4": f"response {out}", "id5": f"reference {inp}",
                "rsp_ent_name": "resp", "rsp_node": rsp[0], "rsp_dir": rsp[1],
                "ref_ent_name": "ref", "ref_node": ref[0], "ref_dir": ref[1],
                "ord_data_type": 6, "abscissa_spacing": 0, "abscissa_spec_data_type": 18,
                "ordinate_spec_data_type": QUANTITY_CODES[quantity],
                "orddenom_spec_data_type": 13, "z_axis_spec_data_type": 0,
                "data": np.asarray(H[:, i, j], dtype=complex), "x": x})
    return sets


def uff58_bytes(dset: Mapping[str, Any]) -> bytes:
    """One function of :func:`uff58_sets` as a binary dataset 58 (``58b``): little endian,
    IEEE 754 doubles, complex ordinate with uneven abscissa (record 12: ``x, Re y, Im y`` a
    point); the id line declares the bytes that follow the 11 header records."""
    x = np.asarray(dset["x"], dtype=float)
    y = np.asarray(dset["data"], dtype=complex)
    table = np.empty((x.size, 3))
    table[:, 0], table[:, 1], table[:, 2] = x, y.real, y.imag
    data = table.astype("<f8").tobytes()

    def ident(text: str) -> str:
        return f"{(text or 'NONE')[:80]:<80}"

    def axis(code: int, label: str, units: str) -> str:
        return f"{code:10d}{0:5d}{0:5d}{0:5d} {label:<20.20} {units:<20.20}"

    head = [f"{-1:6d}", f"{58:6d}b{1:6d}{2:6d}{11:12d}{len(data):12d}{0:6d}{0:6d}{0:12d}{0:12d}",
            *(ident(str(dset[k])) for k in ("id1", "id2", "id3", "id4", "id5")),
            f"{4:5d}{dset['func_id']:10d}{0:5d}{0:10d} {dset['rsp_ent_name']:<10.10}"
            f"{dset['rsp_node']:10d}{dset['rsp_dir']:4d} {dset['ref_ent_name']:<10.10}"
            f"{dset['ref_node']:10d}{dset['ref_dir']:4d}",
            f"{6:10d}{x.size:10d}{0:10d}{0.0:13.5e}{0.0:13.5e}{0.0:13.5e}",
            axis(18, "Frequency", "Hz"),
            axis(int(dset["ordinate_spec_data_type"]), str(dset["id2"]), "NONE"),
            axis(13, "Force", "NONE"), axis(0, "NONE", "NONE")]
    text = "\n".join(head) + "\n"
    return text.encode("ascii", errors="replace") + data + f"{-1:6d}\n".encode("ascii")


def uff55_sets(modes: Modes, name: str = "") -> list[dict[str, Any]]:
    """One UFF 55 dataset per mode: coordinate ``k`` of the shape as node ``k``, ``x``."""
    import pyuff

    n = modes.shapes.shape[0]
    nodes = np.arange(1, n + 1)
    sets = []
    for k in range(len(modes)):
        u = np.asarray(modes.shapes[:, k], dtype=complex)
        zero = np.zeros(n, dtype=complex)
        lam = complex(modes.eigenvalues[k])
        sets.append(pyuff.prepare_55(
            id1=f"substruct modes {name}"[:80], id2=f"mode {k + 1}", id3=modes.method[:80],
            id4=f"omega {modes.omega[k]:.12g} rad/s", id5="", model_type=1,
            analysis_type=3, data_ch=2, spec_data_type=8, data_type=5, n_data_per_node=3,
            load_case=1, mode_n=k + 1, eig=lam, modal_a=0j, modal_b=0j,
            node_nums=nodes, r1=u, r2=zero, r3=zero))
    return sets


def uff15_set(n: int) -> dict[str, Any]:
    """The nodes ``1 .. n`` at ``(k, 0, 0)``."""
    import pyuff

    k = np.arange(1, n + 1)
    zero = np.zeros(n, dtype=int)
    return pyuff.prepare_15(node_nums=k, def_cs=zero, disp_cs=zero, color=np.ones(n, dtype=int),
                            x=k.astype(float), y=np.zeros(n), z=np.zeros(n))


def uff2411_set(n: int) -> dict[str, Any]:
    """The nodes ``1 .. n`` at ``(k, 0, 0)`` as the double-precision node dataset 2411."""
    import pyuff

    k = np.arange(1, n + 1)
    zero = np.zeros(n, dtype=int)
    return pyuff.prepare_2411(node_nums=k, def_cs=zero + 1, disp_cs=zero + 1,
                              color=np.ones(n, dtype=int), x=k.astype(float), y=np.zeros(n),
                              z=np.zeros(n))


def uff2414_text(modes: Modes, name: str = "") -> str:
    r"""The modes as UFF 2414 datasets (analysis data), one per mode, in double precision.

    Record 9: model type 1 (structural), analysis type 3 (complex eigenvalue, first order),
    data characteristic 1 (scalar), result type 94 (unknown scalar: a generalized
    coordinate), data type 6 (double precision complex), one value a node; records 12-13:
    the frequency (Hz), the damping ratio and the eigenvalue :math:`\lambda_k` in
    ``E13.5``; record 2: ``mode k lambda <re>
    <im>`` to 17 significant digits; records 14-15: node ``k`` (coordinate ``k`` of the model)
    and ``Re u_k, Im u_k`` in ``2D25.16`` (``%25.16e``: 17 significant digits, the double
    itself).
    """
    lines = []
    n = modes.shapes.shape[0]
    for k in range(len(modes)):
        lam = complex(modes.eigenvalues[k])
        w, zeta = float(modes.omega[k]), float(modes.damping_ratio[k])
        head = [f"{-1:6d}", f"{2414:6d}", f"{k + 1:10d}",
                f"mode {k + 1} lambda {lam.real:.17g} {lam.imag:.17g}"[:80], f"{1:10d}",
                f"substruct modes {name}"[:80], f"mode {k + 1}", modes.method[:80],
                f"omega {w:.17g} rad/s"[:80], f"damping ratio {zeta:.17g}"[:80],
                "".join(f"{v:10d}" for v in (1, 3, 1, 94, 6, 1)),
                "".join(f"{v:10d}" for v in (1, 0, 1, 0, 1, k + 1, 0, 0)),
                "".join(f"{v:10d}" for v in (0, 0)),
                "".join(f"{v:13.5e}" for v in (0.0, w / (2 * np.pi), 0.0, 0.0, zeta, 0.0)),
                "".join(f"{v:13.5e}" for v in (lam.real, lam.imag, 0.0, 0.0, 0.0, 0.0))]
        lines += head
        u = np.asarray(modes.shapes[:, k], dtype=complex)
        for node in range(n):
            lines.append(f"{node + 1:10d}")
            lines.append(f"{u[node].real:25.16e}{u[node].imag:25.16e}")
        lines.append(f"{-1:6d}")
    return "\n".join(lines) + "\n" if lines else ""


def modes_from_2414(sets: Sequence[dict[str, Any]]) -> tuple[np.ndarray, np.ndarray]:
    """``(eigenvalues, shapes)`` of the 2414 datasets of :func:`uff2414_text` as ``pyuff``
    reads them (the eigenvalue from record 2, the shape from records 14-15).

    Raises:
        ValueError: no 2414 dataset of complex modes.
    """
    modal = [s for s in sets if s.get("type") == 2414 and s.get("analysis_type") == 3]
    if not modal:
        raise ValueError("no UFF 2414 dataset of complex modes")
    lam, shapes = [], []
    for s in modal:
        words = str(s["analysis_dataset_name"]).split()
        lam.append(complex(float(words[3]), float(words[4])))
        order = np.argsort(s["node_nums"])
        values = np.array([s["data_at_node"][i] for i in order], dtype=float)
        shapes.append(values[:, 0] + 1j * values[:, 1])
    return np.array(lam), np.array(shapes).T


def write_uff(path: str | os.PathLike, sets: Sequence[dict[str, Any]],
              text: str = "") -> Path:
    """Write the datasets to ``path`` (replacing it) in their order (58 by
    :func:`uff58_bytes`, the others by ``pyuff``), then the datasets already written as
    ``text`` (:func:`uff2414_text`), and return it.

    Raises:
        ValueError: ``pyuff`` refused a dataset (it writes nothing then).
    """
    import pyuff

    p = Path(path)
    p.unlink(missing_ok=True)
    p.touch()
    try:  # "add" to a new file: pyuff's "overwrite" truncates the header of binary 58 sets
        for s in sets:
            if s.get("type") == 58:
                with open(p, "ab") as fh:
                    fh.write(uff58_bytes(s))
            else:
                pyuff.UFF(str(p)).write_sets([s], mode="add")
    except Exception as err:  # pyuff raises plain Exceptions
        p.unlink(missing_ok=True)
        raise ValueError(f"UFF export of {p.name}: {' '.join(str(err).split())}") from None
    if text:
        with open(p, "a", encoding="ascii") as fh:
            fh.write(text)
    return p


def read_uff(path: str | os.PathLike) -> list[dict[str, Any]]:
    """Every dataset of a UFF file, as ``pyuff`` reads it."""
    import pyuff

    sets = pyuff.UFF(str(path)).read_sets()
    return [sets] if isinstance(sets, dict) else list(sets)


def uff_path(result: Result, out: str | os.PathLike) -> Path:
    """Where :func:`export_uff` writes: ``out`` if it ends in ``.uff`` or ``.unv``, else
    ``out/<case>.uff`` (the case name read from the result through
    :func:`~substruct.io.paths.safe_stem`: never a path outside ``out``)."""
    from substruct.io.paths import safe_stem

    p = Path(out)
    return p if p.suffix.lower() in (".uff", ".unv") else \
        p / f"{safe_stem(result.case_name)}.uff"


def export_uff(result: Result, out: str | os.PathLike, force: bool = False) -> Path:
    """Write the result's receptances (58), modes (55, and 2414 in double precision) and the
    nodes of both (15, or 2411 above :data:`E13_EXACT_NODES`: the model's coordinates, then
    the other points of the receptances, :func:`frf_nodes`) to one UFF file
    (:func:`uff_path`), atomically; return its path.  A result that keeps the channel
    geometry of its virtual points (``/channels``) is written with the test's header, units,
    nodes and systems instead of 15 (:mod:`substruct.io.uff_channels`).

    Raises:
        FileExistsError: the file exists and ``force`` is not set.
        ValueError: a result with neither modes nor receptances.
    """
    path = uff_path(result, out)
    if path.exists() and not force:
        raise FileExistsError(f"{path} exists; use --force to overwrite it")
    sets: list[dict[str, Any]] = []
    text = ""
    modes, frf = result.modes, result.frf
    coordinates = list(result.model.dof_labels)
    if modes is not None and modes.shapes.shape[0] != len(coordinates):
        coordinates = [f"coordinate {k + 1}" for k in range(modes.shapes.shape[0])]
    points = [] if frf is None else [*frf.outputs, *frf.inputs]
    geometry = None
    if result.channels:
        from substruct.io.uff_channels import channel_nodes, geometry_sets

        geometry = channel_nodes(points, coordinates, result.channels)
        nodes, n = geometry.where, len(geometry.xyz)
    else:
        nodes, n = frf_nodes(points, coordinates)
    if modes is not None and len(modes):
        sets += uff55_sets(modes, result.case_name)
        text = uff2414_text(modes, result.case_name)
    if frf is not None:
        sets += uff58_sets(frf.omega, frf.H, frf.outputs, frf.inputs, frf.quantity, nodes)
    if not sets:
        raise ValueError(f"{result.case_name}: no modes and no receptances to export")
    if geometry is not None:
        sets[:0] = geometry_sets(geometry, result.case_name)
    else:
        sets.insert(0, uff15_set(n) if n <= E13_EXACT_NODES else uff2411_set(n))
    with atomic_path(path, suffix=".uff") as tmp:
        write_uff(tmp, sets, text)
    return path
