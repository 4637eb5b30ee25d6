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
* **15**: the nodes ``1 .. n`` of the 55 datasets at ``x = k`` (the model's coordinates are
  generalized ones, not points in space).

ASCII UFF holds an abscissa to 6 significant digits and values to 13: the round trip of the
values is exact to ``5e-13`` relative (``tests/test_uff.py``).
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

__all__ = ["QUANTITY_CODES", "uff58_sets", "uff55_sets", "uff15_set", "write_uff",
           "read_uff", "frf_nodes", "uff_path", "export_uff"]

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


def write_uff(path: str | os.PathLike, sets: Sequence[dict[str, Any]]) -> Path:
    """Write the datasets to ``path`` (replacing it) and return it.

    Raises:
        ValueError: ``pyuff`` refused a dataset (it writes nothing then).
    """
    import pyuff

    p = Path(path)
    p.unlink(missing_ok=True)
    try:  # "add" to a new file: pyuff's "overwrite" truncates the header of binary 58 sets
        pyuff.UFF(str(p)).write_sets(list(sets), mode="add")
    except Exception as err:  # pyuff raises plain Exceptions
        p.unlink(missing_ok=True)
        raise ValueError(f"UFF export of {p.name}: {' '.join(str(err).split())}") from None
    return p


def read_uff(path: str | os.PathLike) -> list[dict[str, Any]]:
    """Every dataset of a UFF file, as ``pyuff`` reads it."""
    import pyuff

    sets = pyuff.UFF(str(path)).read_sets()
    return [sets] if isinstance(sets, dict) else list(sets)


def uff_path(result: Result, out: str | os.PathLike) -> Path:
    """Where :func:`export_uff` writes: ``out`` if it ends in ``.uff``, else
    ``out/<case>.uff``."""
    p = Path(out)
    return p if p.suffix.lower() == ".uff" else p / f"{result.case_name}.uff"


def export_uff(result: Result, out: str | os.PathLike, force: bool = False) -> Path:
    """Write the result's receptances (58), modes (55) and their nodes (15) to one UFF file
    (:func:`uff_path`), atomically; return its path.

    Raises:
        FileExistsError: the file exists and ``force`` is not set.
        ValueError: a result with neither modes nor receptances.
    """
    path = uff_path(result, out)
    if path.exists() and not force:
        raise FileExistsError(f"{path} exists; use --force to overwrite it")
    sets: list[dict[str, Any]] = []
    if result.modes is not None and len(result.modes):
        sets.append(uff15_set(result.modes.shapes.shape[0]))
        sets += uff55_sets(result.modes, result.case_name)
    frf = result.frf
    if frf is not None:
        sets += uff58_sets(frf.omega, frf.H, frf.outputs, frf.inputs, frf.quantity)
    if not sets:
        raise ValueError(f"{result.case_name}: no modes and no receptances to export")
    with atomic_path(path, suffix=".uff") as tmp:
        write_uff(tmp, sets)
    return path
