r"""The ``analysis: transient:`` block of a case file: the constrained transient response
(eqs 5, 10; :mod:`substruct.analysis.transient.response`).

Loads act at points; each is ``amplitude`` times a shape of ``t`` (a signal,
:mod:`substruct.case.transient_signals`: ``step``, ``ramp``, ``half-sine``, ``harmonic``,
``expression``, ``table``; each shape takes its own keys and no other); ``base`` moves grounded
supports by a signal (their acceleration or displacement); ``initial`` sets the state at
``t = 0`` (:class:`InitialState`).

Sizes are checked here, before anything is allocated: the number of steps, and the memory of
the load table (one value per load and instant, copied once by each of the null-space and modal
forms) together with the recorded samples, against :data:`~substruct.case.fields.MEMORY_LIMIT`.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

import numpy as np
from pydantic import Field, field_validator, model_validator

from substruct.case.check_list import refuse_idle_checks
from substruct.case.errors import FieldError
from substruct.case.fields import (
    MEMORY_LIMIT,
    Count,
    Number,
    Point,
    Positive,
    StrictModel,
    gigabytes,
)
from substruct.case.modal_spec import TransientModal
from substruct.case.transient_files import MAX_TABLE_ROWS, read_table
from substruct.case.transient_signals import Signal, TransientLoad, load_values
from substruct.vocabulary import (
    DEFAULT_TOLERANCE,
    GENERALIZED_INVERSE,
    Integrator,
    TransientForm,
)

__all__ = ["MAX_STEPS", "MAX_TABLE_ROWS", "MAX_LOAD_VALUES", "RECORD_BYTES", "Signal", "TransientLoad", "BaseExcitation",
           "InitialState", "TransientAnalysis", "load_values", "read_table", "memory_need",
           "RHO_INF"]

#: The most steps a run may take.
MAX_STEPS = 10_000_000
#: The most values a load table may hold (loads times instants: 800 MB), whatever the memory.
MAX_LOAD_VALUES = 100_000_000
#: Bytes a recorded sample takes besides its values (measured, :func:`memory_need`).
RECORD_BYTES = 1000
#: The spectral radius at infinite frequency of generalized-alpha when ``rho_inf`` is not given.
RHO_INF = 0.9


class BaseExcitation(StrictModel):
    r"""A prescribed ground motion :math:`g(t)` of the supports at the points ``at``: each
    point must be held by a constraint row on it alone (``terms: {p: c}``), which becomes
    :math:`c\, u(p) = \text{rhs} + c\, g(t)` (:mod:`substruct.analysis.transient.base`).
    Give the ``acceleration`` :math:`\ddot g` (the ground starts at rest) or the
    ``displacement`` :math:`g`, each a signal as a load's."""

    at: Annotated[list[Point], Field(min_length=1)]
    acceleration: Signal | None = None
    displacement: Signal | None = None

    @model_validator(mode="after")
    def _one(self) -> "BaseExcitation":
        if (self.acceleration is None) == (self.displacement is None):
            raise FieldError("acceleration", "give the ground's acceleration or its "
                             "displacement (one of the two)")
        return self

    @property
    def kind(self) -> str:
        """``"acceleration"`` or ``"displacement"``."""
        return "acceleration" if self.acceleration is not None else "displacement"

    @property
    def signal(self) -> Any:
        """The signal given."""
        sig = self.acceleration if self.acceleration is not None else self.displacement
        assert sig is not None
        return sig


