"""Where the samples of a study run: in this process one after the other (the default), on a
``dask.distributed`` LocalCluster of worker processes started here, or on an existing cluster
reached through its scheduler's address.

Every backend runs the same :func:`substruct.studies.study_task.run_sample` on the same
:class:`~substruct.studies.study_task.SampleTask` objects and returns the records in the order
of the tasks, so the study's table does not depend on the backend.  On Dask each task is
submitted with ``retries``: a task whose worker dies is run again on another worker (the
scheduler does that by itself for a lost worker, up to ``distributed.scheduler.allowed-failures``
times); a task that still cannot finish becomes a failed sample with the message Dask gave.

A :class:`Session` keeps one client for a whole study: the shared reduced parts are made first
(one task each), scattered to every worker once (``client.scatter(..., broadcast=True)``) and
handed to every sample task.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any, Callable, Mapping, Sequence

from substruct.builder import Substructure
from substruct.studies.study_task import (
    PartJob,
    SampleRecord,
    SampleTask,
    make_part,
    run_sample,
)

__all__ = ["Backend", "BackendError", "Session", "execute", "RETRIES"]

#: How many times Dask runs a task again after it failed (a killed worker included).
RETRIES = 3

#: ``progress(done, total)`` after each finished sample.
Tick = Callable[[int, int], None]


class BackendError(RuntimeError):
    """The backend cannot be used: Dask not installed, the scheduler not reachable."""


@dataclass(frozen=True)
class Backend:
    """``workers``: start a LocalCluster of that many processes (one thread each);
    ``scheduler``: ``tcp://host:port`` of an existing cluster; neither: in-process, serial."""

    workers: int | None = None
    scheduler: str | None = None
    connect_timeout: float = 20.0

    def describe(self) -> str:
        """``"in-process"``, ``"LocalCluster (2 workers)"`` or ``"scheduler tcp://..."``."""
        if self.scheduler is not None:
            return f"scheduler {self.scheduler}"
        if self.workers is not None:
            return f"LocalCluster ({self.workers} worker{'s' * (self.workers != 1)})"
        return "in-process"


def _serial(tasks: Sequence[SampleTask], tick: Tick | None,
            shared: Mapping[str, Substructure] | None = None) -> list[SampleRecord]:
    out = []
    for k, task in enumerate(tasks):
        out.append(run_sample(task, shared))
        if tick is not None:
            tick(k + 1, len(tasks))
    return out


def _client(backend: Backend) -> tuple[Any, Any]:
    """A ``distributed.Client`` and the LocalCluster it owns (``None`` for a scheduler)."""
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise BackendError("--workers and --scheduler need dask.distributed: "
                           "pip install 'substruct[dask]'") from None
    if backend.scheduler is not None:
        try:
            return Client(backend.scheduler, timeout=backend.connect_timeout), None
        except (OSError, TimeoutError, ValueError) as err:
            detail = " ".join(str(err).split()) or type(err).__name__
            raise BackendError(f"cannot reach the Dask scheduler {backend.scheduler} "
                               f"({detail})") from None
    cluster = LocalCluster(n_workers=int(backend.workers or 1), threads_per_worker=1,
                           processes=True, host="127.0.0.1", dashboard_address=":0",
                           silence_logs=logging.ERROR, env={"OMP_NUM_THREADS": "1"})
    return Client(cluster), cluster


def _on_dask(client: Any, tasks: Sequence[SampleTask], tick: Tick | None,
             shared: Any = None) -> list[SampleRecord]:
    from distributed import as_completed

    args: list[Any] = [list(tasks)]
    if shared is not None:
        args.append([shared] * len(tasks))
    futures = client.map(run_sample, *args, pure=False, retries=RETRIES)
    where = {f.key: k for k, f in enumerate(futures)}
    out: list[SampleRecord | None] = [None] * len(tasks)
    done = 0
    for future in as_completed(futures):
        k = where[future.key]
        try:
            out[k] = future.result()
        except Exception as err:  # the task itself never raises: a lost worker did
            text = " ".join(str(err).split())
            out[k] = SampleRecord(index=tasks[k].index, error=f"{type(err).__name__}: {text}")
        done += 1
        if tick is not None:
            tick(done, len(tasks))
    return [r for r in out if r is not None]


class Session:
    """A backend in use (a context manager): the Dask client, if any, is opened once for the
    shared reductions and the samples, and closed (with its LocalCluster) at the end.

    Attributes:
        backend: where the tasks run.
        client: the ``distributed.Client`` (``None`` in-process).
    """

    def __init__(self, backend: Backend):
        self.backend = backend
        self.client: Any = None
        self.cluster: Any = None

    def __enter__(self) -> "Session":
        if self.backend.workers is not None or self.backend.scheduler is not None:
            self.client, self.cluster = _client(self.backend)
        return self

    def __exit__(self, *exc: Any) -> None:
        if self.client is not None:
            self.client.close()
        if self.cluster is not None:
            self.cluster.close()

    def map(self, function: Callable[..., Any], *args: Sequence[Any],
            tick: Tick | None = None) -> list[Any]:
        """``[function(*a) for a in zip(*args)]``, each call a task on Dask (in parallel,
        results in order); an exception of a call is raised here."""
        calls = list(zip(*args))
        if self.client is None:
            out = []
            for k, a in enumerate(calls):
                out.append(function(*a))
                if tick is not None:
                    tick(k + 1, len(calls))
            return out
        from distributed import as_completed

        futures = self.client.map(function, *[list(a) for a in args], pure=False,
                                  retries=RETRIES)
        for k, _ in enumerate(as_completed(futures)):
            if tick is not None:
                tick(k + 1, len(calls))
        return list(self.client.gather(futures))

    def parts(self, jobs: Sequence[PartJob], tick: Tick | None = None
              ) -> dict[str, Substructure]:
        """The shared reduced parts, each made once (one task each on Dask)."""
        made = self.map(make_part, jobs, tick=tick)
        return {job.name: sub for job, sub in zip(jobs, made)}

    def samples(self, tasks: Sequence[SampleTask], tick: Tick | None = None,
                shared: Mapping[str, Substructure] | None = None) -> list[SampleRecord]:
        """Every sample (with the ``shared`` parts: scattered to every worker once, on Dask);
        the records in the order of ``tasks``."""
        if self.client is None:
            return _serial(tasks, tick, shared)
        future = None
        if shared:
            future = self.client.scatter([dict(shared)], broadcast=True, hash=False)[0]
        return _on_dask(self.client, tasks, tick, future)


def execute(tasks: Sequence[SampleTask], backend: Backend,
            tick: Tick | None = None) -> list[SampleRecord]:
    """Run every task on ``backend``; the records in the order of ``tasks``.

    Raises:
        BackendError: Dask missing, or the scheduler not reachable.
    """
    with Session(backend) as session:
        return session.samples(tasks, tick)
