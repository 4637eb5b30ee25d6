r"""What an analysis takes: the system (:class:`ConstrainedSystem`) and how to analyse it
(:class:`ModesOptions`, :class:`SweepOptions`), each validated once when it is made.

The front doors read ``modes(system, count, options=ModesOptions(...))`` and
``receptance_sweep(system, omegas, inputs, outputs, options=SweepOptions(...))``
(:mod:`substruct.analysis.api`).  :class:`ConstrainedSystem` is defined in
:mod:`substruct.linalg.system`, below the assembly, so that ``Assembly.system`` gives one; it is
named here so that an analysis finds its inputs in one module.

Examples
--------
>>> from substruct.analysis.system import ModesOptions, SweepOptions
>>> ModesOptions(method="null-space", checks=["kkt"]).checks
('kkt',)
>>> SweepOptions(method="modal").method
'modal'
>>> SweepOptions(method="lagrange")
Traceback (most recent call last):
...
ValueError: unknown method 'lagrange'; expected one of generalized-inverse, null-space, kkt, modal, auto
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol, Sequence

from substruct.linalg.system import ConstrainedSystem
from substruct.vocabulary import (
    DEFAULT_TOLERANCE,
    FORMULATIONS,
    FRF_METHODS,
    GENERALIZED_INVERSE,
    SOLVERS,
)

if TYPE_CHECKING:  # at run time only attributes are read: no import of the analyses here
    from substruct.analysis.events import Phase

__all__ = ["ConstrainedSystem", "ModesOptions", "Progress", "SweepOptions"]


class Progress(Protocol):
    """``progress(done, total, label)``: called as work advances (``done`` of ``total`` steps
    of what ``label`` names: a formulation during a frequency sweep, a level in a study)."""

    def __call__(self, done: int, total: int, label: str, /) -> None: ...


def _one_of(kind: str, name: str, allowed: Sequence[str]) -> None:
    if name not in allowed:
        raise ValueError(f"unknown {kind} {name!r}; expected one of {', '.join(allowed)}")


def _tolerance(value: float) -> float:
    tol = float(value)
    if math.isnan(tol) or tol < 0:
        raise ValueError(f"tolerance must be a number >= 0, got {value!r}")
    return tol


@dataclass(frozen=True)
class ModesOptions:
    """How coupled modes are computed and checked (:func:`substruct.analysis.api.modes`).

    Attributes:
        method: the main formulation, one of :data:`substruct.vocabulary.FORMULATIONS`.
        checks: check formulations (the main one and repeats are skipped).
        solver: ``"auto"``, ``"dense"``, ``"sparse"`` or ``"amls"``
            (:func:`substruct.analysis.modes.eigen.choose_solver`).
        tolerance: the largest relative eigenvalue disagreement a check may have.
        what: how the analysis is named in error messages.
        full_checks: on the sparse path, solve ``method`` and each check in full.
        events: called as each eigen solve starts (:class:`substruct.analysis.events.Phase`).
        amls: with ``solver="amls"``, the reduction
            (:class:`substruct.analysis.modes.amls.AmlsOptions`; its defaults if ``None``).

    Raises:
        ValueError: an unknown method, check or solver; a tolerance below 0 or NaN.
    """

    method: str = GENERALIZED_INVERSE
    checks: Sequence[str] = ()
    solver: str = "auto"
    tolerance: float = DEFAULT_TOLERANCE
    what: str = "modes"
    full_checks: bool = False
    events: Phase | None = None
    amls: Any = None  # AmlsOptions (of the strategy that reads it: no import cycle)

    def __post_init__(self) -> None:
        for name in (self.method, *self.checks):
            _one_of("method", name, FORMULATIONS)
        _one_of("solver", self.solver, SOLVERS)
        object.__setattr__(self, "checks", tuple(self.checks))
        object.__setattr__(self, "tolerance", _tolerance(self.tolerance))


@dataclass(frozen=True)
class SweepOptions:
    """How receptances are computed and checked
    (:func:`substruct.analysis.api.receptance_sweep`).

    Attributes:
        method: a formulation, ``"modal"`` or ``"auto"`` (:data:`substruct.vocabulary.FRF_METHODS`).
        checks: check formulations (the main one and repeats are skipped).
        tolerance: the largest ``max |H_check - H| / max |H|`` a check may have.
        input_names, output_names: names of the inputs and outputs (``"1"``, ... if ``None``).
        progress: called as ``progress(done, total, method)`` during the sweeps.
        what: how the analysis is named in error messages.
        modal: the options of a modal sweep
            (:class:`~substruct.analysis.frf.modal.ModalOptions`; its defaults if ``None``).

    Raises:
        ValueError: an unknown method or check; a tolerance below 0 or NaN.
    """

    method: str = GENERALIZED_INVERSE
    checks: Sequence[str] = ()
    tolerance: float = DEFAULT_TOLERANCE
    input_names: Sequence[str] | None = None
    output_names: Sequence[str] | None = None
    progress: Progress | None = None
    what: str = "frf"
    modal: Any = None  # ModalOptions (of the modal sweep that reads it: no import cycle)

    def __post_init__(self) -> None:
        _one_of("method", self.method, FRF_METHODS)
        for name in self.checks:
            _one_of("method", name, FORMULATIONS)
        object.__setattr__(self, "checks", tuple(self.checks))
        object.__setattr__(self, "tolerance", _tolerance(self.tolerance))
