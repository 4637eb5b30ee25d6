"""A whole study: the samples of a case's ``study:`` block run on a backend, gathered into one
table (:class:`StudyResult`) that :mod:`substruct.io.study_file` writes.

Data flow: :func:`study_tasks` turns the case into one
:class:`~substruct.studies.study_task.SampleTask` per row of the parameter table
(:func:`substruct.studies.study_plan.samples`); :func:`substruct.studies.study_backend.execute`
runs them; :func:`gather` stacks the records.  A failed sample leaves NaN in its rows and its
message in ``errors``; the others are unaffected.
"""

from __future__ import annotations

import re
import time
from dataclasses import dataclass, field, replace

import numpy as np

from substruct.case.fields import gigabytes, memory_limit
from substruct.case.loader import Case
from substruct.case.study import StudySpec
from substruct.run.runner import build_model, run_case
from substruct.studies.study_backend import Backend, Session, Tick
from substruct.studies.study_inputs import check_study_parameters
from substruct.studies.study_plan import overrides_of, samples
from substruct.studies.study_shared import shared_parts
from substruct.studies.study_tracking import TrackedStudy, track_study
from substruct.studies.study_task import (
    PartJob,
    SampleRecord,
    COMPLEX_FIELDS,
    SampleTask,
    collect,
    record_fields,
)

__all__ = ["StudyResult", "study_tasks", "gather", "run_study", "study_of",
           "check_tracked_memory", "UNCOLLECTED"]


@dataclass
class StudyResult:
    """Everything a study produced.

    Attributes:
        case_name: the case's name.
        kind: ``"grid"`` or ``"random"``.
        parameters: the names of the varied parameters.
        table: ``(samples, parameters)`` values.
        values: collected arrays by name, each ``(samples, k)`` (NaN for failed samples);
            ``frf`` is ``(samples, n_omega, curves)``, complex.
        errors: one message per sample, ``""`` for a sample that ran.
        seconds: time each sample took where it ran.
        reference: the collected arrays of the case as written (no study values).
        backend: where it ran.
        case_yaml: the case text.
        peaks: ``"output<-input"`` names of the FRF peaks.
        curves: ``"output<-input"`` names of the full FRF curves (``values["frf"][s, :, c]``).
        shared: the reduced parts made once and shared by every sample.
        shared_seconds: the time it took to make them.
        tracking: the modes followed through the samples (``collect: track``), or a note
            saying why they could not be.
    """

    case_name: str
    kind: str
    parameters: list[str]
    table: np.ndarray
    values: dict[str, np.ndarray]
    errors: list[str]
    seconds: np.ndarray
    reference: dict[str, np.ndarray] = field(default_factory=dict)
    backend: str = "in-process"
    case_yaml: str = ""
    peaks: list[str] = field(default_factory=list)
    curves: list[str] = field(default_factory=list)
    shared: list[str] = field(default_factory=list)
    shared_seconds: float = 0.0
    tracking: TrackedStudy | str | None = None

    @property
    def failed(self) -> list[int]:
        """Indices of the samples that failed."""
        return [k for k, e in enumerate(self.errors) if e]


#: The analyses no ``collect`` entry reads: a study refuses them rather than compute each
#: for every sample and discard it.
UNCOLLECTED = ("transient", "random", "base_frf", "srs", "tpa", "semm")


def study_of(case: Case) -> StudySpec:
    """The case's ``study:`` block.

    Raises:
        CaseError: the case has none; a ``--set`` of a parameter the study varies, or a
            varied parameter that reaches nothing
            (:func:`substruct.studies.study_inputs.check_study_parameters`); an analysis no
            ``collect`` entry reads (:data:`UNCOLLECTED`).
    """
    if case.study is None:
        raise case.error(("study",), "the case has no study: block (see docs/studies.md)")
    check_study_parameters(case, case.study.parameter_names())
    for key in UNCOLLECTED:
        if getattr(case.analysis, key, None) is not None:
            raise case.error(("analysis", key), "a study collects nothing of it (collect "
                             "takes modes and receptances: frequencies, damping ratios, MAC, "
                             "FRF peaks and curves), yet every sample would compute it; leave "
                             "it out of the case the study runs", "{...}")
    return case.study


def check_tracked_memory(case: Case, n_dof: int) -> None:
    r"""Refuse a tracked study (``collect: track``) whose samples, each keeping the shapes of
    its ``f`` collected modes over the model's ``n_dof`` coordinates (16 bytes a value:
    :math:`S\, n\, f \cdot 16` more than :meth:`StudySpec.memory` counts without them), would
    not fit the memory the machine has available
    (:func:`~substruct.case.fields.memory_limit`).

    Raises:
        CaseError: at ``study.collect.track``, with the estimate.
    """
    spec = study_of(case)
    frf = case.analysis.frf
    n_omega = len(frf.omega.grid()) if frf is not None and spec.collect.frf else 0
    need = spec.memory(n_omega, n_dof)
    limit = memory_limit()
    if need > limit:
        raise case.error(("study", "collect", "track"), f"{spec.size():,} samples keeping the "
                         f"shapes of {spec.collect.frequencies} modes over {n_dof:,} "
                         f"coordinates would need about {gigabytes(need)} of memory, more than "
                         f"the {gigabytes(limit)} available: fewer samples or modes, or no "
                         "track", True)


