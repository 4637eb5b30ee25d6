"""Files the commands touch: output directories and files checked before anything is computed,
the targets checked again under the directory's lock, result files read back, and the optional
layers (pictures, exports) imported only when needed.

Every command that writes (``run``, ``converge``, ``study``, ``export``, ``compare --image``)
follows the one path policy of :mod:`substruct.io.paths`:

* an output directory is refused, before anything is computed, when it is given as ``''``
  (use ``.`` for the working directory), is or lies below a dangling symbolic link or a file,
  has a component or would hold a file name longer than the file system allows (``NAME_MAX``,
  usually 255 bytes, counting the temporary names of the set), or cannot be written; missing
  folders are created (``a/b/../c`` is ``a/c``);
* file names come from the case name (checked by the case file's schema) or from a name read
  from a file through :func:`~substruct.io.paths.safe_stem`, so no file lands outside the
  directory;
* under the directory's lock (:class:`~substruct.io.file_set.OutputDir`), every target is
  checked again (:func:`check_targets`): none may be a file the command reads, even with
  ``--force``; none may exist unless ``--force``;
* the files are written as one set, committed only when everything succeeded; a failure of
  the file system (full disk, read-only folder) is one line, exit code 2, nothing left."""

from __future__ import annotations

import contextlib
import gc
import importlib
import os
import tempfile
from pathlib import Path
from types import ModuleType
from typing import Any, Iterable, Iterator, Sequence

from substruct.cli.errors import InputError
from substruct.io.paths import plain_name, resolved_dir, same_file

__all__ = ["writable_dir", "check_out_dir", "check_out_file", "check_targets", "input_files",
           "optional_module", "load_result", "TEMP_NAME_EXTRA"]

#: Bytes a temporary name adds to a file name (``.substruct-<name>.<random>.commit``).
TEMP_NAME_EXTRA = 30


def _limit(path: Path, name: str, default: int) -> int:
    try:
        return int(os.pathconf(path, name))
    except (OSError, ValueError, AttributeError):
        return default


def _shown(name: str) -> str:
    return repr(name) if len(name) <= 40 else repr(name[:37] + "...")


def check_out_dir(text: str, what: str, names: Sequence[str] = ()) -> Path:
    """``text`` as an output directory that can hold the files ``names``; raise
    :class:`InputError` (one line) for every path that would fail only once written.

    Args:
        text: the directory as the user gave it.
        what: how the user named it (``--out``), for the message.
        names: file names the command will write into it.
    """
    if not str(text).strip():
        raise InputError(f"{what} {text!r}: an empty directory name; give a directory "
                         "(. for the working directory)")
    if "\0" in str(text):
        raise InputError(f"{what} {_shown(str(text))}: a NUL character in a path")
    for name in names:
        if not plain_name(name):  # a bug: the names are made by substruct
            raise RuntimeError(f"{name!r} is not a plain file name")
    out = resolved_dir(text)
    name_max = _limit(Path("."), "PC_NAME_MAX", 255)
    for part in out.parts:
        if len(os.fsencode(part)) > name_max:
            raise InputError(f"{what} {_shown(str(out))}: the name {_shown(part)} has "
                             f"{len(os.fsencode(part))} bytes, more than the {name_max} the "
                             "file system allows")
    probe = out
    try:
        while not probe.exists():
            if probe.is_symlink():
                raise InputError(f"{what} {out}: {probe} is a symbolic link to "
                                 f"{os.readlink(probe)}, which does not exist")
            if probe.parent == probe:
                break
            probe = probe.parent
    except OSError as err:
        raise InputError(f"{what} {_shown(str(out))}: {err.strerror or err}") from None
    name_max = _limit(probe, "PC_NAME_MAX", name_max)
    for name in names:
        size = len(os.fsencode(name)) + TEMP_NAME_EXTRA
        if size > name_max:
            raise InputError(f"{what} {out}: the file name {_shown(name)} is too long "
                             f"({size - TEMP_NAME_EXTRA} bytes; with its temporary name at "
                             f"most {name_max} bytes): shorten the case name")
    path_max = _limit(probe, "PC_PATH_MAX", 4096)
    longest = max([len(os.fsencode(n)) for n in names] + [0]) + 2 * TEMP_NAME_EXTRA
    full = len(os.fsencode(os.path.abspath(out))) + longest
    if full >= path_max:
        raise InputError(f"{what} {_shown(str(out))}: a path of {full} bytes to its files, "
                         f"more than the {path_max} the file system allows")
    writable_dir(out, what)
    return out


