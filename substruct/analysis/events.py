"""Phase events: how the analyses say what they are starting, for a caller that shows it.

A long run is silent without them: assembly, factorizations and eigen solves of large models
take seconds to minutes.  The command line passes a callback through
:func:`substruct.run.runner.run_case` into :func:`substruct.analysis.api.modes`, which calls it
as each phase starts; nothing is printed from this layer.
"""

from __future__ import annotations

from typing import Protocol

__all__ = ["Phase", "PHASE_KINDS"]

#: The kinds of phase: ``"assembly"`` (size: stacked coordinates), ``"dense-eigen"`` (all roots
#: of the dense pencil of eqs 28-34; size: coordinates, the cost grows as its cube),
#: ``"sparse-eigen"`` (factorization and shift-invert eigen solve), ``"sweep"`` (receptances
#: over a frequency grid; size: frequencies), ``"amls"`` (a stage or a tree level of the AMLS
#: reduction done; size: coordinates of the model reduced).
PHASE_KINDS = ("assembly", "dense-eigen", "sparse-eigen", "sweep", "amls")


class Phase(Protocol):
    """``events(kind, what, size)``: a phase of kind ``kind`` (one of :data:`PHASE_KINDS`),
    described by ``what``, of size ``size``, starts now."""

    def __call__(self, kind: str, what: str, size: int, /) -> None: ...
