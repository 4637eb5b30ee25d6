r"""Reading arrays from ``.npz`` archives with every size checked before anything is allocated.

``np.load`` of an ``.npz`` member allocates the array its ``.npy`` header declares before it
reads a byte of data, and inflates whatever the zip directory lets it: a 6 GB declared header
is a ``MemoryError``, a zip bomb fills the memory.  :func:`read_npz` reads, for each member
asked for, only the zip directory entry and the ``.npy`` header (a few hundred bytes), and
refuses, in one line naming the file, the member and the value:

* a file that is not a zip archive, a member missing, more than :data:`MAX_NPZ_MEMBERS`
  members, a member that is not an ``.npy`` array (bad magic or header);
* a dtype that is not a plain number, boolean or string (objects, structured records);
* a declared size that does not add up: the member's uncompressed size in the zip directory
  must be its header plus exactly ``prod(shape) * itemsize`` bytes (a header that promises more
  than the member holds, or a member that inflates to more than its header says);
* a compression ratio above :data:`MAX_RATIO` (deflate cannot exceed about 1032:1, so more is
  a crafted archive);
* a member whose entries cannot become the caller's type without loss of kind (complex or
  strings where real numbers are asked for);
* arrays whose sizes, plus the converted copies the caller asks for (``as_dtype``), add up to
  more than :data:`~substruct.case.fields.MEMORY_LIMIT` (whatever the machine has: an input
  file is accepted or refused the same way everywhere).

Only then are the members read, and never more bytes than their headers declare; a member
already of the type asked for is not copied again.
"""

from __future__ import annotations

import os
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np

from substruct.case.fields import MEMORY_LIMIT, gigabytes

__all__ = ["NpzMember", "npz_members", "read_npz", "MAX_NPZ_MEMBERS", "MAX_RATIO",
           "MAX_HEADER"]

#: Members an archive may have (the zip directory is read whole by :mod:`zipfile`).
MAX_NPZ_MEMBERS = 1000
#: Largest uncompressed / compressed size of a deflated member (deflate's own bound is ~1032).
MAX_RATIO = 1100
#: Largest ``.npy`` header read (numpy writes 128 bytes or a multiple of 64 of them).
MAX_HEADER = 65_536


@dataclass(frozen=True)
class NpzMember:
    """One ``.npy`` member of an archive, as its headers declare it.

    Attributes:
        key: the array's name (the member without ``.npy``).
        shape: the declared shape.
        dtype: the declared dtype.
        data_bytes: ``prod(shape) * itemsize``, what the header promises.
        held: the bytes the zip directory says the member holds after its header.
        stored: the member's compressed size in the zip directory.
    """

    key: str
    shape: tuple[int, ...]
    dtype: np.dtype
    data_bytes: int
    held: int
    stored: int

    @property
    def count(self) -> int:
        """The number of entries, ``prod(shape)``."""
        return int(np.prod(self.shape, dtype=object)) if self.shape else 1

    def check_held(self, name: str) -> None:
        """Refuse a member whose zip directory size is not its header's promise: a truncated
        member or a header that lies (less), or a member inflating past it (more).

        Raises:
            ValueError: naming the file ``name``, the member and both sizes.
        """
        if self.held != self.data_bytes:
            dims = " x ".join(map(str, self.shape)) or "scalar"
            raise ValueError(f"{name}: member {self.key!r} declares a {dims} array of "
                             f"{self.dtype} ({self.data_bytes} bytes) but the archive says it "
                             f"holds {self.held}: a truncated file or a header that lies")


def _header(fp: object, name: str, key: str) -> tuple[tuple[int, ...], np.dtype, int]:
    """``(shape, dtype, header bytes)`` of the ``.npy`` stream ``fp``."""
    fmt = np.lib.format
    try:
        version = fmt.read_magic(fp)  # type: ignore[arg-type]
        if version == (1, 0):
            shape, _, dtype = fmt.read_array_header_1_0(fp, max_header_size=MAX_HEADER)  # type: ignore[arg-type]
        elif version in ((2, 0), (3, 0)):
            shape, _, dtype = fmt.read_array_header_2_0(fp, max_header_size=MAX_HEADER)  # type: ignore[arg-type]
        else:
            raise ValueError(f"version {version}")
    except (ValueError, SyntaxError, TypeError, EOFError, OSError) as err:
        raise ValueError(f"{name}: member {key!r} is not an .npy array "
                         f"({' '.join(str(err).split())[:120]})") from None
    if not all(isinstance(d, int) and d >= 0 for d in shape):
        raise ValueError(f"{name}: member {key!r} declares the shape {shape!r}, not a list "
                         "of sizes")
    return tuple(shape), dtype, int(fp.tell())  # type: ignore[attr-defined]


