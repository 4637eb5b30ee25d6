"""The specification analyses of a case: random vibration (force and base-acceleration PSDs,
correlated inputs) and shock response spectra of a transient's outputs (the ``random:`` and
``srs:`` blocks of ``analysis``)."""

from __future__ import annotations

from typing import Annotated, Any, Literal, Sequence

import numpy as np
from pydantic import Discriminator, Field, Tag, model_validator

from substruct.case.check_list import refuse_idle_checks
from substruct.case.errors import FieldError
from substruct.case.fields import (
    MAX_FREQUENCIES,
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
from substruct.case.frequency_grid import Omega
from substruct.case.modal_spec import ModalFrf
from substruct.case.random_cross import CrossPsd, check_cross
from substruct.vocabulary import DEFAULT_TOLERANCE, GENERALIZED_INVERSE, FormulationName

__all__ = ["LossFactorSpec", "BaseDrivenResponse", "PsdTable", "ForcePsd", "BaseSupports", "NamedBaseSupports",
           "BasePsd", "NamedBasePsd", "RandomAnalysis", "BaseFrfAnalysis", "SrsFrequencies",
           "SrsAnalysis"]


#: One loss factor on all of K, or one per substructure (by name); a mapping is validated as
#: one, so that a bad value is named by its substructure.
LossFactorSpec = Annotated[
    Annotated[NonNegative, Tag("all")] | Annotated[dict[Name, NonNegative], Tag("each")],
    Discriminator(lambda v: "each" if isinstance(v, dict) else "all")]


class PsdTable(StrictModel):
    """A PSD specification table ``[[f (Hz), level], ...]``, log-log interpolated between its
    rows (0 outside them)."""

    rows: list[tuple[NonNegative, NonNegative]]

    @model_validator(mode="before")
    @classmethod
    def _list(cls, value: Any) -> Any:
        if not isinstance(value, list):
            raise ValueError("a PSD table is a list of [frequency (Hz), level] rows")
        return {"rows": value}

    @model_validator(mode="after")
    def _table(self) -> "PsdTable":
        if len(self.rows) < 2:
            raise FieldError((), "a PSD table needs at least two [frequency, level] rows",
                             len(self.rows))
        if len(self.rows) > MAX_FREQUENCIES:
            raise FieldError((), f"at most {MAX_FREQUENCIES} rows", len(self.rows))
        for i in range(1, len(self.rows)):
            if self.rows[i][0] <= self.rows[i - 1][0]:
                raise FieldError((i, 0), f"frequencies must increase (after "
                                 f"{self.rows[i - 1][0]:g} Hz)", self.rows[i][0])
        return self

    def columns(self) -> tuple[np.ndarray, np.ndarray]:
        """``(frequency (Hz), level)``."""
        table = np.asarray(self.rows, dtype=float)
        return table[:, 0], table[:, 1]


class ForcePsd(StrictModel):
    """A force PSD (force^2/Hz in the case's units) at a point; several are uncorrelated."""

    at: Point
    psd: PsdTable


class BaseSupports(StrictModel):
    """A base input moving the grounded supports ``at`` together (each held by a constraint
    on it alone, as a transient's base)."""

    at: Annotated[list[Point], Field(min_length=1)]


class NamedBaseSupports(BaseSupports):
    """One of several base inputs (``bases`` of ``analysis.base_frf``): a name and its
    grounded supports ``at`` (moved together, by no other input)."""

    name: Name


class BasePsd(BaseSupports):
    """A base acceleration PSD ((length/s^2)^2/Hz in the case's units) moving the grounded
    supports ``at`` together (each held by a constraint on it alone, as a transient's base)."""

    psd: PsdTable


class NamedBasePsd(BasePsd):
    """One of several base acceleration inputs (``bases``): a name for ``cross``, its grounded
    supports ``at`` (moved together, by no other input) and its PSD."""

    name: Name


class BaseDrivenResponse(StrictModel):
    """What a random response and a base-driven receptance share: the outputs, the motion
    they are given as (absolute displacement, velocity or acceleration), the checks of the
    formulation (each has its own ``method``), and the structural damping; and the rule that names several base inputs
    once each."""

    outputs: Annotated[list[Point], Field(min_length=1)]
    #: what the outputs' response is of (absolute motion; per base acceleration, the
    #: acceleration is the transmissibility proper)
    quantity: Literal["displacement", "velocity", "acceleration"] = "acceleration"
    check: list[FormulationName] = Field(default_factory=list)
    tolerance: Positive = DEFAULT_TOLERANCE
    #: structural damping: one loss factor on all of K, or {substructure: eta}
    loss_factor: LossFactorSpec | None = None

    @staticmethod
    def check_named_once(bases: Sequence[NamedBaseSupports | NamedBasePsd]) -> None:
        """Refuse a name given to two of ``bases``."""
        for k, b in enumerate(bases):
            if b.name in [c.name for c in bases[:k]]:
                raise FieldError(("bases", k, "name"), "a base input named twice", b.name)


class RandomAnalysis(BaseDrivenResponse):
    """Response PSDs ``S_y = H S_f H^H`` and RMS values at ``outputs`` over ``frequencies``
    (Hz) for force PSDs ``forces``, one base acceleration PSD ``base`` or several named ones
    ``bases`` (uncorrelated, or pairs correlated by ``cross``)."""

    frequencies: Omega
    #: a direct formulation, or modal: the receptances summed over the coupled modes
    method: Literal["generalized-inverse", "null-space", "kkt", "modal"] = GENERALIZED_INVERSE
    #: how method: modal sums the modes (as analysis.frf.modal; the AMLS basis included)
    modal: ModalFrf | None = None
    forces: list[ForcePsd] = Field(default_factory=list)
    #: correlated pairs of inputs (:mod:`substruct.case.random_cross`)
    cross: list[CrossPsd] = Field(default_factory=list)
    base: BasePsd | None = None
    bases: list[NamedBasePsd] = Field(default_factory=list)
    #: largest estimated relative error of the trapezoid rule on a mean square (a grid that
    #: steps over a resonance: :mod:`substruct.analysis.frf.psd_resolution`)
    rms_tolerance: Positive = 1e-2

    @model_validator(mode="after")
    def _inputs(self) -> "RandomAnalysis":
        given = [k for k, v in (("forces", self.forces), ("base", self.base),
                                ("bases", self.bases)) if v]
        if len(given) != 1:
            raise FieldError(given[1] if len(given) > 1 else "forces", "give force PSDs "
                             "(forces), a base acceleration PSD (base) or several (bases), one "
                             "of the three")
        self.check_named_once(self.bases)
        refuse_idle_checks(self.method, self.check)
        if self.modal is not None and self.method != "modal":
            raise FieldError("modal", f"the modal block is for method: modal; the method is "
                             f"{self.method}", "{...}")
        if self.modal is not None:
            self.modal.refuse_unchecked(self.check)
        if self.method == "modal" and self.loss_factor is not None:
            raise FieldError("method", "a loss factor is taken by the direct formulations "
                             "only (generalized-inverse, null-space, kkt)", self.method)
        check_cross(self.input_names() if self.base is None else [], self.cross)
        f = self.frequencies.grid()
        if len(f) < 2:
            raise FieldError("frequencies", "the RMS integrates the response PSD over the grid: "
                             "give at least two frequencies", self.frequencies.values)
        if np.any(f <= 0):
            raise FieldError("frequencies", "must be > 0 Hz", float(f[f <= 0][0]))
        if np.any(np.diff(f) <= 0):
            raise FieldError("frequencies", "must increase", self.frequencies.values)
        p = max(len(self.forces), len(self.bases), 1)
        need = 16.0 * len(f) * len(self.outputs) * (p + len(self.outputs))
        if need > memory_limit():
            raise FieldError((), f"the response PSDs would need about {gigabytes(need)} of "
                             f"memory, more than this machine has available", len(f))
        return self

    def hertz(self) -> np.ndarray:
        """The frequency grid (Hz)."""
        return self.frequencies.grid()

    def input_names(self) -> list[str]:
        """The inputs' names: the force points, ``base``, or the names of ``bases``."""
        if self.forces:
            return [ld.at for ld in self.forces]
        return ["base"] if self.base is not None else [b.name for b in self.bases]

    def base_inputs(self) -> list[BasePsd]:
        """The base acceleration inputs (``[base]``, ``bases``, or none for forces)."""
        return [self.base] if self.base is not None else list(self.bases)


class BaseFrfAnalysis(BaseDrivenResponse):
    """Transmissibilities ``T[k, i, j]``: output ``i``'s displacement, velocity or
    acceleration (absolute) per unit acceleration of base input ``j`` at ``omega`` (> 0), one
    base ``base`` or several named ones ``bases`` (the supports of ``analysis.random``)."""

    omega: Omega
    method: FormulationName = GENERALIZED_INVERSE
    #: the unit of the omega grid's values (rad/s or Hz)
    units: Literal["rad/s", "Hz"] = "rad/s"
    base: BaseSupports | None = None
    bases: list[NamedBaseSupports] = Field(default_factory=list)

    @model_validator(mode="after")
    def _inputs(self) -> "BaseFrfAnalysis":
        if (self.base is None) == (not self.bases):
            raise FieldError("bases" if self.bases else "base", "give one base input (base) "
                             "or several (bases), one of the two")
        self.check_named_once(self.bases)
        refuse_idle_checks(self.method, self.check)
        w = self.omega.grid()
        if np.any(w <= 0):
            raise FieldError("omega", "must be > 0 (the response per unit base acceleration "
                             "is unbounded at omega = 0)", float(w[w <= 0][0]))
        need = 16.0 * len(w) * len(self.outputs) * max(len(self.bases), 1)
        if need > memory_limit():
            raise FieldError((), f"the transmissibilities would need about {gigabytes(need)} "
                             f"of memory, more than this machine has available", len(w))
        return self

    def omegas(self) -> np.ndarray:
        """The circular frequencies of the grid (rad/s), converted from Hz if ``units: Hz``."""
        w = self.omega.grid()
        return 2 * np.pi * w if self.units == "Hz" else w

    def input_names(self) -> list[str]:
        """``base``, or the names of ``bases``."""
        return ["base"] if self.base is not None else [b.name for b in self.bases]

    def base_inputs(self) -> list[BaseSupports]:
        """The base inputs (``[base]`` or ``bases``)."""
        return [self.base] if self.base is not None else list(self.bases)


class SrsFrequencies(StrictModel):
    """The natural frequencies of an SRS (Hz): ``start`` to ``stop``, ``num`` log-spaced or
    ``per_octave`` a factor ``2^(1/per_octave)`` apart."""

    start: Positive
    stop: Positive
    num: Count | None = None
    per_octave: Count | None = None

    @model_validator(mode="after")
    def _grid(self) -> "SrsFrequencies":
        if self.stop <= self.start:
            raise FieldError("stop", f"must be > start ({self.start:g})", self.stop)
        if (self.num is None) == (self.per_octave is None):
            raise FieldError("num", "give num or per_octave, one of the two")
        if self.count() > MAX_FREQUENCIES:  # counted, never allocated, before the check
            key = "per_octave" if self.num is None else "num"
            raise FieldError(key, f"{self.count():,} frequencies from {self.start:g} to "
                             f"{self.stop:g} Hz, at most {MAX_FREQUENCIES:,}",
                             getattr(self, key))
        return self

    def count(self) -> int:
        """The number of frequencies of :meth:`grid`, computed without building it."""
        if self.num is not None:
            return self.num
        assert self.per_octave is not None
        return int(np.floor(self.per_octave * np.log2(self.stop / self.start) + 1e-9)) + 1

    def grid(self) -> np.ndarray:
        """The natural frequencies (Hz)."""
        if self.num is not None:
            return np.geomspace(self.start, self.stop, self.num)
        assert self.per_octave is not None
        return self.start * 2.0 ** (np.arange(self.count()) / self.per_octave)


class SrsAnalysis(StrictModel):
    """Shock response spectra of the absolute accelerations of a transient's ``outputs``
    (all of them if not given), damping ratio ``damping`` or ``Q = 1 / (2 damping)``."""

    frequencies: SrsFrequencies
    outputs: Annotated[list[Point], Field(min_length=1)] | None = None
    damping: Annotated[Number, Field(gt=0, lt=1)] | None = None
    Q: Annotated[Number, Field(gt=0.5)] | None = None

    @model_validator(mode="after")
    def _damping(self) -> "SrsAnalysis":
        if self.damping is not None and self.Q is not None:
            raise FieldError("Q", "give damping or Q, not both", self.Q)
        return self

    def zeta(self) -> float:
        """The damping ratio (0.05, Q = 10, if neither is given)."""
        if self.Q is not None:
            return 1 / (2 * self.Q)
        return 0.05 if self.damping is None else float(self.damping)
