"""Running a case: the analyses it asks for on its model, into one
:class:`~substruct.run.result.Result`.

The names below are imported on first use, so that reading a result
(:mod:`substruct.run.result`, what :mod:`substruct.io.hdf5` needs) does not import the case
layer, the builder and the analyses."""

from __future__ import annotations

from substruct.lazy import lazy_getattr

__all__ = ["Model", "Progress", "build_model", "run_case"]


__getattr__ = lazy_getattr(__name__, dict.fromkeys(__all__, "substruct.run.runner"))
