"""The path policy of every file substruct writes: where a file may go and what it may be called.

Four rules, one place (the command line's checks in :mod:`substruct.cli.files` and the writers
of :mod:`substruct.io` call these):

* a name read from inside a file (the case name stored in a result, a variant name) becomes a
  file name only through :func:`safe_stem`: no separator, no ``..``, no leading dot, no
  control character, at most :data:`STEM_BYTES` bytes -- so nothing is ever written outside
  the chosen directory;
* a directory given with ``..`` after a folder that does not exist yet is resolved as a path
  (:func:`resolved_dir`: ``a/b/../c`` is ``a/c``), never handed to ``mkdir`` component by
  component;
* a file that is read is never a file that is written (:func:`same_file`);
* a write that fails for a reason of the file system (a full disk, a read-only or vanished
  folder, a quota) is a :class:`WriteError` with one line naming the file and the reason
  (:func:`write_errors`), and the set being written is dropped whole
  (:class:`~substruct.io.file_set.OutputDir`).
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import unicodedata
from pathlib import Path
from typing import Iterator

__all__ = ["STEM_BYTES", "TEMP_PREFIX", "WRITE_ERRNOS", "WriteError", "safe_stem",
           "plain_name", "resolved_dir", "same_file", "describe", "write_errors"]

#: Every temporary file or folder substruct makes in an output directory starts with this.
TEMP_PREFIX = ".substruct-"

#: Longest file stem made from a name read from a file, in bytes of UTF-8 (a file name of the
#: stem, a suffix such as ``_modes_<variant>.vtu`` and a temporary name stays under the 255
#: bytes of common file systems).
STEM_BYTES = 120

#: ``errno`` values that mean "the file system cannot take this file", not a bug.
WRITE_ERRNOS = frozenset(getattr(errno, name) for name in (
    "ENOSPC", "EDQUOT", "EROFS", "EACCES", "EPERM", "EFBIG", "EIO", "ENOENT", "ENOTDIR",
    "EISDIR", "ENAMETOOLONG", "EMLINK", "EXDEV") if hasattr(errno, name))


class WriteError(Exception):
    """A file could not be written for a reason of the file system (one line: the file and
    the reason); nothing of the set being written was left."""


def safe_stem(name: str, fallback: str = "case") -> str:
    """``name`` (read from inside a file) as a file stem that stays in its directory.

    Every run of characters other than letters, digits, ``_``, ``.``, ``+`` and ``-`` (a run of
    two or more dots counts as one of them) becomes one ``_`` (so ``/``, ``\\``, ``..``, NUL, control and
    format characters go; ``a/../../b`` is ``a_b``); leading and trailing
    dots and underscores are stripped (no hidden file, no ``.`` or ``..``); the result is cut
    to :data:`STEM_BYTES` bytes of UTF-8 on a character boundary; an empty result is
    ``fallback``.

    Args:
        name: the name as read (any string).
        fallback: the stem of a name with nothing usable in it.
    """
    text = unicodedata.normalize("NFC", str(name))
    text = "".join(c if unicodedata.category(c)[0] != "C" else "_" for c in text)
    stem = re.sub(r"(?:[^\w.+-]|\.\.+)+", "_", text, flags=re.UNICODE).strip("._")
    raw = stem.encode("utf-8")[:STEM_BYTES]
    stem = raw.decode("utf-8", errors="ignore").strip("._")
    return stem or fallback


def plain_name(name: str) -> bool:
    """Whether ``name`` is one file name in a directory: not empty, no separator, no NUL, no
    control character, not ``.`` or ``..``."""
    return (bool(name) and "/" not in name and os.sep not in name and "\0" not in name
            and name not in (".", "..")
            and not any(unicodedata.category(c) == "Cc" for c in name))


def resolved_dir(path: str | os.PathLike) -> Path:
    """``path`` as a directory to create: unchanged without ``..``; with ``..``, resolved
    (symbolic links of the folders that exist followed, the rest taken by name, so
    ``a/b/../c`` with ``a/b`` missing is ``<cwd>/a/c``)."""
    p = Path(path)
    return Path(os.path.realpath(p)) if ".." in p.parts else p


def same_file(a: str | os.PathLike, b: str | os.PathLike) -> bool:
    """Whether ``a`` and ``b`` are one file (hard and symbolic links included); a path that does
    not exist is compared by its resolved name."""
    try:
        return os.path.samefile(a, b)
    except OSError:
        return Path(os.path.realpath(a)) == Path(os.path.realpath(b))


def describe(err: OSError, where: str | os.PathLike) -> str:
    """One line for a failed write: the file (``err.filename`` if set and not a temporary name,
    else ``where``) and the reason."""
    target = err.filename if isinstance(err.filename, (str, bytes, os.PathLike)) else where
    if any(part.startswith(TEMP_PREFIX) for part in Path(os.fsdecode(target)).parts):
        target = where  # the user knows the file by its final name
    reason = err.strerror or (os.strerror(err.errno) if err.errno else str(err))
    return f"cannot write {os.fsdecode(target)}: {' '.join(str(reason).split())}"


@contextlib.contextmanager
def write_errors(where: str | os.PathLike) -> Iterator[None]:
    """Turn an :class:`OSError` of the file system (:data:`WRITE_ERRNOS`) raised in the block
    into :class:`WriteError` naming ``where`` (or the file the error names).

    Other exceptions pass unchanged (a bug stays an internal error)."""
    try:
        yield
    except OSError as err:
        if err.errno in WRITE_ERRNOS and type(err) in (OSError, PermissionError,
                                                       FileNotFoundError, NotADirectoryError,
                                                       IsADirectoryError):
            raise WriteError(describe(err, where)) from None
        raise
