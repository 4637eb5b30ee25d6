r"""One analysis spread over a backend: its substructure reductions and the frequency chunks of
its receptance sweep as tasks.

:func:`run_distributed` makes every reduced part of the case (rods and solids with ``reduce:``,
:func:`substruct.builder.parts.reduced_part`) as one task each, all at once; assembles the model
with them (the same model as :func:`substruct.run.runner.build_model`, bit for bit); computes
the modes where it runs; and, for a direct receptance sweep (``generalized-inverse``,
``null-space``, ``kkt``: each frequency solved on its own), splits the frequency grid into
``chunks`` consecutive pieces, one task each on the model scattered to every worker, and puts
the pieces back in order.  Each frequency is solved by the same code on the same matrices, so
the curve is the serial sweep's.  Each chunk is checked on its own (its cross-checks and
constraint residual held to the case's tolerance); the joined sweep reports for each figure the
largest over the chunks, which for a figure relative to ``max |H|`` is at least the whole
sweep's,

.. math::  r = \max_c r_c \ \ge\ \frac{\max_k |H^{check}_k - H_k|}{\max_k |H_k|} .

A modal sweep (``modal``, ``auto``) is not split (its modes and their cut-off belong to the
whole grid); it runs where the modes do.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Sequence

import numpy as np

from substruct.analysis.formulations import FORMULATIONS
from substruct.analysis.results import Receptance
from substruct.builder.model import Model
from substruct.builder.parts import reduced_names
from substruct.case.loader import Case, parse_case
from substruct.run.analyses import frf_result
from substruct.run.result import Result
from substruct.run.runner import build_model, run_case
from substruct.studies.study_backend import Backend, Session, Tick
from substruct.studies.study_plan import number_text
from substruct.studies.study_task import PartJob

__all__ = ["ChunkJob", "chunk_bounds", "sweep_chunk", "join_chunks",
           "run_distributed"]


@dataclass(frozen=True)
class ChunkJob:
    """A piece of a sweep: the case as text and the grid values (in the grid's unit) of the
    chunk."""

    case_text: str
    source: str
    base_dir: str
    values: tuple[float, ...]


def chunk_bounds(n: int, chunks: int) -> list[tuple[int, int]]:
    """``chunks`` consecutive ``[start, stop)`` pieces of ``range(n)``, sizes differing by at
    most one (fewer pieces when ``n < chunks``)."""
    chunks = max(1, min(int(chunks), n))
    edges = [round(k * n / chunks) for k in range(chunks + 1)]
    return [(a, b) for a, b in zip(edges[:-1], edges[1:]) if b > a]


def sweep_chunk(job: ChunkJob, model: Model) -> Receptance:
    """The receptances of the case at the chunk's frequencies, on the assembled ``model``."""
    values = "[" + ", ".join(number_text(v) for v in job.values) + "]"
    case = parse_case(job.case_text, job.source, job.base_dir,
                      [f"analysis.frf.omega={values}"])
    return frf_result(case, model, None)


def join_chunks(pieces: Sequence[Receptance]) -> Receptance:
    """The chunks of one sweep, in order, as one :class:`Receptance` (each check figure the
    largest over the chunks)."""
    first = pieces[0]
    agreement = {name: max(p.agreement.get(name, 0.0) for p in pieces)
                 for name in first.agreement}
    return replace(first, omega=np.concatenate([p.omega for p in pieces]),
                   H=np.concatenate([p.H for p in pieces], axis=0), agreement=agreement,
                   constraint_residual=max(p.constraint_residual for p in pieces))


def run_distributed(case: Case, backend: Backend = Backend(), chunks: int = 1,
                    tick: Tick | None = None) -> Result:
    """Run ``case`` with its reductions as tasks and its direct sweep in ``chunks`` tasks
    (``tick(done, total)`` as reductions, then chunks, finish).

    Returns:
        The :class:`~substruct.run.result.Result` of :func:`substruct.run.runner.run_case`
        (the same receptances, frequency by frequency).

    Raises:
        CaseError, CheckError: as :func:`~substruct.run.runner.run_case`.
        BackendError: the backend cannot be used.
    """
    jobs = [PartJob(case.text, case.source, str(case.base_dir), n) for n in reduced_names(case)]
    frf = case.analysis.frf
    with Session(backend) as session:
        parts = session.parts(jobs, tick) if jobs else {}
        model = build_model(case, prebuilt=parts)
        if frf is None or frf.method not in FORMULATIONS or chunks <= 1:  # one solve a frequency
            return run_case(case, model=model)
        grid = np.asarray(frf.omega.grid(), dtype=float)
        rest = case.model_copy(update={"analysis": case.analysis.model_copy(
            update={"frf": None})})
        result = run_case(rest, model=model)
        pieces = [ChunkJob(case.text, case.source, str(case.base_dir),
                           tuple(float(v) for v in grid[a:b]))
                  for a, b in chunk_bounds(len(grid), chunks)]
        shared = session.scatter(model)
        received = session.map(sweep_chunk, pieces, [shared] * len(pieces), tick=tick)
        result.frf = join_chunks(received)
    return result