class InitialState(StrictModel):
    r"""The state at ``t = 0`` (zero if nothing is given).

    The displacement is given one way: ``mode`` (``scale`` times coupled mode ``mode``, 1-based,
    M-normalized), ``displacement`` (``{point: value}``: those coordinates set, the others 0),
    ``file`` (an ``.npz`` file whose array ``displacement`` holds every coordinate of the
    model) or ``static: true`` (the constrained static state under the loads at ``t = 0``,
    :math:`K q + A^T \lambda = P(0)`, :math:`A q = b(0)`; ``initial: static`` for short).
    The velocity likewise: ``velocity_mode`` (with ``velocity_scale``), ``velocity``
    (``{point: value}``) or the array ``velocity`` of ``file``.  The state must satisfy the
    constraints, :math:`A q_0 = b(0)`, :math:`A \dot q_0 = \dot b(0)`; one that does not is
    refused with its residual (never projected)."""

    mode: Count | None = None
    scale: Number = 1.0
    velocity_mode: Count | None = None
    velocity_scale: Number = 1.0
    displacement: dict[Point, Number] | None = None
    velocity: dict[Point, Number] | None = None
    file: str | None = None
    static: bool = False

    @model_validator(mode="before")
    @classmethod
    def _shorthand(cls, data: Any) -> Any:
        """``initial: static`` is ``initial: {static: true}``."""
        if data == "static":
            return {"static": True}
        if isinstance(data, str):
            raise FieldError((), "must be a mapping (key: value) or static", data)
        return data

    @model_validator(mode="after")
    def _one_way(self) -> "InitialState":
        ways = [k for k, on in (("mode", self.mode is not None),
                                ("displacement", self.displacement is not None),
                                ("static", self.static)) if on]
        if len(ways) > 1:
            raise FieldError(ways[1], f"the initial displacement is given one way; "
                             f"{ways[0]} is given too", getattr(self, ways[1]))
        if self.velocity_mode is not None and self.velocity is not None:
            raise FieldError("velocity", "the initial velocity is given one way; "
                             "velocity_mode is given too", self.velocity)
        for name in ("displacement", "velocity"):
            if getattr(self, name) == {}:
                raise FieldError(name, "must name at least one point", {})
        if "scale" in self.model_fields_set and self.mode is None:
            raise FieldError("scale", "scales a mode: give mode too", self.scale)
        if "velocity_scale" in self.model_fields_set and self.velocity_mode is None:
            raise FieldError("velocity_scale", "scales a mode: give velocity_mode too",
                             self.velocity_scale)
        return self


def memory_need(steps: int, every: int, n_loads: int, n_outputs: int, forms: int,
                copies: int) -> tuple[float, float]:
    """``(table, records)``: bytes of the load table and of the recorded samples.

    The table holds ``n_loads`` values per instant, beside the instants themselves and the
    temporaries of one load's evaluation (5 columns more); each of ``copies`` forms (null
    space, modal) copies it with 4 columns more.  A recorded sample takes
    :data:`RECORD_BYTES` (measured with ``tracemalloc``: 968 bytes a sample for one output and
    one constraint row) and 16 bytes per value (its array, then the stacked copy), per form
    run."""
    n = float(steps + 1)
    table = 8.0 * n * (n_loads + 5) + 8.0 * n * (n_loads + 4) * copies
    samples = steps // every + 2
    records = samples * (RECORD_BYTES + 16.0 * (3 * n_outputs + 6)) * forms
    return table, records


