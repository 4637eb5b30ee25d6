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

import contextlib
import logging
import shutil
import signal
import tempfile
from dataclasses import dataclass
from typing import Any, Callable, Iterator, Mapping, Sequence

from substruct.builder import Substructure
from substruct.case.errors import printable
from substruct.studies.scheduler_probe import (
    BackendError,
    connect_timeout,
    probe,
    scheduler_address,
)
from substruct.studies.study_task import (
    PartJob,
    SampleRecord,
    SampleTask,
    make_part,
    run_sample,
)

__all__ = ["Backend", "BackendError", "Session", "execute", "RETRIES", "CONNECT_TIMEOUT",
           "SCRATCH_PREFIX", "QUIET_LOGGERS"]

#: How many times Dask runs a task again after it failed (a killed worker included).
RETRIES = 3
#: Default seconds to reach a scheduler and receive its handshake (``--connect-timeout``).
CONNECT_TIMEOUT = 5.0
#: The study's Dask scratch directory: ``<system temp dir>/substruct-dask-XXXXXXXX``.
SCRATCH_PREFIX = "substruct-dask-"
#: Loggers that are silent while a Dask backend is in use (their lines would reach the
#: terminal from this process: the LocalCluster's scheduler and nannies, the client).
QUIET_LOGGERS = ("distributed", "tornado", "asyncio", "bokeh")

#: ``progress(done, total)`` after each finished sample.
Tick = Callable[[int, int], None]


@dataclass(frozen=True)
class Backend:
    """``workers``: start a LocalCluster of that many processes (one thread each);
    ``scheduler``: ``tcp://host:port`` of an existing cluster, reached within
    ``connect_timeout`` seconds; neither: in-process, serial."""

    workers: int | None = None
    scheduler: str | None = None
    connect_timeout: float = CONNECT_TIMEOUT

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


@contextlib.contextmanager
def quiet_dask_logs() -> Iterator[None]:
    """The loggers of :data:`QUIET_LOGGERS` silent (above CRITICAL) inside the block, their
    levels restored after it."""
    loggers = [logging.getLogger(name) for name in QUIET_LOGGERS]
    levels = [lg.level for lg in loggers]
    for lg in loggers:
        lg.setLevel(logging.CRITICAL + 1)
    try:
        yield
    finally:
        for lg, level in zip(loggers, levels):
            lg.setLevel(level)


def _one_line(err: BaseException) -> str:
    text = printable(" ".join(str(err).split()))
    text = text if len(text) <= 200 else text[:197] + "..."
    return f"{type(err).__name__}: {text}" if text else type(err).__name__


def _connect(backend: Backend) -> Any:
    """A ``distributed.Client`` of the scheduler of ``backend``: the address and protocol
    checked, then probed for a Dask handshake (:mod:`substruct.studies.scheduler_probe`),
    then connected within the timeout; every failure one :class:`BackendError`."""
    assert backend.scheduler is not None
    address = scheduler_address(backend.scheduler)
    timeout = connect_timeout(backend.connect_timeout)
    probe(address, timeout)
    try:
        from distributed import Client
    except ImportError:
        raise BackendError("--scheduler needs dask.distributed: "
                           "pip install 'substruct[dask]'") from None
    client = Client.__new__(Client)  # held here, so that a failed start is closed here
    try:
        Client.__init__(client, str(address), timeout=timeout)
        return client
    except Exception as err:  # anything Dask raises while connecting: the peer's doing
        message = (f"--scheduler {address}: not a Dask scheduler (the connection failed: "
                   f"{_one_line(err)})")
    with contextlib.suppress(Exception):
        client.close(timeout=timeout)
    raise BackendError(message)


def _local_cluster(workers: int, scratch: str, stack: contextlib.ExitStack) -> Any:
    """A LocalCluster of ``workers`` processes (one thread each) on 127.0.0.1 (its dashboard
    on a free port), its scratch space in ``scratch`` and each worker's output in a log file
    there (:mod:`substruct.studies.dask_worker`); its closing pushed on ``stack``.

    SIGINT is blocked in this thread while the cluster starts: the cluster's event-loop
    thread, created meanwhile, inherits the mask, and so does every worker process it spawns
    (now or when a worker is restarted), so a Ctrl-C of the terminal, sent to the whole
    process group, reaches this process only.  A Ctrl-C during the start is delivered here
    once the cluster exists and is on ``stack``.
    """
    try:
        import dask
        from distributed import LocalCluster
    except ImportError:
        raise BackendError("--workers needs dask.distributed: "
                           "pip install 'substruct[dask]'") from None
    from multiprocessing import resource_tracker

    # started here first: starting it unblocks SIGINT in the thread that does
    resource_tracker.ensure_running()
    mask = getattr(signal, "pthread_sigmask", None)
    old = mask(signal.SIG_BLOCK, {signal.SIGINT}) if mask is not None else None
    try:
        cluster = LocalCluster.__new__(LocalCluster)  # held here, closed if its start fails
        stack.callback(_close_quietly, cluster)
        # Dask starts its workers with a 64 kB malloc trim threshold (so that freed memory
        # shows as returned); that fixes glibc's mmap threshold too, so every temporary array
        # above 128 kB is a fresh mapping whose pages fault in on first touch: the 74 AMLS
        # subdomain tasks of a 98,400-coordinate box took 7.5 s on two workers with it, 5.5 s
        # without (4.2 s in one process).  The workers keep glibc's defaults, as the command.
        environ = {key: value for key, value in
                   dask.config.get("distributed.nanny.pre-spawn-environ", {}).items()
                   if key != "MALLOC_TRIM_THRESHOLD_"}
        with dask.config.set({"temporary-directory": scratch,
                              "distributed.nanny.pre-spawn-environ": environ}):
            LocalCluster.__init__(cluster, n_workers=int(workers), threads_per_worker=1,
                                  processes=True, host="127.0.0.1",
                                  dashboard_address="127.0.0.1:0",
                                  silence_logs=logging.CRITICAL, local_directory=scratch,
                                  preload=["substruct.studies.dask_worker"],
                                  env={"OMP_NUM_THREADS": "1"})
    finally:
        if mask is not None and old is not None:
            mask(signal.SIG_SETMASK, old)
    return cluster


