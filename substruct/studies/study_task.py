r"""One sample of a study as a task: ``(case, overrides) -> small result record``.

A :class:`SampleTask` carries everything a sample needs as plain data (the case text, where its
files are, the overrides of the sample, what to collect, the reference mode shapes), so that it
runs the same in this process, in a worker process or on another machine, and shares nothing
with the other samples.  :func:`run_sample` never raises for a sample that cannot be computed:
bad input, a failed cross-check or any other exception becomes the record's ``error`` (one
line), and the study goes on.

What is kept (:class:`substruct.case.study.Collect`): the lowest physical frequencies and
damping ratios, padded with NaN to the count asked for; the peak of each named receptance over
the sweep and where it is; and the modal assurance criterion of mode :math:`i` to mode
:math:`i` of the reference set (the case as written),

.. math::  \mathrm{MAC}_i = \frac{|\phi_i^{r\,H} \phi_i|^2}{(\phi_i^{r\,H}\phi_i^r)
           (\phi_i^H \phi_i)} .
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from typing import Mapping

from substruct.builder import Substructure
from substruct.builder.parts import reduced_part
from substruct.case.loader import parse_case
from substruct.case.study import Collect
from substruct.run.result import Result
from substruct.run.runner import build_model, run_case
from substruct.studies.study_derivative import frequency_derivative

__all__ = ["SampleTask", "SampleRecord", "PartJob", "make_part", "run_sample", "collect",
           "mac_diagonal", "record_fields", "COMPLEX_FIELDS"]


@dataclass(frozen=True)
class SampleTask:
    """One sample: the case as text with its base overrides, and the sample's own overrides.

    Attributes:
        index: position of the sample in the study's table.
        case_text, source, base_dir: the case file's text, its name for messages and the
            directory its matrix and mesh files are relative to.
        overrides: ``key.path=value`` strings, those of the command line then the sample's.
        collect: what to keep of the run.
        reference: the reference mode shapes (``n x k``) for the MAC, or ``None``.
        derivative: ``(parameter, value)`` of the sample when ``collect.derivatives`` asks for
            the frequencies' derivatives with respect to it.
    """

    index: int
    case_text: str
    source: str
    base_dir: str
    overrides: tuple[str, ...]
    collect: Collect
    reference: np.ndarray | None = None
    derivative: tuple[str, float] | None = None


@dataclass(frozen=True)
class PartJob:
    """One reduced part shared by the samples: the case as text (without sample overrides)
    and the part's name."""

    case_text: str
    source: str
    base_dir: str
    name: str


def make_part(job: PartJob) -> Substructure:
    """The reduced part ``job.name`` of the case (:func:`substruct.builder.parts.reduced_part`)."""
    case = parse_case(job.case_text, job.source, job.base_dir)
    return reduced_part(case, job.name)


@dataclass
class SampleRecord:
    """What one sample produced: named small arrays, or the one-line error that stopped it;
    with ``collect.track``, the shapes of its collected modes (``n x k``)."""

    index: int
    values: dict[str, np.ndarray] = field(default_factory=dict)
    error: str = ""
    seconds: float = 0.0
    shapes: np.ndarray | None = None


def record_fields(spec: Collect, n_omega: int = 0) -> dict[str, int]:
    """The arrays of a record and their lengths: ``frequency``, ``damping_ratio``, ``mac``
    (one per mode), ``frf_peak`` and ``frf_peak_omega`` (one per peak), ``frf_omega`` (the
    sweep's ``n_omega`` frequencies) and ``frf`` (complex, the curves one after the other,
    ``n_omega`` values each)."""
    out: dict[str, int] = {}
    if spec.frequencies:
        out["frequency"] = spec.frequencies
    if spec.damping_ratios and spec.frequencies:
        out["damping_ratio"] = spec.frequencies
    if spec.mac and spec.frequencies:
        out["mac"] = spec.frequencies
    if spec.derivatives and spec.frequencies:
        out["frequency_derivative"] = spec.frequencies
    if spec.frf_peaks:
        out["frf_peak"] = out["frf_peak_omega"] = len(spec.frf_peaks)
    if spec.frf:
        out["frf_omega"] = n_omega
        out["frf"] = n_omega * len(spec.frf)
    return out


