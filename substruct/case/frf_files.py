r"""Reading receptances from files: NPZ and Universal File Format dataset 58.

* NPZ: ``H`` complex ``(n_omega, n, n)`` (``H[k, i, j] = u_i / F_j``), ``labels`` (``n``
  strings), and ``omega`` (rad/s) or ``freq_hz``;
* UFF 58 (read with ``pyuff``): one function per (response, reference) pair, labelled
  ``"<node>:<dir>"`` with the directions ``1..6`` as ``x, y, z, rx, ry, rz``; a negative
  direction flips the sign; the abscissa in Hz.  Every pair of the square matrix must be
  there.  The ASCII form stores the abscissa with 6 significant digits and the values with
  13: a grid is given in values that 6 digits hold exactly (``common_grid`` compares to
  :data:`GRID_DIGITS_RTOL`).

Both give ``(omega, labels, H)``; any problem is a ``ValueError`` of one line.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

import numpy as np

__all__ = ["DIRECTIONS", "MAX_FRF_FILE", "GRID_DIGITS_RTOL", "read_frf_file", "uff_label",
           "label_node_dir"]

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


def _read_npz(path: Path) -> tuple[np.ndarray, list[str], np.ndarray]:
    try:
        with np.load(path, allow_pickle=False) as z:
            keys = set(z.files)
            if "H" not in keys or "labels" not in keys or not keys & {"omega", "freq_hz"}:
                raise ValueError(f"{path.name} needs arrays H, labels and omega (or freq_hz); "
                                 f"it has {', '.join(sorted(keys)) or 'none'}")
            H = np.asarray(z["H"])
            labels = [str(s) for s in np.asarray(z["labels"]).ravel()]
            omega = np.asarray(z["omega"], dtype=float) if "omega" in keys else \
                2 * np.pi * np.asarray(z["freq_hz"], dtype=float)
    except (OSError, EOFError) as err:
        raise ValueError(f"{path.name} is not a readable .npz file ({err})") from None
    if not np.issubdtype(H.dtype, np.number):
        raise ValueError(f"{path.name}: H is not numeric")
    return omega, labels, H.astype(complex)


def _read_uff58(path: Path) -> tuple[np.ndarray, list[str], np.ndarray]:
    import pyuff

    try:
        sets = pyuff.UFF(str(path)).read_sets()
    except Exception as err:  # pyuff raises plain Exceptions
        raise ValueError(f"{path.name} is not a readable UFF file ({' '.join(str(err).split())})"
                         ) from None
    sets = [sets] if isinstance(sets, dict) else list(sets)
    frfs = [s for s in sets if s.get("type") == 58]
    if not frfs:
        raise ValueError(f"{path.name} holds no UFF 58 function")
    x = np.asarray(frfs[0]["x"], dtype=float)
    entries: dict[tuple[str, str], np.ndarray] = {}
    order: list[str] = []
    for s in frfs:
        rsp = uff_label(s["rsp_node"], s["rsp_dir"])
        ref = uff_label(s["ref_node"], s["ref_dir"])
        sign = np.sign(s["rsp_dir"]) * np.sign(s["ref_dir"])
        data = np.asarray(s["data"])
        if data.shape != x.shape or not np.allclose(s["x"], x, rtol=1e-12, atol=0):
            raise ValueError(f"{path.name}: the function {rsp}/{ref} has another abscissa "
                             "than the first")
        entries[(rsp, ref)] = sign * data.astype(complex)
        for lab in (rsp, ref):
            if lab not in order:
                order.append(lab)
    n = len(order)
    H = np.empty((x.size, n, n), dtype=complex)
    for i, rsp in enumerate(order):
        for j, ref in enumerate(order):
            if (rsp, ref) not in entries:
                raise ValueError(f"{path.name} lacks the function of response {rsp} to "
                                 f"reference {ref}: coupling needs the whole square matrix")
            H[:, i, j] = entries[(rsp, ref)]
    return 2 * np.pi * x, order, H


def read_frf_file(path: str | os.PathLike) -> tuple[np.ndarray, list[str], np.ndarray]:
    """``(omega, labels, H)`` from an ``.npz`` or a UFF (``.uff``, ``.unv``) file.

    Raises:
        ValueError: a missing or unreadable file, shapes that do not agree, a grid that is not
            ascending and positive, values that are not finite.
    """
    p = Path(path)
    _check_file(p)
    suffix = p.suffix.lower()
    if suffix == ".npz":
        omega, labels, H = _read_npz(p)
    elif suffix in (".uff", ".unv"):
        omega, labels, H = _read_uff58(p)
    else:
        raise ValueError(f"{p.name}: an FRF file is .npz, .uff or .unv")
    n = len(labels)
    if H.shape != (omega.size, n, n):
        raise ValueError(f"{p.name}: H has shape {list(H.shape)}, expected "
                         f"[{omega.size}, {n}, {n}] for {omega.size} frequencies and {n} labels")
    if len(set(labels)) != n:
        raise ValueError(f"{p.name}: labels repeated")
    if not (np.all(np.isfinite(omega)) and np.all(np.isfinite(H))):
        raise ValueError(f"{p.name}: frequencies and receptances must be finite")
    if omega.size == 0 or np.any(omega <= 0) or np.any(np.diff(omega) <= 0):
        raise ValueError(f"{p.name}: the frequencies must be positive and ascending")
    return omega, labels, H