def study_tasks(case: Case, reference: np.ndarray | None = None) -> tuple[list[str], np.ndarray,
                                                                          list[SampleTask]]:
    """The parameter names, the table and one task per sample of the case's study."""
    spec = study_of(case)
    names, table = samples(spec)
    tasks = [SampleTask(index=k, case_text=case.text, source=case.source,
                        base_dir=str(case.base_dir), overrides=tuple(overrides_of(names, row)),
                        collect=spec.collect, reference=reference,
                        derivative=(names[0], float(row[0])) if spec.collect.derivatives
                        else None)
             for k, row in enumerate(table)]
    return names, table, tasks


def gather(records: list[SampleRecord], spec: StudySpec, n_omega: int = 0
           ) -> tuple[dict[str, np.ndarray], list[str], np.ndarray]:
    """Stack the records: arrays ``(samples, k)`` (NaN for a failed sample), errors, seconds.

    The full FRF (``collect: frf``) is ``frf`` ``(samples, n_omega, curves)``, complex, with
    ``frf_omega`` ``(samples, n_omega)``; a sample whose sweep has not ``n_omega``
    frequencies (its grid named a varied parameter) is recorded as failed.
    """
    lengths = record_fields(spec.collect, n_omega)
    values: dict[str, np.ndarray] = {
        name: np.full((len(records), n), np.nan, dtype=complex if name in COMPLEX_FIELDS
                      else float) for name, n in lengths.items()}
    errors = []
    for s, record in enumerate(records):
        error = record.error
        sizes = {name: len(array) for name, array in record.values.items()}
        if not error and any(sizes[n] != lengths[n] for n in sizes):
            error = (f"the sweep has {sizes.get('frf_omega')} frequencies, the study's "
                     f"{n_omega}: collect: frf needs one grid for every sample")
        errors.append(error)
        if error:
            continue
        for name, array in record.values.items():
            values[name][s, :] = array
    if "frf" in values:
        curves = len(spec.collect.frf)
        values["frf"] = values["frf"].reshape(len(records), curves, n_omega).transpose(0, 2, 1)
    return values, errors, np.array([r.seconds for r in records])


def run_study(case: Case, backend: Backend = Backend(), tick: Tick | None = None,
              share: bool = True, parts_tick: Tick | None = None) -> StudyResult:
    """Run the study of ``case`` on ``backend`` (default: in-process, serial).

    The reduced parts no study parameter changes (:func:`substruct.studies.study_shared.
    shared_parts`) are made once (on Dask one task each, then scattered to every worker) and
    used by every sample, unless ``share`` is false; the table is the same either way.
    ``tick(done, total)`` is called as samples finish, ``parts_tick`` as shared parts do.  The
    case as written is run first, here, when the MAC is collected: its mode shapes are the
    reference set, sent with every task.

    With ``collect: track`` the case as written is built first and the study refused if the
    shapes its samples keep would not fit (:func:`check_tracked_memory`), before any sample.

    Raises:
        CaseError: no study block, or the case as written cannot be run for the reference,
            or a shared part cannot be made, or a tracked study too large for the memory.
        BackendError: the backend cannot be used.
    """
    spec = study_of(case)
    built = None
    if spec.collect.track:  # the shapes kept depend on the model's size: build it first
        built = build_model(case)
        check_tracked_memory(case, built.assembly.n_dof)
    names, table, tasks = study_tasks(case)
    names_shared = shared_parts(case, names) if share else []
    jobs = [PartJob(case.text, case.source, str(case.base_dir), n) for n in names_shared]
    with Session(backend) as session:
        start = time.perf_counter()
        shared = session.parts(jobs, parts_tick) if jobs else {}
        made = time.perf_counter() - start
        reference: dict[str, np.ndarray] = {}
        if spec.collect.mac:
            model = build_model(case, prebuilt=shared) if shared else built
            base = run_case(case, model=model)
            shapes = base.modes.shapes if base.modes is not None else None
            reference = collect(base, spec.collect, shapes)
            tasks = [replace(t, reference=shapes) for t in tasks]
        records = session.samples(tasks, tick, shared)
    frf = case.analysis.frf
    n_omega = len(frf.omega.grid()) if frf is not None and spec.collect.frf else 0
    values, errors, seconds = gather(records, spec, n_omega)
    first = frf.inputs[0] if frf is not None else ""
    peaks = [f"{p.output}<-{p.input or first}" for p in spec.collect.frf_peaks]
    curves = [f"{p.output}<-{p.input or first}" for p in spec.collect.frf]
    if "frf" in reference:
        reference["frf"] = reference["frf"].reshape(len(curves), -1).T
    tracking: TrackedStudy | str | None = None
    if spec.collect.track:
        others: dict[str, np.ndarray] = {
            k: values[k] for k in ("damping_ratio", "frequency_derivative") if k in values}
        tracking = track_study(names[0], table[:, 0], values["frequency"],
                               [r.shapes for r in records], others)
    return StudyResult(case_name=case.name, kind="grid" if spec.grid is not None else "random",
                       parameters=names, table=table, values=values, errors=errors,
                       seconds=seconds, reference=reference, backend=backend.describe(),
                       case_yaml=case.text, peaks=peaks, curves=curves, shared=names_shared,
                       shared_seconds=made, tracking=tracking)
