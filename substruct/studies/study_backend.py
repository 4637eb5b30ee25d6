"""Where the samples of a study run: in this process one after the other (the default), on a
``dask.distributed`` LocalCluster of worker processes started here, or on an existing cluster
reached through its scheduler's address.

Every backend runs the same :func:`substruct.studies.study_task.run_sample` on the same
:class:`~substruct.studies.study_task.SampleTask` objects and returns the records in the order
of the tasks, so the study's table does not depend on the backend.  On Dask each task is
submitted with ``retries``: a task whose worker dies is run again on another worker (the
scheduler does that by itself for a lost worker, up to ``distributed.scheduler.allowed-failures``
times); a task that still cannot finish becomes a failed sample with the message Dask gave.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any, Callable, Sequence

from substruct.studies.study_task import SampleRecord, SampleTask, run_sample

__all__ = ["Backend", "BackendError", "execute", "RETRIES"]

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


def _serial(tasks: Sequence[SampleTask], tick: Tick | None) -> list[SampleRecord]:
    out = []
    for k, task in enumerate(tasks):
        out.append(run_sample(task))
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


def _on_dask(tasks: Sequence[SampleTask], backend: Backend,
             tick: Tick | None) -> list[SampleRecord]:
    from distributed import as_completed

    client, cluster = _client(backend)
    try:
        futures = client.map(run_sample, list(tasks), pure=False, retries=RETRIES)
        where = {f.key: k for k, f in enumerate(futures)}
        out: list[SampleRecord | None] = [None] * len(tasks)
        done = 0
        for future in as_completed(futures):
            k = where[future.key]
            try:
                out[k] = future.result()
            except Exception as err:  # the task itself never raises: a lost worker did
                text = " ".join(str(err).split())
                out[k] = SampleRecord(index=tasks[k].index,
                                      error=f"{type(err).__name__}: {text}")
            done += 1
            if tick is not None:
                tick(done, len(tasks))
        return [r for r in out if r is not None]
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def execute(tasks: Sequence[SampleTask], backend: Backend,
            tick: Tick | None = None) -> list[SampleRecord]:
    """Run every task on ``backend``; the records in the order of ``tasks``.

    Raises:
        BackendError: Dask missing, or the scheduler not reachable.
    """
    if backend.workers is None and backend.scheduler is None:
        return _serial(tasks, tick)
    return _on_dask(tasks, backend, tick)