class TransientAnalysis(StrictModel):
    """Time histories (eqs 5, 10) from 0 to ``t_end`` with the constant step ``dt``."""

    t_end: Positive
    dt: Positive
    integrator: Integrator = "newmark"
    #: generalized-alpha only (Newmark's average acceleration has 1)
    rho_inf: Annotated[float, Field(ge=0, le=1)] | None = None
    method: TransientForm = GENERALIZED_INVERSE
    check: list[TransientForm] = Field(
        default_factory=list)
    tolerance: Positive = DEFAULT_TOLERANCE
    loads: list[TransientLoad] = Field(default_factory=list)
    #: a prescribed ground motion of grounded supports
    base: BaseExcitation | None = None
    initial: InitialState = Field(default_factory=InitialState)
    outputs: list[Point] = Field(default_factory=list)
    constraint_forces: bool = True
    #: record every this many steps
    every: Annotated[int, Field(ge=1, le=MAX_STEPS)] = 1
    #: keep the full displacement field every this many steps (0: never)
    field_every: Annotated[int, Field(ge=0, le=MAX_STEPS)] = 0
    #: modes of the modal form (default: all of a small model)
    modal_count: Count | None = None
    #: how the modal form finds its modes (solver, AMLS cut-off, residual)
    modal: TransientModal | None = None

    @field_validator("initial", mode="before")
    @classmethod
    def _initial(cls, value: Any) -> Any:
        return {"static": True} if value == "static" else value

    @property
    def steps(self) -> int:
        """The number of steps, ``ceil(t_end / dt)`` (to rounding)."""
        return int(np.ceil(self.t_end / self.dt - 1e-9))

    @property
    def spectral_radius(self) -> float:
        """The ``rho_inf`` the integrator uses: as given (generalized-alpha, default
        :data:`RHO_INF`), 1 for Newmark's average acceleration."""
        if self.integrator == "newmark":
            return 1.0
        return RHO_INF if self.rho_inf is None else float(self.rho_inf)

    @model_validator(mode="after")
    def _sizes(self) -> "TransientAnalysis":
        if self.rho_inf is not None and self.integrator == "newmark":
            raise FieldError("rho_inf", "only integrator: generalized-alpha takes rho_inf "
                             "(Newmark's average acceleration has rho_inf = 1)", self.rho_inf)
        if self.dt > self.t_end:
            raise FieldError("dt", f"must be at most t_end ({self.t_end:g})", self.dt)
        if self.t_end / self.dt > MAX_STEPS:
            raise FieldError("dt", f"t_end / dt is more than {MAX_STEPS} steps", self.dt)
        values = len(self.loads) * (self.steps + 1)
        if values > MAX_LOAD_VALUES:
            raise FieldError("loads", f"{len(self.loads)} loads over {self.steps + 1} instants "
                             f"are {values:.3g} values in the load table (about "
                             f"{gigabytes(8.0 * values)}), more than the {MAX_LOAD_VALUES:.0e} "
                             f"allowed: take a longer dt, a shorter t_end or fewer loads",
                             len(self.loads))
        refuse_idle_checks(self.method, self.check)
        forms = {self.method, *self.check}
        if self.method == "modal" and self.constraint_forces and \
                "constraint_forces" in self.model_fields_set:
            raise FieldError("constraint_forces", "the modal form records no constraint forces "
                             "(its modes hold the constraints): give method: "
                             "generalized-inverse or null-space, with check: [modal]", True)
        if self.modal is not None and "modal" not in forms:
            raise FieldError("modal", "the modal block is for the modal form: give method: "
                             "modal or check: [modal]", "{...}")
        if self.modal_count is not None and "modal" not in forms:
            raise FieldError("modal_count", "the modes of the modal form, which this run does "
                             "not use: give method: modal or check: [modal], or leave "
                             "modal_count out", self.modal_count)
        if self.field_every % self.every:
            raise FieldError("field_every", f"the fields are kept at recorded steps: a "
                             f"multiple of every ({self.every}), or 0", self.field_every)
        if self.modal is not None and self.modal.cutoff is not None and \
                self.modal_count is not None:
            raise FieldError(("modal", "cutoff"), f"keep the modes below a cut-off or the "
                             f"lowest modal_count ({self.modal_count}), not both",
                             self.modal.cutoff)
        table, records = memory_need(self.steps, self.every, len(self.loads),
                                     len(self.outputs), len(forms),
                                     len(forms & {"null-space", "modal"}))
        if table + records > MEMORY_LIMIT:
            samples = self.steps // self.every + 2
            if table >= records:
                raise FieldError("loads", f"{len(self.loads)} loads over {self.steps + 1} "
                                 f"instants need about {gigabytes(table)} for the load table "
                                 f"(and {gigabytes(records)} for the records), more than the "
                                 f"{gigabytes(MEMORY_LIMIT)} allowed: take a longer dt or a "
                                 f"shorter t_end", len(self.loads))
            raise FieldError("every", f"{samples} recorded samples of {len(self.outputs)} "
                             f"outputs would need about {gigabytes(records)} (and "
                             f"{gigabytes(table)} for the load table), more than the "
                             f"{gigabytes(MEMORY_LIMIT)} allowed: record every more steps",
                             self.every)
        return self

    def refuse_frf_parts(self, substructures: list[Any]) -> None:
        """Refuse a substructure known only by its receptances (``type: frf``): it has no
        ``M``, ``C``, ``K`` to integrate, and leaving it out would answer for another
        structure.

        Raises:
            FieldError: at ``analysis.transient``, naming the part.
        """
        for sub in substructures:
            if getattr(sub, "type", None) == "frf":
                raise FieldError(("analysis", "transient"), f"cannot include substructure "
                                 f"{sub.name!r} (type: frf, known by its receptances only, "
                                 f"without M, C, K to integrate): give it by its matrices or "
                                 f"leave analysis.transient out", sub.name)
