r"""Universal File Format export (``pyuff``): receptances as dataset 58, modes as 55, the
nodes as 15.

* **58** (one function per output/input pair): abscissa in Hz (uneven spacing, the grid as
  computed), ordinate complex double (``ord_data_type 6``, 13 significant digits in ASCII);
  ``func_type 4`` (frequency response function), ordinate displacement, velocity or
  acceleration over force for receptance, mobility or accelerance (spec data types 8, 11, 12
  over 13).  A point named ``<node>:<dir>`` is written as that node and direction; any other
  name as node ``k`` (its 1-based place among the points) in direction ``x``, with the
  names in the id lines (``id4`` response, ``id5`` reference).
* **55** (one dataset per mode): the complex shape, one node per coordinate of the model
  (node ``k`` = coordinate ``k``, value in ``x``; ``data_ch 2``, 3 values a node), with the
  frequency (Hz), the damping ratio and the eigenvalue; the coordinate labels are listed in
  the id lines of the 15 dataset's header.
* **2414** (one dataset per mode, :func:`uff2414_text`): the same shapes in double precision,
  analysis type 3 (complex eigenvalue), data at nodes, data type 6 (double complex), one value
  a node (``x``), written ``2D25.16`` (50 columns: within the 80 of a record); the eigenvalue
  to 17 digits in record 2 (the dataset name), as records 12-13 hold only ``E13.5``.
* **15**: the nodes ``1 .. n`` of the 55 datasets at ``x = k`` (the model's coordinates are
  generalized ones, not points in space): integers, exact in ``E13.5`` up to 999,999 nodes;
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
from typing import Any, Sequence

import numpy as np

from substruct.analysis.results import Modes
from substruct.case.frf_files import label_node_dir
from substruct.io.hdf5 import atomic_path
from substruct.run.result import Result

__all__ = ["QUANTITY_CODES", "uff58_sets", "uff55_sets", "uff15_set", "uff2411_set",
           "uff2414_text", "modes_from_2414", "write_uff", "read_uff", "frf_nodes", "uff_path",
           "export_uff", "E13_EXACT_NODES"]

#: Node positions ``x = k`` are exact in dataset 15's ``E13.5`` fields up to this many nodes.
E13_EXACT_NODES = 999_999

#: UFF specific data types of the ordinate of each quantity (denominator: force, 13).
QUANTITY_CODES = {"receptance": 8, "mobility": 11, "accelerance": 12}


def frf_nodes(names: Sequence[str]) -> list[tuple[int, int]]:
    """``(node, direction)`` of each point name: ``<node>:<dir>`` as such, any other name
    as its 1-based place in ``names``, direction ``x``."""
    out = []
    for k, name in enumerate(names):
        try:
            out.append(label_node_dir(name))
        except ValueError:
            out.append((k + 1, 1))
    return out


def uff58_sets(omega: np.ndarray, H: np.ndarray, outputs: Sequence[str],
               inputs: Sequence[str], quantity: str = "receptance") -> list[dict[str, Any]]:
    """The UFF 58 datasets of ``H[k, i, j]`` (output ``i`` per input ``j``) at ``omega``
    (rad/s; written in Hz)."""
    import pyuff

    x = np.asarray(omega, dtype=float) / (2 * np.pi)
    rsp, ref = frf_nodes(outputs), frf_nodes(inputs)
    sets = []
    for i, out in enumerate(outputs):
        for j, inp in enumerate(inputs):
            sets.append(pyuff.prepare_58(
                binary=1, func_type=4, ver_num=0, load_case_id=0,
                id1="substruct FRF", id2=quantity, id3="", id4=f"response {out}"[:80],
                id5=f"reference {inp}"[:80], rsp_ent_name="resp", rsp_node=rsp[i][0],
                rsp_dir=rsp[i][1], ref_ent_name="ref", ref_node=ref[j][0], ref_dir=ref[j][1],
                ord_data_type=6, abscissa_spacing=0, abscissa_min=0.0, abscissa_inc=0.0,
                z_axis_value=0.0, abscissa_spec_data_type=18,
                ordinate_spec_data_type=QUANTITY_CODES[quantity], orddenom_spec_data_type=13,
                z_axis_spec_data_type=0, data=np.asarray(H[:, i, j], dtype=complex), x=x))
    return sets


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
    """Write the datasets to ``path`` (replacing it), then the datasets already written as
    ``text`` (:func:`uff2414_text`), and return it.

    Raises:
        ValueError: ``pyuff`` refused a dataset (it writes nothing then).
    """
    import pyuff

    p = Path(path)
    p.unlink(missing_ok=True)
    try:  # "add" to a new file: pyuff's "overwrite" truncates the header of binary 58 sets
        if sets:
            pyuff.UFF(str(p)).write_sets(list(sets), mode="add")
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
    """Where :func:`export_uff` writes: ``out`` if it ends in ``.uff``, else
    ``out/<case>.uff`` (the case name read from the result through
    :func:`~substruct.io.paths.safe_stem`: never a path outside ``out``)."""
    from substruct.io.paths import safe_stem

    p = Path(out)
    return p if p.suffix.lower() == ".uff" else p / f"{safe_stem(result.case_name)}.uff"


def export_uff(result: Result, out: str | os.PathLike, force: bool = False) -> Path:
    """Write the result's receptances (58), modes (55, and 2414 in double precision) and their
    nodes (15, or 2411 above :data:`E13_EXACT_NODES`) to one UFF file (:func:`uff_path`),
    atomically; return its path.

    Raises:
        FileExistsError: the file exists and ``force`` is not set.
        ValueError: a result with neither modes nor receptances.
    """
    path = uff_path(result, out)
    if path.exists() and not force:
        raise FileExistsError(f"{path} exists; use --force to overwrite it")
    sets: list[dict[str, Any]] = []
    text = ""
    if result.modes is not None and len(result.modes):
        n = result.modes.shapes.shape[0]
        sets.append(uff15_set(n) if n <= E13_EXACT_NODES else uff2411_set(n))
        sets += uff55_sets(result.modes, result.case_name)
        text = uff2414_text(result.modes, result.case_name)
    frf = result.frf
    if frf is not None:
        sets += uff58_sets(frf.omega, frf.H, frf.outputs, frf.inputs, frf.quantity)
    if not sets:
        raise ValueError(f"{result.case_name}: no modes and no receptances to export")
    with atomic_path(path, suffix=".uff") as tmp:
        write_uff(tmp, sets, text)
    return path
