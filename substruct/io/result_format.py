"""The marks of a substruct result file: its ``format`` and ``format_version`` root attributes
and the root attributes that are fields of the result (written by :mod:`substruct.io.hdf5`,
checked by :mod:`substruct.io.result_reader`)."""

from __future__ import annotations

__all__ = ["FORMAT", "FORMAT_VERSION", "RESERVED_ATTRS"]

#: Value of the root attribute ``format`` that marks a substruct result file.
FORMAT = "substruct-result"
#: Layout version; bumped when the layout changes incompatibly.
FORMAT_VERSION = 1
#: Root attributes that :func:`~substruct.io.result_reader.load` turns into fields (not into
#: ``Result.attrs``).
RESERVED_ATTRS = ("format", "format_version", "case_name", "case_yaml")