def npz_members(path: str | os.PathLike, keys: Sequence[str] | None = None
                ) -> dict[str, NpzMember]:
    """The members ``keys`` (every member if ``None``) of an ``.npz`` archive, from the zip
    directory and the ``.npy`` headers only: the archive, the members and their dtypes checked
    (see the module); what the sizes promise is the caller's to check (:func:`read_npz`
    checks the memory, then :meth:`NpzMember.check_held`).

    Raises:
        ValueError: one line naming the file, the member and the value.
    """
    p = Path(path)
    name = p.name
    try:
        archive = zipfile.ZipFile(p)
    except (zipfile.BadZipFile, OSError, EOFError, ValueError) as err:
        raise ValueError(f"{name} is not a zip archive ({type(err).__name__}: "
                         f"{' '.join(str(err).split())[:120]})") from None
    with archive:
        infos = archive.infolist()
        if len(infos) > MAX_NPZ_MEMBERS:
            raise ValueError(f"{name} has {len(infos)} members, more than the "
                             f"{MAX_NPZ_MEMBERS} accepted")
        seen: set[str] = set()
        for i in infos:  # two members of one name: which one a reader takes is arbitrary
            if i.filename in seen:
                raise ValueError(f"{name}: member {i.filename[:80]!r} is in the archive twice")
            seen.add(i.filename)
        by_key = {i.filename[:-4]: i for i in infos if i.filename.endswith(".npy")}
        wanted = list(by_key) if keys is None else list(keys)
        out: dict[str, NpzMember] = {}
        for key in wanted:
            info = by_key.get(key)
            if info is None:
                raise ValueError(f"{name} has no array {key!r} (it has "
                                 f"{', '.join(sorted(by_key)) or 'none'})")
            if info.flag_bits & 0x1:
                raise ValueError(f"{name}: member {key!r} is encrypted")
            if info.compress_type not in (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED):
                raise ValueError(f"{name}: member {key!r} uses zip compression method "
                                 f"{info.compress_type}; .npz members are stored or deflated")
            if info.compress_type == zipfile.ZIP_DEFLATED and \
                    info.file_size > MAX_RATIO * max(info.compress_size, 1):
                raise ValueError(f"{name}: member {key!r} inflates {info.compress_size} bytes "
                                 f"to {info.file_size}, a ratio above the {MAX_RATIO} deflate "
                                 "allows: a crafted archive (zip bomb)")
            try:
                with archive.open(info) as fp:
                    shape, dtype, head = _header(fp, name, key)
            except (zipfile.BadZipFile, OSError, EOFError, RuntimeError) as err:
                raise ValueError(f"{name}: member {key!r} cannot be read "
                                 f"({' '.join(str(err).split())[:120]})") from None
            if dtype.hasobject or dtype.fields is not None or dtype.kind not in "biufcU" or \
                    dtype.subdtype is not None:
                raise ValueError(f"{name}: member {key!r} holds {dtype} entries, not numbers "
                                 "or strings")
            count = 1
            for d in shape:
                count *= d
            out[key] = NpzMember(key, shape, dtype, count * dtype.itemsize,
                                 info.file_size - head, info.compress_size)
        return out


def read_npz(path: str | os.PathLike, keys: Sequence[str],
             as_dtype: Mapping[str, np.dtype | type] | None = None,
             limit: float | None = None) -> dict[str, np.ndarray]:
    """The arrays ``keys`` of an ``.npz`` archive, each converted to ``as_dtype[key]`` if given,
    after :func:`npz_members` has checked them and their sizes (as read, plus the converted
    copies) against ``limit`` bytes (:data:`~substruct.case.fields.MEMORY_LIMIT` if ``None``).

    Raises:
        ValueError: one line naming the file, the member and the value.
    """
    p = Path(path)
    members = npz_members(p, keys)
    conv = dict(as_dtype or {})
    need = 0.0
    for key, m in members.items():
        need += m.data_bytes
        if key in conv:
            target = np.dtype(conv[key])
            if not np.can_cast(m.dtype, target, casting="same_kind") or \
                    (m.dtype.kind == "U") != (target.kind == "U"):
                raise ValueError(f"{p.name}: member {key!r} holds {m.dtype} entries, not "
                                 f"{'real ' if target.kind == 'f' else ''}numbers")
            need += float(m.count) * target.itemsize
    cap = MEMORY_LIMIT if limit is None else limit
    if need > cap:
        sizes = ", ".join(f"{k} {' x '.join(map(str, m.shape)) or 'scalar'} {m.dtype}"
                          for k, m in members.items())
        raise ValueError(f"{p.name}: the arrays ({sizes}) would need about {gigabytes(need)} "
                         f"of memory, more than the {gigabytes(cap)} allowed")
    for m in members.values():
        m.check_held(p.name)
    out: dict[str, np.ndarray] = {}
    try:
        with np.load(p, allow_pickle=False) as z:
            for key in keys:
                arr = np.asarray(z[key])
                out[key] = arr.astype(conv[key], copy=False) if key in conv else arr
    except (OSError, EOFError, ValueError, zipfile.BadZipFile) as err:
        raise ValueError(f"{p.name}: cannot read its arrays "
                         f"({' '.join(str(err).split())[:120]})") from None
    return out
