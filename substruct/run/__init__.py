"""Running a case: the analyses it asks for on its model, into one
:class:`~substruct.run.result.Result`.

The names below are imported on first use, so that reading a result
(:mod:`substruct.run.result`, what :mod:`substruct.io.hdf5` needs) does not import the case
layer, the builder and the analyses."""

from __future__ import annotations

from importlib import import_module
from typing import Any

__all__ = ["Model", "Progress", "build_model", "run_case"]


def __getattr__(name: str) -> Any:
    """``Model``, ``Progress``, ``build_model``, ``run_case`` from
    :mod:`substruct.run.runner`, imported on first use."""
    if name not in __all__:
        raise AttributeError(f"module 'substruct.run' has no attribute {name!r}")
    value = getattr(import_module("substruct.run.runner"), name)
    globals()[name] = value
    return value
