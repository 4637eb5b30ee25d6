"""Case-file constraints and analyses: user constraints, modes, variants and receptances.

A user constraint is ``sum_k c_k u(p_k) = rhs + sum_j d_j F(p_j)`` (eqs 41, 52); the analyses
are the coupled modes (eqs 28-34) and the receptances at a frequency grid (eqs 11-15), each by
one formulation and checked by others (:mod:`substruct.analysis.formulations.coupling`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated, Any, Literal, TypeAlias

import numpy as np
from pydantic import Field, model_validator

from substruct.case.check_list import refuse_idle_checks
from substruct.case.errors import FieldError
from substruct.case.fields import (
    Coefficient,
    Count,
    Name,
    NonNegative,
    Number,
    Point,
    Positive,
    StrictModel,
    gigabytes,
    memory_limit,
)
from substruct.case.numbers import MAX_MAGNITUDE, RANGE
from substruct.case.frequency_grid import Omega
from substruct.case.modal_spec import AmlsSpec, ModalFrf
from substruct.case.lazy_models import LazyType
from substruct.lazy import lazy_getattr
from substruct.vocabulary import (
    DEFAULT_TOLERANCE,
    GENERALIZED_INVERSE,
    FormulationName,
    FrfMethod,
    Quantity,
    Solver,
)

if TYPE_CHECKING:
    from substruct.case.spec_analysis import (
        BaseFrfAnalysis,
        BasePsd,
        ForcePsd,
        LossFactorSpec,
        NamedBasePsd,
        PsdTable,
        RandomAnalysis,
        SrsAnalysis,
        SrsFrequencies,
    )
    from substruct.case.testlab_analysis import SemmAnalysis, TpaAnalysis
    from substruct.case.transient import TransientAnalysis

    LossFactorBlock: TypeAlias = LossFactorSpec | None
    TransientBlock: TypeAlias = TransientAnalysis | None
    RandomBlock: TypeAlias = RandomAnalysis | None
    BaseFrfBlock: TypeAlias = BaseFrfAnalysis | None
    SrsBlock: TypeAlias = SrsAnalysis | None
    TpaBlock: TypeAlias = TpaAnalysis | None
    SemmBlock: TypeAlias = SemmAnalysis | None
else:  # the blocks a case may leave out, their modules imported when a case has them
    _SPEC, _LAB = "substruct.case.spec_analysis", "substruct.case.testlab_analysis"
    LossFactorBlock = Annotated[Any, LazyType(_SPEC, "LossFactorSpec")]
    TransientBlock = Annotated[Any, LazyType("substruct.case.transient", "TransientAnalysis")]
    RandomBlock = Annotated[Any, LazyType(_SPEC, "RandomAnalysis")]
    BaseFrfBlock = Annotated[Any, LazyType(_SPEC, "BaseFrfAnalysis")]
    SrsBlock = Annotated[Any, LazyType(_SPEC, "SrsAnalysis")]
    TpaBlock = Annotated[Any, LazyType(_LAB, "TpaAnalysis")]
    SemmBlock = Annotated[Any, LazyType(_LAB, "SemmAnalysis")]

#: The models of the analyses' blocks, importable from here as before (imported on first use).
__getattr__ = lazy_getattr(__name__, {
    name: "substruct.case.spec_analysis" for name in (
        "LossFactorSpec", "PsdTable", "ForcePsd", "BasePsd", "NamedBasePsd", "RandomAnalysis",
        "SrsFrequencies", "SrsAnalysis", "BaseFrfAnalysis")})

__all__ = ["ConstraintSpec", "Variant", "ModesBand", "AmlsSpec", "ModesAnalysis", "Omega",
           "ModalFrf", "FrfAnalysis", "Analysis", "Output", "LossFactorSpec", "PsdTable",
           "ForcePsd", "BasePsd", "NamedBasePsd", "RandomAnalysis", "SrsFrequencies",
           "SrsAnalysis", "BaseFrfAnalysis"]



class ConstraintSpec(StrictModel):
    """``sum_k c_k u(p_k) = rhs + sum_j d_j F(p_j)`` (eqs 41, 52)."""

    name: Name | None = None
    terms: dict[Point, Coefficient]
    rhs: Coefficient = 0.0
    rhs_force: dict[Point, Coefficient] = Field(default_factory=dict)
    active: bool = True

    @model_validator(mode="after")
    def _not_empty(self) -> "ConstraintSpec":
        if not self.terms or all(c == 0 for c in self.terms.values()):
            raise FieldError("terms", "a constraint needs at least one term with a nonzero "
                             "coefficient", self.terms)
        # the row may have any scale; the displacement it prescribes may not
        implied = abs(self.rhs) / max(abs(c) for c in self.terms.values())
        if implied > MAX_MAGNITUDE:
            raise FieldError("rhs", f"out of range: the displacement it prescribes, "
                             f"|rhs| / max |terms| = {implied:.3g}, is too large ({RANGE})",
                             self.rhs)
        return self


class Variant(StrictModel):
    """The same model with some constraints left out (e.g. Table 1 without eq 52)."""

    name: Name
    drop: Annotated[list[Name], Field(min_length=1)]


class ModesBand(StrictModel):
    """A frequency band of the modes kept, ``min`` to ``max`` rad/s (``max`` blank: no upper
    end)."""

    min: NonNegative = 0.0
    max: Positive | None = None

    @model_validator(mode="after")
    def _order(self) -> "ModesBand":
        if self.max is not None and self.max <= self.min:
            raise FieldError("max", f"the band ends above its start ({self.min})", self.max)
        return self


class ModesAnalysis(StrictModel):
    """Coupled modes (eqs 28-34) by ``method``, checked by the ``check`` formulations; with a
    ``band``, only the modes in it, ``count`` at most (Nastran's EIGRL ``V1``, ``V2``)."""

    count: Count = 6
    band: ModesBand | None = None
    method: FormulationName = GENERALIZED_INVERSE
    check: list[FormulationName] = Field(default_factory=list)
    variants: list[Variant] = Field(default_factory=list)
    #: dense (eqs 28-34, all roots), sparse (shift-invert, the lowest count roots) or auto
    #: (sparse above SPARSE_ABOVE coordinates); see substruct.analysis.api.choose_solver
    solver: Solver = "auto"
    #: largest relative eigenvalue difference a check may have from the main formulation; a
    #: larger one fails the run (substruct.analysis.checks.require_agreement)
    tolerance: Positive = DEFAULT_TOLERANCE
    #: the reduction of solver: amls (its defaults if blank)
    amls: AmlsSpec | None = None

    @model_validator(mode="after")
    def _amls_block(self) -> "ModesAnalysis":
        refuse_idle_checks(self.method, self.check)
        if self.amls is not None and self.solver != "amls":
            raise FieldError("amls", f"the amls block is for solver: amls; the solver is "
                             f"{self.solver}", "{...}")
        return self


class FrfAnalysis(StrictModel):
    """Receptances ``H[k, i, j]`` (eqs 11-15) at ``omega`` for forces at ``inputs``."""

    omega: Omega
    inputs: Annotated[list[Point], Field(min_length=1)]
    outputs: Annotated[list[Point], Field(min_length=1)]
    #: a direct formulation, modal (modal superposition) or auto (modal on large models)
    method: FrfMethod = GENERALIZED_INVERSE
    check: list[FormulationName] = Field(default_factory=list)
    modal: ModalFrf = Field(default_factory=ModalFrf)
    #: the unit of the omega grid's values (rad/s or Hz)
    units: Literal["rad/s", "Hz"] = "rad/s"
    #: what the results are reported as: u / F, velocity / F or acceleration / F
    quantity: Quantity = "receptance"
    #: how the pictures draw |H|: on a log axis, or in decibels, 20 log10 (|H| / 1 unit)
    magnitude: Literal["log", "db"] = "log"
    #: largest max |H_check - H| / max |H| a check may have; a larger one fails the run
    tolerance: Positive = DEFAULT_TOLERANCE
    #: structural damping: one loss factor on all of K, or {substructure: eta}
    loss_factor: LossFactorBlock = None

    def omegas(self) -> np.ndarray:
        """The circular frequencies of the grid (rad/s), converted from Hz if ``units: Hz``."""
        w = self.omega.grid()
        return 2 * np.pi * w if self.units == "Hz" else w

    @model_validator(mode="after")
    def _positive(self) -> "FrfAnalysis":
        refuse_idle_checks(self.method, self.check)
        self.modal.refuse_unchecked(self.check)
        w = self.omega.grid()
        if GENERALIZED_INVERSE in (self.method, *self.check) and np.any(w <= 0):
            raise FieldError("omega", "the generalized-inverse receptance (eq 15) is singular "
                             "at omega = 0: use frequencies > 0 (or method kkt for statics)",
                             float(w[w <= 0][0]))
        if "modal" in self.model_fields_set and self.method not in ("modal", "auto"):
            raise FieldError("modal", f"the modal block is for method: modal (or auto, which "
                             f"sums the modes on a large model); the method is {self.method}",
                             "{...}")
        if self.loss_factor is not None and self.method in ("modal", "auto"):
            raise FieldError("method", "a loss factor is taken by the direct formulations "
                             "only (generalized-inverse, null-space, kkt)", self.method)
        sizes = {"frequencies": len(w), "outputs": len(self.outputs), "inputs": len(self.inputs)}
        # the result and, on a small model's direct path, one check sweep at a time (the
        # sparse path checks at three frequencies only)
        arrays = 2 if set(self.check) - {self.method} else 1
        need = 16.0 * arrays * len(w) * len(self.outputs) * len(self.inputs)
        if need > memory_limit():
            raise FieldError((), f"the receptances would need about {gigabytes(need)} of memory "
                             f"({len(w)} frequencies x {len(self.outputs)} outputs x "
                             f"{len(self.inputs)} inputs, complex, {arrays} array(s) at a "
                             f"time), more than this machine has available", sizes)
        return self


class Analysis(StrictModel):
    """What to compute: coupled ``modes`` and/or receptances ``frf``."""

    modes: ModesAnalysis | None = None
    frf: FrfAnalysis | None = None
    #: time histories (eqs 5, 10): substruct.case.transient
    transient: TransientBlock = None
    #: response PSDs and RMS under force or base acceleration PSDs
    random: RandomBlock = None
    #: transmissibilities per base acceleration (substruct.case.spec_analysis)
    base_frf: BaseFrfBlock = None
    #: shock response spectra of the transient's output accelerations
    srs: SrsBlock = None
    #: transfer path analysis and model mixing on the receptances of frf
    #: (substruct.case.testlab_analysis)
    tpa: TpaBlock = None
    semm: SemmBlock = None

    @model_validator(mode="after")
    def _something(self) -> "Analysis":
        if self.modes is None and self.frf is None and self.transient is None \
                and self.random is None and self.base_frf is None:
            raise ValueError("nothing to compute: give modes and/or frf")
        if self.srs is not None:
            if self.transient is None:
                raise FieldError("srs", "a shock response spectrum is of a transient's "
                                 "outputs: add analysis.transient")
            for i, p in enumerate(self.srs.outputs or []):
                if p not in self.transient.outputs:
                    raise FieldError(("srs", "outputs", i), "not an output of "
                                     "analysis.transient", p)
        if self.tpa is not None or self.semm is not None:
            from substruct.case.testlab_analysis import check_against_frf

            check_against_frf(self.tpa, self.semm, self.frf)
        return self


class Output(StrictModel):
    """What ``substruct run`` writes besides the results file."""

    pictures: bool = True
    #: store the assembly's M, K, C (sparse) in the result file (``model/M``, ...)
    matrices: bool = False