def _close_quietly(cluster: Any) -> None:
    """Close ``cluster``, also one whose start was interrupted (then Dask's own clean-up at
    exit would fail on it: it is taken off Dask's list of clusters to close)."""
    try:
        cluster.close()
    except Exception:  # a cluster that never finished starting
        instances = getattr(type(cluster), "_instances", None)
        if instances is not None:
            instances.discard(cluster)


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
            out[k] = SampleRecord(index=tasks[k].index, error=_one_line(err))
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
        self.scratch: str | None = None
        self._stack = contextlib.ExitStack()

    def __enter__(self) -> "Session":
        if self.backend.workers is None and self.backend.scheduler is None:
            return self
        stack = self._stack
        try:
            stack.enter_context(quiet_dask_logs())
            if self.backend.scheduler is not None:
                self.client = _connect(self.backend)
            else:
                self.scratch = tempfile.mkdtemp(prefix=SCRATCH_PREFIX)
                stack.callback(shutil.rmtree, self.scratch, ignore_errors=True)
                self.cluster = _local_cluster(int(self.backend.workers or 1), self.scratch,
                                              stack)
                from distributed import Client

                self.client = Client(self.cluster)
            stack.callback(self.client.close)
        except BaseException:
            stack.close()
            raise
        return self

    def __exit__(self, *exc: Any) -> None:
        self._stack.close()

    @contextlib.contextmanager
    def contained(self) -> Iterator[None]:
        """Inside the block, a failure of the cluster itself (the connection to the scheduler
        lost, futures cancelled, a task whose workers kept dying, a timeout) is one
        :class:`BackendError`; an exception raised by a task's own function passes."""
        from concurrent.futures import CancelledError

        from distributed import KilledWorker

        try:
            yield
        except (OSError, TimeoutError, CancelledError, KilledWorker) as err:
            raise BackendError(f"the Dask cluster ({self.backend.describe()}) failed during "
                               f"the study ({_one_line(err)})") from None

    def scatter(self, value: Any) -> Any:
        """``value`` sent once to every worker (a future to hand to tasks); ``value`` itself
        in-process."""
        if self.client is None:
            return value
        with self.contained():
            return self.client.scatter([value], broadcast=True, hash=False)[0]

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

        with self.contained():
            futures = self.client.map(function, *[list(a) for a in args], pure=False,
                                      retries=RETRIES)
            for k, _ in enumerate(as_completed(futures)):
                if tick is not None:
                    tick(k + 1, len(calls))
            return list(self.client.gather(futures))

    def submit(self, function: Callable[..., Any], /, *args: Any) -> Any:
        """A task ``function(*args)`` (:class:`substruct.linalg.task_runner.TaskRunner`): a
        Dask future, whose value stays on its worker until a later task or
        :meth:`completed` needs it; in-process the value itself, computed now."""
        if self.client is None:
            return function(*args)
        with self.contained():
            return self.client.submit(function, *args, pure=False, retries=RETRIES)

    def done(self, handle: Any, /) -> bool:
        """Whether the task of ``handle`` (from :meth:`submit`) has finished."""
        return self.client is None or bool(handle.done())

    def completed(self, handles: Sequence[Any], /) -> Iterator[tuple[int, Any]]:
        """``(position, value)`` of every handle, as each task finishes; an exception of a
        task is raised here."""
        if self.client is None:
            yield from enumerate(handles)
            return
        from distributed import as_completed

        where = {f.key: k for k, f in enumerate(handles)}
        with self.contained():
            for future, value in as_completed(handles, with_results=True):
                yield where[future.key], value

    def task_memory(self) -> int | None:
        """The least memory limit of the cluster's workers in bytes (a LocalCluster's: the
        machine's memory over the number of workers); ``None`` in-process, or when a worker
        has no limit."""
        if self.client is None:
            return None
        with self.contained():
            workers = list(self.client.scheduler_info().get("workers", {}).values())
        limits = [int(w.get("memory_limit") or 0) for w in workers]
        return min(limits) if limits and all(limits) else None

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
        future = self.scatter(dict(shared)) if shared else None
        with self.contained():
            return _on_dask(self.client, tasks, tick, future)


def execute(tasks: Sequence[SampleTask], backend: Backend,
            tick: Tick | None = None) -> list[SampleRecord]:
    """Run every task on ``backend``; the records in the order of ``tasks``.

    Raises:
        BackendError: Dask missing, the scheduler refused or not reachable, the cluster
            failed.
    """
    with Session(backend) as session:
        return session.samples(tasks, tick)
