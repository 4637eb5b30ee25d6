"""The modal blocks of a case's analyses: how an AMLS reduction is made (``amls:``), and how a
modal superposition is made (``modal:`` of ``analysis.frf`` and ``analysis.random``, and of
``analysis.transient``): which eigensolver, which modes, which residual."""

from __future__ import annotations

from typing import Annotated, Literal, Sequence

from pydantic import Field, model_validator

from substruct.case.errors import FieldError
from substruct.case.fields import Count, Number, Positive, StrictModel
from substruct.vocabulary import Residual, Solver

__all__ = ["AmlsSpec", "ModalFrf", "TransientModal"]


class AmlsSpec(StrictModel):
    """How ``solver: amls`` reduces (:mod:`substruct.analysis.modes.amls`): every block keeps
    its modes up to ``cutoff`` times the highest wanted frequency; subdomains of at most
    ``leaf_size`` coordinates; ``iterations`` subspace iterations with the full factorization
    after the reduction, on the Ritz vectors up to ``ritz_ratio`` times the wanted frequency
    (at most ``cutoff``; default 2, only with iterations)."""

    cutoff: Annotated[Number, Field(gt=1)] = 5.0
    leaf_size: Annotated[int, Field(ge=8, le=1_000_000)] = 1000
    iterations: Annotated[int, Field(ge=0, le=10)] = 0
    ritz_ratio: Annotated[Number, Field(ge=1)] | None = None

    @model_validator(mode="after")
    def _ritz_ratio(self) -> "AmlsSpec":
        if self.ritz_ratio is not None and not self.iterations:
            raise FieldError("ritz_ratio", "the Ritz vectors are iterated only with iterations "
                             ">= 1; iterations is 0", self.ritz_ratio)
        if self.ritz_ratio is not None and self.ritz_ratio > self.cutoff:
            raise FieldError("ritz_ratio", f"at most the cut-off {self.cutoff:g} (the blocks "
                             f"keep no mode above it)", self.ritz_ratio)
        return self


class ModalFrf(StrictModel):
    """How ``method: modal`` sums the coupled modes (:mod:`substruct.analysis.frf.modal`)."""

    #: the number of modes kept (default: those up to cutoff x the highest frequency)
    count: Count | None = None
    cutoff: Annotated[Number, Field(ge=1)] = 10.0
    residual: Residual = "second-order"
    #: frequencies of the grid at which the direct solve checks the modal sum
    check_frequencies: Annotated[int, Field(ge=0, le=100)] = 3
    #: amls: every root below the cut-off on the AMLS basis, damping projected on it
    solver: Solver = "auto"
    #: the reduction of solver: amls (its defaults if blank)
    amls: AmlsSpec | None = None

    @model_validator(mode="after")
    def _amls_block(self) -> "ModalFrf":
        if self.amls is not None and self.solver != "amls":
            raise FieldError("amls", f"the amls block is for solver: amls; the solver is "
                             f"{self.solver}", "{...}")
        if self.count is not None and "cutoff" in self.model_fields_set:
            raise FieldError("cutoff", f"keep the modes up to the cut-off or the lowest count "
                             f"({self.count}), not both", self.cutoff)
        return self

    def refuse_unchecked(self, checks: Sequence[str]) -> None:
        """Refuse a ``check`` list beside ``check_frequencies: 0``, which runs no check.

        Raises:
            FieldError: at ``modal.check_frequencies``.
        """
        if checks and self.check_frequencies == 0:
            raise FieldError(("modal", "check_frequencies"), f"the checks {', '.join(checks)} "
                             f"run at the check frequencies: give at least 1, or leave check "
                             f"out to run none", 0)


class TransientModal(StrictModel):
    """How the modal form of ``analysis.transient`` finds its modes
    (:mod:`substruct.analysis.transient.modal`): the eigensolver; with ``solver: amls`` every
    AMLS mode below ``cutoff`` times the step's Nyquist frequency ``pi / dt`` (default 1),
    reduced as ``amls`` says; the static correction of the modes left out (``residual``)."""

    solver: Solver = "auto"
    #: with solver: amls, the modes below cutoff x pi / dt
    cutoff: Positive | None = None
    #: static: the static correction of the modes left out (mode acceleration); none: without
    residual: Literal["static", "none"] = "static"
    #: the reduction of solver: amls (its defaults if blank)
    amls: AmlsSpec | None = None

    @model_validator(mode="after")
    def _amls_only(self) -> "TransientModal":
        if self.amls is not None and self.solver != "amls":
            raise FieldError("amls", f"the amls block is for solver: amls; the solver is "
                             f"{self.solver}", "{...}")
        if self.cutoff is not None and self.solver != "amls":
            raise FieldError("cutoff", f"the cut-off keeps the AMLS modes below it (solver: "
                             f"amls); the {self.solver} solver keeps modal_count modes",
                             self.cutoff)
        return self
