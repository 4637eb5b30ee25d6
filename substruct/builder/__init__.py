"""From a validated case to an assembled model: substructures made from their
specifications, points resolved, drawings laid out, constraints checked.

The layers above see what the builder makes through this package: a
:class:`~substruct.substructure.Substructure` (a part, made and perhaps reduced) and an
:class:`~substruct.assembly.stack.Assembly` (the stacked parts and ``A q = b + R F``)."""

from substruct.assembly.stack import Assembly
from substruct.substructure import Substructure

__all__ = ["Assembly", "Substructure"]
