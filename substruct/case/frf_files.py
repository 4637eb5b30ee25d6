r"""Reading receptances from files: NPZ and Universal File Format dataset 58.

* NPZ (:func:`substruct.case.npz_files.read_npz`: headers and sizes checked before reading):
  ``H`` ``(n_omega, n, n)`` of numbers (``H[k, i, j] = u_i / F_j``), ``labels`` (``n``
  strings), and ``omega`` (rad/s) or ``freq_hz``;
* UFF 58 (:func:`substruct.case.uff_records.read_uff_records`, ASCII or binary ``58b``): one
  function per (response, reference) pair, labelled ``"<node>:<dir>"`` with the directions
  ``1..6`` as ``x, y, z, rx, ry, rz``; a negative direction flips the sign.  Every pair of the
  square matrix must be there.  The header codes are honoured or refused
  (:func:`_as_receptance`): function type 4 (FRF) only; load case 0; abscissa data type 18
  (frequency) in Hz; ordinate displacement (8), velocity (11) or acceleration (12) over
  excitation force (13), the last two turned into receptances exactly,
  :math:`H = V / (i\omega)`, :math:`H = A / (i\omega)^2`, with :math:`\omega = 2\pi f > 0`;
  a real ordinate (data types 2, 4) is a receptance with no imaginary part.  The units of a
  dataset 164 before the functions are honoured (the records are read in SI,
  :func:`substruct.case.uff_units.to_si`: a displacement over force at translations is
  multiplied by :math:`f_F / f_L`); the units
  exponents of records 8-10 (fields 2-4) are either all blank or 0 or those that 58's
  Addendum A gives the data type at the direction, and refused otherwise.  A function given
  twice (the same response and reference, after the sign of the directions) is read once if
  both copies are equal and refused otherwise.  If the file has node datasets (15, 2411),
  every response and reference node must be one of them.  The ASCII form stores the abscissa
  with 6 significant digits and the values with 13: a grid is given in values that 6 digits
  hold exactly (:func:`grid_problem` compares to :data:`GRID_DIGITS_RTOL`).

Both give ``(omega, labels, H)``; any problem is a ``ValueError`` of one line naming the file,
and for UFF the dataset, record and value.  A measured part reduced to virtual points needs
only its sensors x impacts: :func:`read_measured_file` gives ``(omega, outputs, inputs, H)``
of an ``.npz`` with ``outputs`` and ``inputs`` (``H`` of shape ``(n_omega, n_out, n_in)``)
or of a UFF file's responses x references (every pair given), with the same checks.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

import numpy as np

from substruct.case.npz_files import npz_members, read_npz
from substruct.case.uff_geometry import node_positions, uff_coordinate_systems
from substruct.case.uff_records import Uff58, read_uff_records
from substruct.case.uff_units import unit_exponents

__all__ = ["DIRECTIONS", "MAX_FRF_FILE", "GRID_DIGITS_RTOL", "read_frf_file",
           "read_measured_file", "uff_label",
           "label_node_dir", "grid_problem", "FUNCTION_TYPES", "ORDINATES"]

#: UFF direction codes 1..6.
DIRECTIONS = ("x", "y", "z", "rx", "ry", "rz")
#: Largest FRF file read, in bytes.
MAX_FRF_FILE = 2_000_000_000
#: The relative precision of a UFF 58 ASCII abscissa (6 significant digits).
GRID_DIGITS_RTOL = 5e-6


def uff_label(node: int, direction: int) -> str:
    """``"<node>:<dir>"`` for a UFF node and direction code (the sign is the caller's)."""
    d = abs(int(direction))
    if not 1 <= d <= 6:
        raise ValueError(f"UFF direction {direction} is not one of 1..6 (x, y, z, rx, ry, rz)")
    return f"{int(node)}:{DIRECTIONS[d - 1]}"


def label_node_dir(label: str) -> tuple[int, int]:
    """The UFF node and direction code of a label ``"<node>:<dir>"``.

    Raises:
        ValueError: a label not of that form.
    """
    node, _, d = label.partition(":")
    if not node.isdigit() or d not in DIRECTIONS:
        raise ValueError(f"label {label!r} is not <node>:<dir> (dir one of "
                         f"{', '.join(DIRECTIONS)}), as UFF needs")
    return int(node), DIRECTIONS.index(d) + 1


def _check_file(path: Path) -> None:
    try:
        info = os.stat(path)
    except OSError as err:
        raise ValueError(f"cannot read {path.name}: {err.strerror}") from None
    if not stat.S_ISREG(info.st_mode):
        raise ValueError(f"{path.name} is not a regular file")
    if info.st_size > MAX_FRF_FILE:
        raise ValueError(f"{path.name} has {info.st_size} bytes, more than the "
                         f"{MAX_FRF_FILE} accepted")


def _read_npz(path: Path, rectangular: bool = False
              ) -> tuple[np.ndarray, list[str], list[str], np.ndarray]:
    """``(omega, outputs, inputs, H)`` of an archive with ``labels`` (square; outputs and
    inputs the same list) or, when ``rectangular``, with ``outputs`` and ``inputs``."""
    names = npz_members(path)
    keys = ["labels"]
    if rectangular and "labels" not in names and {"outputs", "inputs"} <= names.keys():
        keys = ["outputs", "inputs"]
    if "H" not in names or not set(keys) <= names.keys() or \
            not names.keys() & {"omega", "freq_hz"}:
        want = "labels (or outputs and inputs)" if rectangular else "labels"
        raise ValueError(f"{path.name} needs arrays H, {want} and omega (or freq_hz); "
                         f"it has {', '.join(sorted(names)) or 'none'}")
    if {"omega", "freq_hz"} <= names.keys():
        raise ValueError(f"{path.name} has both omega and freq_hz: give the grid once")
    other = sorted(names.keys() - {"H", "omega", "freq_hz", *keys})
    if other:
        raise ValueError(f"{path.name}: arrays {', '.join(repr(k[:40]) for k in other[:5])} "
                         f"are not read (an FRF file holds H, {' and '.join(keys)} and omega "
                         "or freq_hz); they would go unused")
    grid = "omega" if "omega" in names else "freq_hz"
    for key, kinds in (("H", "biufc"), (grid, "biuf"), *((k, "U") for k in keys)):
        if names[key].dtype.kind not in kinds:
            raise ValueError(f"{path.name}: {key} holds {names[key].dtype} entries, not "
                             f"{'strings' if key in keys else 'numbers'}")
    z = read_npz(path, ["H", *keys, grid], {"H": np.complex128, grid: np.float64})
    for key in (grid, *keys):
        if z[key].ndim != 1:
            raise ValueError(f"{path.name}: {key} must be a 1-D array, it has the shape "
                             f"{list(z[key].shape)}")
    lists = [[str(s) for s in z[k].ravel()] for k in keys]
    omega = z[grid] if grid == "omega" else 2 * np.pi * z[grid]
    return omega, lists[0], lists[-1], z["H"]


#: Longest coordinate label read from an FRF file (characters).
MAX_FRF_LABEL = 64


#: UFF 58 function types (record 6 field 1), for the messages.
FUNCTION_TYPES = {0: "general or unknown", 1: "time response", 2: "auto spectrum",
                  3: "cross spectrum", 4: "frequency response function",
                  5: "transmissibility", 6: "coherence", 9: "power spectral density"}
#: The ordinates (record 9 field 1, over 13, excitation force) read and the power ``p`` of
#: ``i omega`` that turns each into a receptance: ``H = Y / (i omega)^p``.
ORDINATES = {8: ("displacement", 0), 11: ("velocity", 1), 12: ("acceleration", 2)}


def _as_receptance(f: Uff58) -> np.ndarray:
    """The receptance of one function: its header codes checked (or refused), a mobility
    divided by ``i omega``, an accelerance by ``(i omega)^2``, ``omega = 2 pi x > 0``."""
    w = f.where
    if f.func_type != 4:
        what = FUNCTION_TYPES.get(f.func_type, "another function")
        raise ValueError(f"{w}: record 6 field 1, function type {f.func_type} ({what}): only "
                         "4 (frequency response function) is coupled")
    if f.load_case != 0:
        raise ValueError(f"{w}: record 6 field 4, load case {f.load_case}: only 0 (single "
                         "point excitation) has a reference coordinate")
    if f.abscissa != 18:
        raise ValueError(f"{w}: record 8 field 1, abscissa data type {f.abscissa}: only 18 "
                         "(frequency, in Hz) is read")
    if f.abscissa_units.upper() not in ("", "NONE", "HZ"):
        raise ValueError(f"{w}: record 8 field 6, abscissa units {f.abscissa_units!r}: the "
                         "abscissa is read in Hz")
    if f.numerator not in ORDINATES or f.denominator != 13:
        raise ValueError(f"{w}: records 9-10 field 1, ordinate {f.numerator} over "
                         f"{f.denominator}: only displacement, velocity or acceleration (8, "
                         "11, 12) over excitation force (13) is read")
    for k, (code, d) in enumerate(((18, 0), (f.numerator, f.rsp_dir), (13, f.ref_dir))):
        given = f.exponents[k] if f.exponents else (0, 0, 0)
        own = (*unit_exponents(code, d), 0)
        if any(given) and tuple(given) != own:
            raise ValueError(f"{w}: record {8 + k} fields 2-4, units exponents (length, force,"
                             f" temperature) {list(given)}: data type {code} at direction {d} "
                             f"has {list(own)} (58 Addendum A)")
    if f.spacing == 1 and not f.x_inc > 0:
        raise ValueError(f"{w}: record 7 field 5, abscissa increment {f.x_inc:g}: even "
                         "spacing needs a positive increment")
    power = ORDINATES[f.numerator][1]
    if power == 0:
        return f.y
    if not np.all(f.x > 0):
        raise ValueError(f"{w}: record 12, frequency {float(f.x.min()):g} Hz: a "
                         f"{ORDINATES[f.numerator][0]} over force is turned into a receptance "
                         "by dividing by (i omega)^p, which needs omega > 0")
    return f.y / (1j * 2 * np.pi * f.x) ** power


def _read_uff58(path: Path, rectangular: bool = False
                ) -> tuple[np.ndarray, list[str], list[str], np.ndarray]:
    """``(omega, outputs, inputs, H)``: every label on both sides (the square matrix) or,
    when ``rectangular``, the responses (in the order met) x the references."""
    read = read_uff_records(path)
    try:  # the geometry is not used here, but a file whose geometry is broken is refused
        node_positions(read, uff_coordinate_systems(read))
    except ValueError as err:  # a system's message names the file already, a node's not
        text = str(err)
        raise ValueError(text if text.startswith(path.name) else f"{path.name}: {text}"
                         ) from None
    frfs = read.functions
    if not frfs:
        raise ValueError(f"{path.name} holds no UFF 58 function")
    x = frfs[0].x
    entries: dict[tuple[str, str], tuple[np.ndarray, str]] = {}
    order: list[str] = []
    rows: list[str] = []
    cols: list[str] = []
    for f in frfs:
        for node, which in ((f.rsp_node, "6 (response node)"), (f.ref_node,
                                                                 "9 (reference node)")):
            if read.nodes is not None and node not in read.nodes:
                raise ValueError(f"{f.where}: record 6 field {which} {node} is not a node of "
                                 "the file's datasets 15/2411")
        pair = []
        for node, code, which in ((f.rsp_node, f.rsp_dir, "7 (response direction)"),
                                  (f.ref_node, f.ref_dir, "10 (reference direction)")):
            try:
                pair.append(uff_label(node, code))
            except ValueError as err:
                raise ValueError(f"{f.where}: record 6 field {which}: {err}") from None
        rsp, ref = pair
        if f.x.shape != x.shape or not np.allclose(f.x, x, rtol=1e-12, atol=0):
            raise ValueError(f"{f.where}: the function {rsp}/{ref} has another abscissa "
                             f"than the first ({f.x.size} vs {x.size} points)")
        if not (np.all(np.isfinite(f.x)) and np.all(np.isfinite(f.y))):
            raise ValueError(f"{f.where}: record 12, values that are not finite (NaN or "
                             f"infinite) in the function {rsp}/{ref}")
        sign = np.sign(f.rsp_dir) * np.sign(f.ref_dir)
        data = sign * _as_receptance(f)
        if (rsp, ref) in entries:
            first, where = entries[(rsp, ref)]
            if not np.array_equal(first, data):
                raise ValueError(f"{f.where}: the function {rsp}/{ref} is also in {where}, "
                                 "with other values")
            continue  # an identical copy
        entries[(rsp, ref)] = (data, f.where.split(": ", 1)[1])
        for lab, into in ((rsp, order), (ref, order), (rsp, rows), (ref, cols)):
            if lab not in into:
                into.append(lab)
    if not rectangular:
        rows, cols = order, order
    need = "the virtual points need every sensor x impact" if rectangular else \
        "coupling needs the whole square matrix"
    H = np.empty((x.size, len(rows), len(cols)), dtype=complex)
    for i, rsp in enumerate(rows):
        for j, ref in enumerate(cols):
            if (rsp, ref) not in entries:
                raise ValueError(f"{path.name} lacks the function of response {rsp} to "
                                 f"reference {ref}: {need}")
            H[:, i, j] = entries[(rsp, ref)][0]
    return 2 * np.pi * x, rows, cols, H


def grid_problem(name: str, omega: np.ndarray, grid: np.ndarray, interpolate: str
                 ) -> str | None:
    """Why the receptances of ``name`` on ``omega`` cannot be put on the analysis ``grid``
    (rad/s), or ``None``: the grids agree to :data:`GRID_DIGITS_RTOL`, or ``interpolate`` is
    ``"linear"`` and ``omega`` covers ``grid`` (no extrapolation)."""
    if omega.shape == grid.shape and np.allclose(omega, grid, rtol=GRID_DIGITS_RTOL, atol=0):
        return None
    if interpolate != "linear":
        return (f"the frequency grid of {name} differs from analysis.frf.omega ({len(omega)} "
                f"vs {len(grid)} frequencies); give interpolate: linear to interpolate {name} "
                "onto it")
    lo, hi = float(omega.min()), float(omega.max())
    if grid.min() < lo * (1 - GRID_DIGITS_RTOL) or grid.max() > hi * (1 + GRID_DIGITS_RTOL):
        return (f"{name} covers {lo:g} to {hi:g} rad/s, not the grid of analysis.frf.omega "
                f"({grid.min():g} to {grid.max():g}): no extrapolation")
    return None


def read_frf_file(path: str | os.PathLike) -> tuple[np.ndarray, list[str], np.ndarray]:
    """``(omega, labels, H)`` from an ``.npz`` or a UFF (``.uff``, ``.unv``) file: a square
    receptance.

    Raises:
        ValueError: a missing or unreadable file, shapes that do not agree, a grid that is not
            ascending and positive, values that are not finite.
    """
    omega, labels, _, H = _read(Path(path), False)
    return omega, labels, H


def read_measured_file(path: str | os.PathLike
                       ) -> tuple[np.ndarray, list[str], list[str], np.ndarray]:
    r"""``(omega, outputs, inputs, H)``, ``H[k, i, j] = u_{out_i} / F_{in_j}``: the
    receptances of a measured part that need not be square (sensors x impacts): an ``.npz``
    with ``labels`` (square) or ``outputs`` and ``inputs`` (``H`` of shape ``(n_omega,
    n_out, n_in)``), or a UFF file, its responses x its references (every pair given).

    Raises:
        ValueError: as :func:`read_frf_file`; a response x reference pair missing.
    """
    return _read(Path(path), True)


def _read(p: Path, rectangular: bool
          ) -> tuple[np.ndarray, list[str], list[str], np.ndarray]:
    _check_file(p)
    suffix = p.suffix.lower()
    if suffix == ".npz":
        omega, outs, ins, H = _read_npz(p, rectangular)
    elif suffix in (".uff", ".unv"):
        omega, outs, ins, H = _read_uff58(p, rectangular)
    else:
        raise ValueError(f"{p.name}: an FRF file is .npz, .uff or .unv")
    if H.shape != (omega.size, len(outs), len(ins)):
        if outs is ins:
            raise ValueError(f"{p.name}: H has shape {list(H.shape)}, expected "
                             f"[{omega.size}, {len(outs)}, {len(outs)}] for {omega.size} "
                             f"frequencies and {len(outs)} labels")
        raise ValueError(f"{p.name}: H has shape {list(H.shape)}, expected [{omega.size}, "
                         f"{len(outs)}, {len(ins)}] for {omega.size} frequencies, "
                         f"{len(outs)} outputs and {len(ins)} inputs")
    for names in (outs, ins):
        if len(set(names)) != len(names):
            raise ValueError(f"{p.name}: labels repeated")
    for label in (*outs, *ins):  # names of coordinates: they reach messages, results, exports
        if not 1 <= len(label) <= MAX_FRF_LABEL or not label.isprintable() or \
                label != label.strip():
            raise ValueError(f"{p.name}: a label is 1 to {MAX_FRF_LABEL} printable characters "
                             f"without surrounding blanks: {label[:40]!r}")
    if not (np.all(np.isfinite(omega)) and np.all(np.isfinite(H))):
        raise ValueError(f"{p.name}: frequencies and receptances must be finite")
    if omega.size == 0 or np.any(omega <= 0) or np.any(np.diff(omega) <= 0):
        raise ValueError(f"{p.name}: the frequencies must be positive and ascending")
    return omega, outs, ins, H