#: The arrays of a record that are complex.
COMPLEX_FIELDS = ("frf",)


def _padded(values: np.ndarray, n: int) -> np.ndarray:
    out = np.full(n, np.nan)
    k = min(n, len(values))
    out[:k] = np.real(values[:k])
    return out


def mac_diagonal(reference: np.ndarray, shapes: np.ndarray) -> np.ndarray:
    """:math:`\\mathrm{MAC}_i` of column ``i`` of ``shapes`` to column ``i`` of ``reference``
    (NaN where either is missing or the coordinates differ)."""
    k = min(reference.shape[1], shapes.shape[1])
    out = np.full(max(reference.shape[1], shapes.shape[1]), np.nan)
    if reference.shape[0] != shapes.shape[0]:
        return out
    r, s = reference[:, :k], shapes[:, :k]
    cross = np.abs(np.sum(np.conj(r) * s, axis=0)) ** 2
    norms = np.real(np.sum(np.conj(r) * r, axis=0)) * np.real(np.sum(np.conj(s) * s, axis=0))
    out[:k] = cross / norms
    return out


def collect(result: Result, spec: Collect, reference: np.ndarray | None) -> dict[str, np.ndarray]:
    """The small arrays :func:`record_fields` names, from the full result of one run."""
    out: dict[str, np.ndarray] = {}
    n = spec.frequencies
    if n and result.modes is not None:
        out["frequency"] = _padded(result.modes.omega, n)
        if spec.damping_ratios:
            out["damping_ratio"] = _padded(result.modes.damping_ratio, n)
        if spec.mac:
            mac = (mac_diagonal(reference, result.modes.shapes) if reference is not None
                   else np.full(n, np.nan))
            out["mac"] = _padded(mac, n)
    if spec.frf_peaks and result.frf is not None:
        frf = result.frf
        peaks, where = [], []
        for peak in spec.frf_peaks:
            i = frf.outputs.index(peak.output)
            j = frf.inputs.index(peak.input) if peak.input is not None else 0
            magnitude = np.abs(frf.H[:, i, j])
            k = int(np.argmax(magnitude))
            peaks.append(magnitude[k])
            where.append(frf.omega[k])
        out["frf_peak"] = np.asarray(peaks, dtype=float)
        out["frf_peak_omega"] = np.asarray(where, dtype=float)
    if spec.frf and result.frf is not None:
        frf = result.frf
        curves = [frf.H[:, frf.outputs.index(c.output),
                        frf.inputs.index(c.input) if c.input is not None else 0]
                  for c in spec.frf]
        out["frf_omega"] = np.asarray(frf.omega, dtype=float)
        out["frf"] = np.concatenate(curves).astype(complex)
    return out


def run_sample(task: SampleTask, shared: Mapping[str, Substructure] | None = None
               ) -> SampleRecord:
    """Parse the case with the sample's overrides, run it, keep what ``task.collect`` asks for.

    ``shared``: reduced parts the sample's parameters do not change, made once for the study
    (:mod:`substruct.studies.study_shared`), used instead of reducing them again.

    Never raises for a failing sample (``Exception``): its record holds the error, one line.
    """
    start = time.perf_counter()
    record = SampleRecord(index=task.index)
    try:
        case = parse_case(task.case_text, task.source, task.base_dir, list(task.overrides))
        model = build_model(case, prebuilt=shared) if shared else None
        result = run_case(case, model=model)
        record.values = collect(result, task.collect, task.reference)
        n = task.collect.frequencies
        if task.collect.track and result.modes is not None:
            record.shapes = np.asarray(result.modes.shapes[:, :n])
        if task.derivative is not None and result.modes is not None:
            record.values["frequency_derivative"] = frequency_derivative(
                result.modes, n, task.case_text, task.source, task.base_dir,
                list(task.overrides), *task.derivative, shared=shared)
    except Exception as err:  # a failed sample is a result of the study, not its end
        text = " ".join(str(err).split())
        name = type(err).__name__
        record.error = text if name in ("CaseError", "CheckError") else f"{name}: {text}"
    record.seconds = time.perf_counter() - start
    return record
