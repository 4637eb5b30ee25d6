r"""The ``study:`` block of a case: which parameter values to run and what to keep of each run.

A study runs the case once per *sample*, each sample a set of values of case ``parameters``
(which stiffness, mass, damping, modulus, ... name, :mod:`substruct.case.fields`)::

    study:
      grid:                       # or random: (below)
        combine: product          # product (the first parameter varies slowest) | zip
        parameters:
          - {parameter: kc, values: [5000, 6000, 7000]}
          - {parameter: cc, start: 0, stop: 40, num: 5, spacing: linear}   # or log
      collect:
        frequencies: 4            # the lowest 4 physical frequencies (rad/s)
        damping_ratios: true
        frf_peaks: [rod@200]      # max |H| over the sweep, outputs of analysis.frf
        frf: [rod@200]            # the whole curve H(omega) of each sample
        mac: true                 # MAC of each mode to the same mode of the case as written

    study:
      random:
        seed: 1
        count: 200
        parameters:
          - {parameter: EA0, distribution: normal, mean: 6.0e6, std: 3.0e5}
          - {parameter: m0, distribution: lognormal, median: 1.0, sigma: 0.05}
          - {parameter: kc, distribution: uniform, low: 6000, high: 8000}

Samples are drawn on the client, once, from ``numpy.random.Generator(PCG64(seed))`` in the
order the parameters are listed (:func:`substruct.studies.study_plan.samples`), so the same seed
gives the same table bit for bit on any backend.  A lognormal parameter is
:math:`\exp(\ln(\text{median}) + \sigma\, \xi)`, :math:`\xi \sim N(0, 1)`.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal, Union

from pydantic import BeforeValidator, Field, model_validator

from substruct.case.errors import FieldError
from substruct.case.fields import (
    MEMORY_LIMIT,
    Count,
    Name,
    NonNegative,
    Number,
    Point,
    Positive,
    StrictModel,
    gigabytes,
)

__all__ = ["GridAxis", "Grid", "RandomParameter", "RandomSamples", "Collect", "StudySpec",
           "PeakSpec", "MAX_SAMPLES", "SAMPLE_OVERHEAD", "collect_text"]

#: Most samples a study may ask for (a grid's product, a zip, a random count, an axis).
MAX_SAMPLES = 1_000_000
#: Bytes a sample takes before what it collects: its row of the table, its task (the
#: overrides as text) and its record (:func:`StudySpec.memory`).
SAMPLE_OVERHEAD = 512


class GridAxis(StrictModel):
    """One parameter of a grid: ``values: [...]`` or ``start, stop, num`` (linear or log)."""

    parameter: Name
    values: Annotated[list[Number], Field(min_length=1)] | None = None
    start: Number | None = None
    stop: Number | None = None
    num: Count | None = None
    spacing: Literal["linear", "log"] = "linear"

    @model_validator(mode="after")
    def _one_form(self) -> "GridAxis":
        ranged = (self.start, self.stop, self.num)
        if self.values is not None:
            for key in ("start", "stop", "num", "spacing"):
                if key in self.model_fields_set:
                    raise FieldError(key, "not a key of an axis given by values (start, stop, "
                                     "num and spacing make a range, without values)",
                                     getattr(self, key))
        if (self.values is None) == all(v is None for v in ranged):
            raise ValueError("give values: [...] or start, stop and num")
        if self.values is None:
            for key, v in zip(("start", "stop", "num"), ranged):
                if v is None:
                    raise FieldError(key, "a range needs start, stop and num")
            if self.spacing == "log" and (self.start or 0) <= 0:
                raise FieldError("start", "a log range starts above 0", self.start)
            if self.spacing == "log" and (self.stop or 0) <= 0:
                raise FieldError("stop", "a log range ends above 0", self.stop)
            if self.num == 1 and self.start != self.stop:
                raise FieldError("num", f"a range of one value is start ({self.start:g}) alone "
                                 f"and would leave stop ({self.stop:g}) out: give values: "
                                 f"[{self.start:g}] or num >= 2", self.num)
            if (self.num or 0) > MAX_SAMPLES:
                raise FieldError("num", f"at most {MAX_SAMPLES:,} values", self.num)
        elif len(self.values) > MAX_SAMPLES:
            raise FieldError("values", f"{len(self.values):,} values, at most "
                             f"{MAX_SAMPLES:,}", f"a list of {len(self.values):,} numbers")
        return self

    def count(self) -> int:
        """The number of values of the axis (from ``values`` or ``num``; none computed)."""
        return len(self.values) if self.values is not None else int(self.num or 0)


class Grid(StrictModel):
    """Several :class:`GridAxis`, combined as their product or zipped."""

    combine: Literal["product", "zip"] = "product"
    parameters: Annotated[list[GridAxis], Field(min_length=1)]

    @model_validator(mode="after")
    def _size(self) -> "Grid":
        r"""A product grid's size :math:`\prod_i n_i` from the declared counts (Python
        integers, nothing allocated), at most :data:`MAX_SAMPLES`; the axis where the running
        product first passes the limit is named, the whole product shown."""
        if self.combine != "product":
            return self
        counts = [axis.count() for axis in self.parameters]
        total = 1
        for n in counts:
            total *= n
        if total <= MAX_SAMPLES:
            return self
        shown = " x ".join(map(str, counts[:8])) + (" x ..." if len(counts) > 8 else "")
        size = f"{total:,}" if total < 10 ** 30 else \
            f"about 10^{int(total.bit_length() * 0.30103)}"
        running = 1
        for k, axis in enumerate(self.parameters):
            running *= counts[k]
            if running > MAX_SAMPLES:
                key = "num" if axis.values is None else "values"
                raise FieldError(("parameters", k, key), f"the product grid {shown} is {size} "
                                 f"samples, at most {MAX_SAMPLES:,}",
                                 axis.num if axis.values is None else axis.values)
        return self


class RandomParameter(StrictModel):
    """A parameter drawn from ``normal {mean, std}``, ``lognormal {median, sigma}`` or
    ``uniform {low, high}``."""

    parameter: Name
    distribution: Literal["normal", "lognormal", "uniform"]
    mean: Number | None = None
    std: NonNegative | None = None
    median: Positive | None = None
    sigma: NonNegative | None = None
    low: Number | None = None
    high: Number | None = None

    @model_validator(mode="after")
    def _arguments(self) -> "RandomParameter":
        need = {"normal": ("mean", "std"), "lognormal": ("median", "sigma"),
                "uniform": ("low", "high")}[self.distribution]
        for key in ("mean", "std", "median", "sigma", "low", "high"):
            given = getattr(self, key) is not None
            if key in need and not given:
                raise FieldError(key, f"a {self.distribution} distribution needs "
                                 f"{' and '.join(need)}")
            if key not in need and given:
                raise FieldError(key, f"not an argument of a {self.distribution} "
                                 f"distribution (it takes {' and '.join(need)})",
                                 getattr(self, key))
        if self.distribution == "uniform" and not (self.low or 0) < (self.high or 0):
            raise FieldError("high", "must be above low", self.high)
        return self


class RandomSamples(StrictModel):
    """``count`` samples of the listed parameters, drawn with ``seed``."""

    seed: Annotated[int, Field(ge=0, le=2**63 - 1)]
    count: Annotated[Count, Field(le=MAX_SAMPLES)]
    parameters: Annotated[list[RandomParameter], Field(min_length=1)]


class PeakSpec(StrictModel):
    """A receptance whose peak over the sweep is kept: ``output`` for ``input``."""

    output: Point
    input: Point | None = None


def _peak(value: Any) -> Any:
    """``rod@200`` is ``{output: rod@200}``."""
    return {"output": value} if isinstance(value, str) else value


class Collect(StrictModel):
    """What each sample keeps (small arrays; the full result of a sample is not kept)."""

    frequencies: Annotated[int, Field(ge=0, le=10_000)] = 0
    damping_ratios: bool = False
    frf_peaks: list[Annotated[PeakSpec, BeforeValidator(_peak)]] = Field(default_factory=list)
    frf: list[Annotated[PeakSpec, BeforeValidator(_peak)]] = Field(default_factory=list)
    mac: bool = False
    #: follow the modes from sample to sample by MAC (a grid of one parameter, or a zip)
    track: bool = False
    #: d omega / d parameter of each mode from the formulation (a grid of one parameter)
    derivatives: bool = False


class StudySpec(StrictModel):
    """The ``study:`` block: ``grid`` or ``random``, and ``collect``."""

    grid: Grid | None = None
    random: RandomSamples | None = None
    collect: Collect = Field(default_factory=Collect)

    @model_validator(mode="after")
    def _one(self) -> "StudySpec":
        if (self.grid is None) == (self.random is None):
            raise ValueError("give exactly one of grid: and random:")
        return self

    def parameter_names(self) -> list[str]:
        """The parameters the study varies, in the order of the block."""
        axes: list[Union[GridAxis, RandomParameter]] = list(
            self.grid.parameters if self.grid is not None else
            self.random.parameters if self.random is not None else [])
        return [a.parameter for a in axes]

    def check(self, case: Any) -> None:
        """Cross-checks against the case: known, distinct parameters; frequencies and MAC need
        ``analysis.modes``, peaks ``analysis.frf`` and its points.

        Raises:
            FieldError: at ``study...``, naming the field.
        """
        kind = "grid" if self.grid is not None else "random"
        names = self.parameter_names()
        for k, name in enumerate(names):
            loc = ("study", kind, "parameters", k, "parameter")
            if name not in case.parameters:
                known = ", ".join(case.parameters) or "none"
                raise FieldError(loc, f"not a parameter of the case (parameters: {known})",
                                 name)
            if name in names[:k]:
                raise FieldError(loc, "a parameter varied twice", name)
        if self.grid is not None and self.grid.combine == "zip":
            sizes = [len(a.values) if a.values is not None else a.num or 0
                     for a in self.grid.parameters]
            if len(set(sizes)) > 1:
                raise FieldError(("study", "grid", "combine"), f"zip needs as many values of "
                                 f"every parameter, got {sizes}", "zip")
        collect = self.collect
        modes = case.analysis.modes
        if (collect.frequencies or collect.damping_ratios or collect.mac) and modes is None:
            raise FieldError(("study", "collect"), "frequencies, damping ratios and MAC need "
                             "analysis.modes")
        if modes is not None and collect.frequencies > modes.count:
            raise FieldError(("study", "collect", "frequencies"), f"more than the "
                             f"{modes.count} modes of analysis.modes.count",
                             collect.frequencies)
        for key in ("damping_ratios", "mac"):
            if getattr(collect, key) and not collect.frequencies:
                raise FieldError(("study", "collect", key), "needs collect.frequencies (the "
                                 "modes whose values are kept)", True)
        for key in ("track", "derivatives"):
            if not getattr(collect, key):
                continue
            if not collect.frequencies:
                raise FieldError(("study", "collect", key), "needs collect.frequencies (the "
                                 "modes to follow)", True)
            one = self.grid is not None and (len(self.grid.parameters) == 1 or (
                key == "track" and self.grid.combine == "zip"))
            if not one:
                raise FieldError(("study", "collect", key), "needs a grid of one parameter"
                                 + (" (or a zip)" if key == "track" else ""), True)
        frf = case.analysis.frf
        n_omega = len(frf.omega.grid()) if frf is not None and collect.frf else 0
        need = self.memory(n_omega)
        if need > MEMORY_LIMIT:
            what = collect_text(collect, n_omega)
            raise FieldError(("study",), f"{self.size():,} samples collecting {what} would "
                             f"need about {gigabytes(need)} of memory, at most "
                             f"{gigabytes(MEMORY_LIMIT)}: fewer samples, or less collected")
        for key, k, peak in [("frf_peaks", k, p) for k, p in enumerate(collect.frf_peaks)] + \
                [("frf", k, p) for k, p in enumerate(collect.frf)]:
            where: tuple[str | int, ...] = ("study", "collect", key, k)
            if frf is None:
                what = "an FRF peak" if key == "frf_peaks" else "an FRF curve"
                raise FieldError(where, f"{what} needs analysis.frf", peak.output)
            if peak.output not in frf.outputs:
                raise FieldError((*where, "output"), f"not an output of analysis.frf "
                                 f"({', '.join(frf.outputs)})", peak.output)
            if peak.input is not None and peak.input not in frf.inputs:
                raise FieldError((*where, "input"), f"not an input of analysis.frf "
                                 f"({', '.join(frf.inputs)})", peak.input)

    def size(self) -> int:
        """The number of samples (from the declared counts, Python integers)."""
        if self.random is not None:
            return int(self.random.count)
        assert self.grid is not None
        sizes = [a.count() for a in self.grid.parameters]
        if self.grid.combine == "zip":
            return min(sizes)
        total = 1
        for s in sizes:
            total *= s
        return total

    def memory(self, n_omega: int = 0, n_dof: int = 0) -> int:
        r"""Bytes the study holds for its samples, from the declared counts: per sample its
        parameters and time (8 bytes each), :data:`SAMPLE_OVERHEAD`, 8 bytes a collected real
        (frequencies, damping ratios, MAC, peaks and where they are, the sweep's
        ``n_omega`` frequencies), 16 a complex (``n_omega`` per collected curve) and, with
        ``track``, the shapes of the ``f`` collected modes over the model's ``n_dof``
        coordinates (complex; 0 until the model is built),

        .. math::  S \left(8 (p + 1) + o + 8 (3 f + 2 q + n_\omega)
                   + 16\, c\, n_\omega + 16\, t\, n\, f\right) .
        """
        c = self.collect
        per = 8 * (len(self.parameter_names()) + 1) + SAMPLE_OVERHEAD \
            + 8 * (3 * c.frequencies + 2 * len(c.frf_peaks)) \
            + (8 * n_omega + 16 * len(c.frf) * n_omega if c.frf else 0) \
            + (16 * n_dof * c.frequencies if c.track else 0)
        return self.size() * per


def collect_text(collect: Collect, n_omega: int) -> str:
    """What each sample keeps, in words, for a message (``"4 frequencies and 2 curves of 181
    frequencies"``)."""
    parts = []
    if collect.frequencies:
        parts.append(f"{collect.frequencies} frequencies")
    if collect.frf_peaks:
        parts.append(f"{len(collect.frf_peaks)} peaks")
    if collect.frf:
        parts.append(f"{len(collect.frf)} FRF curves of {n_omega:,} frequencies")
    return " and ".join(parts) or "nothing"