def check_out_file(text: str, what: str, suffixes: Sequence[str]) -> tuple[Path, str]:
    """``text`` as a file to write: its directory (checked as by :func:`check_out_dir`) and its
    name, which must end in one of ``suffixes``.

    Args:
        text: the file as the user gave it.
        what: how the user named it (``--image``), for the message.
        suffixes: the endings allowed (``.png``), lower case.
    """
    if not str(text).strip():
        raise InputError(f"{what} {text!r}: an empty file name")
    path = Path(text)
    if str(text).endswith(("/", os.sep)) or path.name in ("", ".", ".."):
        raise InputError(f"{what} {_shown(str(text))}: a directory, not a file name")
    if path.suffix.lower() not in suffixes:
        raise InputError(f"{what} {_shown(str(text))}: the file name must end in "
                         f"{' or '.join(suffixes)}")
    folder = check_out_dir(str(path.parent), what, [path.name])
    return folder, path.name


def check_targets(out: Path, names: Iterable[str], inputs: Iterable[str | os.PathLike],
                  force: bool) -> None:
    """Refuse (one line) a target ``out/<name>`` that is a directory, is one of the files the
    command reads (``inputs``; even with ``force``), or exists without ``force``.

    Call it holding the lock of ``out`` (:class:`~substruct.io.file_set.OutputDir`), so that no
    other writer adds the file between the check and the commit."""
    inputs = [p for p in inputs if str(p)]
    for name in names:
        path = out / name
        for read in inputs:
            if same_file(path, read):
                also = "" if Path(os.path.abspath(path)) == Path(os.path.abspath(read)) \
                    else f" (the same file as {read})"
                raise InputError(f"{path}{also} is a file this command reads; write into "
                                 "another file or directory")
        if path.is_dir():
            raise InputError(f"{path} is a directory")
        if (path.exists() or path.is_symlink()) and not force:
            raise InputError(f"{path} exists; use --force to overwrite it")


def input_files(case: Any) -> list[Path]:
    """The files a case reads: the case file and every string of the case that names an
    existing file relative to its folder (matrix, mesh and FRF files)."""
    found: list[Path] = []
    if case.source and Path(case.source).is_file():
        found.append(Path(case.source))
    base = Path(case.base_dir)

    def walk(value: Any) -> None:
        if isinstance(value, str):
            if 0 < len(value) < 4096 and "\0" not in value and "\n" not in value:
                path = Path(value) if Path(value).is_absolute() else base / value
                try:
                    if path.is_file():
                        found.append(path)
                except (OSError, ValueError):
                    pass
        elif isinstance(value, dict):
            for v in value.values():
                walk(v)
        elif isinstance(value, (list, tuple)):
            for v in value:
                walk(v)
    walk(case.model_dump())
    return found


def writable_dir(out: Path, what: str) -> None:
    """Raise :class:`InputError` unless ``out`` is, or can be created as, a writable directory.

    Nothing is left behind: a probe file in the nearest existing directory is removed again.

    Args:
        out: the directory.
        what: how the user named it (``--out``), for the message.
    """
    if out.exists() and not out.is_dir():
        raise InputError(f"{what} {out} exists and is not a directory")
    probe = out
    while not probe.exists():
        if probe.parent == probe:
            break
        probe = probe.parent
    if not probe.is_dir():
        raise InputError(f"{what} {out}: {probe} is not a directory")
    try:
        with tempfile.TemporaryFile(dir=probe):
            pass
    except OSError as err:
        raise InputError(f"{what} {out} is not writable ({err.strerror or err})") from None


@contextlib.contextmanager
def collector_paused() -> Iterator[None]:
    """Pause Python's cyclic garbage collector while the block runs (reading the case, loading
    the layers a command computes with), and let it run again after.

    Loading modules makes many objects and no garbage: the collections it triggers are about
    8 % of the start-up of ``substruct run`` (0.04 s of a 0.55 s import of its layers).  What
    the block made is then moved to the oldest generation unscanned (``gc.freeze`` then
    ``gc.unfreeze``): left in the youngest, the first collection after the block walked all of
    it (0.02-0.03 s each time, twice in a run).  It is still collected by the full
    collections.  The computations themselves run with the collector as usual."""
    was = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was:
            gc.freeze()
            gc.unfreeze()
            gc.enable()


def optional_module(name: str) -> ModuleType:
    """``substruct.<name>``, imported on demand (pictures and exports load pyvista, meshio).

    Raises:
        RuntimeError: the module is missing from this installation (an internal error).
    """
    try:
        return importlib.import_module(f"substruct.{name}")
    except ModuleNotFoundError as err:
        if err.name == f"substruct.{name}":
            raise RuntimeError(f"substruct.{name} is not available in this installation") \
                from None
        raise


def load_result(path: str) -> Any:
    """The :class:`~substruct.run.result.Result` in the HDF5 file ``path``.

    Raises:
        InputError: no such file, or not a substruct result (one line).
    """
    results = optional_module("io.hdf5")
    try:
        return results.load(path)
    except FileNotFoundError:
        raise InputError(f"{path}: no such file") from None
    except (ValueError, OSError) as err:
        raise InputError(" ".join(str(err).split())) from None
