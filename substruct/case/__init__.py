"""Case files: YAML loading, the validated schema, safe expressions and one-line errors.

Nothing numerical happens here; the layers below :mod:`substruct.builder` turn a case into
matrices.

The names below are imported on first use: importing one module of the layer (the text
escapes of :mod:`substruct.case.text`) does not import the schema (pydantic)."""

from __future__ import annotations

from substruct.lazy import lazy_getattr

#: Public name -> the module that defines it.
_LAZY = {"Case": "loader", "CaseError": "errors", "apply_overrides": "yaml_io",
         "load_case": "loader", "parse_case": "loader", "parse_point": "fields"}

__all__ = ["Case", "CaseError", "apply_overrides", "load_case", "parse_case", "parse_point"]


__getattr__ = lazy_getattr(__name__, _LAZY, prefix="substruct.case.")
