"""Files the commands touch: output directories checked before anything is computed, result
files read back, and the optional layers (pictures, exports) imported only when needed."""

from __future__ import annotations

import importlib
import tempfile
from pathlib import Path
from types import ModuleType
from typing import Any

from substruct.cli.arguments import InputError

__all__ = ["writable_dir", "optional_module", "load_result"]


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
