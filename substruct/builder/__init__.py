"""From a validated case to an assembled model: substructures made from their
specifications, points resolved, drawings laid out, constraints checked.

The layers above see what the builder makes through this package: a
:class:`~substruct.substructure.Substructure` (a part, made and perhaps reduced) and an
:class:`~substruct.assembly.stack.Assembly` (the stacked parts and ``A q = b + R F``)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from substruct.lazy import lazy_getattr

if TYPE_CHECKING:
    from substruct.assembly.stack import Assembly
    from substruct.substructure import Substructure

__all__ = ["Assembly", "Substructure"]

#: Public name -> the module that defines it (imported on first use: a module of the builder,
#: such as the drawings a result reader needs, does not import the assembly).
_LAZY = {"Assembly": "substruct.assembly.stack", "Substructure": "substruct.substructure"}


__getattr__ = lazy_getattr(__name__, _LAZY)
