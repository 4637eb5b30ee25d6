r"""Arrays of the transient block read from files: a load table (``.csv`` rows ``t, value`` or
``.npz`` arrays ``t`` and ``value``) and an initial state vector (``.npz`` arrays
``displacement`` and ``velocity`` over the model's coordinates).

An NPZ member is read only after its header: a 1-D array of real numbers, of a length the
caller accepts (at most :data:`MAX_TABLE_ROWS` rows of a table, exactly ``n`` entries of a
state vector), whose data the archive's member really holds.  A header that declares 6 GB, a
member that decompresses past what it declares (a zip bomb) or a 2-D array is refused before
anything is allocated.  Files must be regular files (not FIFOs or devices).  A member of
another name is refused (:func:`npz_only`): a misspelt ``velocty`` would otherwise leave the
velocity at zero without a word.
"""

from __future__ import annotations

import stat
from pathlib import Path

import numpy as np

from substruct.case.npz_files import npz_members, read_npz

__all__ = ["MAX_TABLE_ROWS", "npz_only", "npz_vector", "read_table"]

#: The most rows a load table may have.
MAX_TABLE_ROWS = 1_000_000
#: Bytes of a CSV table per row at most (so its size is checked before it is parsed).
CSV_ROW_BYTES = 64


def _regular(path: Path, what: str) -> None:
    try:
        mode = path.stat().st_mode
    except OSError:
        raise ValueError(f"no such {what} file {path.name!r}") from None
    if not stat.S_ISREG(mode):
        raise ValueError(f"{path.name!r} is not a regular file")


def npz_only(path: Path, keys: tuple[str, ...]) -> None:
    """Refuse an ``.npz`` archive with a member other than ``keys`` (from its directory only).

    Raises:
        ValueError: not a readable archive, or a member that is not read, named.
    """
    _regular(path, "NPZ")
    other = sorted(set(npz_members(path)) - set(keys))
    if other:
        raise ValueError(f"{path.name}: member {other[0][:80]!r} is not read (the members are "
                         f"{' and '.join(keys)})")


def npz_vector(path: Path, key: str, max_len: int, exact: int | None = None
               ) -> np.ndarray | None:
    """The 1-D real array ``key`` of the ``.npz`` file ``path`` as float64 (``None`` if the
    archive has no such array), its header checked before its data is read
    (:func:`substruct.case.npz_files.npz_members`): a 1-D array of integers or floats with at
    most ``max_len`` entries (exactly ``exact`` if given) that the member holds in full.

    Raises:
        ValueError: not a readable archive, a header of another shape or kind, a length
            outside the limits, a member shorter or longer than its header declares.
    """
    _regular(path, "NPZ")
    if key not in npz_members(path):
        return None
    member = npz_members(path, [key])[key]
    if len(member.shape) != 1:
        raise ValueError(f"{key} must be a 1-D array, the file holds one of shape "
                         f"{list(member.shape)}")
    if member.dtype.kind not in "iuf":
        raise ValueError(f"{path.name}: member {key!r} holds {member.dtype} entries, not real "
                         "numbers")
    size = int(member.shape[0])
    if size > max_len or (exact is not None and size != exact):
        want = f"{exact}" if exact is not None else f"at most {max_len}"
        raise ValueError(f"{key} has {size} entries, {want} expected")
    return read_npz(path, [key], {key: np.float64})[key]


def read_table(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """``(t, value)`` of a load table (CSV ``t, value`` rows or NPZ arrays ``t``, ``value``).

    Raises:
        ValueError: not a regular file, too many rows, non-finite values, times not strictly
            increasing.
    """
    _regular(path, "table")
    if path.suffix == ".npz":
        npz_only(path, ("t", "value"))
        t_arr = npz_vector(path, "t", MAX_TABLE_ROWS)
        v_arr = npz_vector(path, "value", MAX_TABLE_ROWS)
        if t_arr is None or v_arr is None:
            raise ValueError("an NPZ table needs arrays t and value")
        t, v = t_arr, v_arr
    elif path.suffix == ".csv":
        if path.stat().st_size > CSV_ROW_BYTES * MAX_TABLE_ROWS:
            raise ValueError(f"more than {MAX_TABLE_ROWS} rows")
        with open(path, encoding="utf-8", errors="replace") as fh:
            if not any(line.split("#", 1)[0].strip() for line in fh):
                raise ValueError("the file is empty (or only comments): a CSV table has rows "
                                 "t, value")
        data = np.loadtxt(path, delimiter=",", ndmin=2, comments="#")
        if data.shape[1] != 2:
            raise ValueError("a CSV table has two columns, t and value")
        t, v = data[:, 0], data[:, 1]
    else:
        raise ValueError("a table is a .csv or .npz file")
    if t.size != v.size or t.size < 2 or t.size > MAX_TABLE_ROWS:
        raise ValueError(f"a table needs 2 to {MAX_TABLE_ROWS} rows of t and value")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(v))):
        raise ValueError("a table with a value that is not finite (NaN or inf)")
    if np.any(np.diff(t) <= 0):
        k = int(np.flatnonzero(np.diff(t) <= 0)[0])
        raise ValueError(f"times not strictly increasing at row {k + 1} (t = {t[k + 1]:g} "
                         f"after {t[k]:g})")
    return t, v
