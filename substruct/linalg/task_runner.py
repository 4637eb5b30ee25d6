"""Where independent tasks run: this process, or a cluster (a Dask session,
:class:`substruct.studies.study_backend.Session`, has the same methods).

A task is a pure function of picklable data, so its result does not depend on where it ran.
:meth:`TaskRunner.submit` returns a *handle* that later tasks take as an argument in place of
the value: on a cluster the value then goes from the worker that made it to the worker that
needs it (or stays there), never through the caller; in this process the handle is the value,
computed at once.
"""

from __future__ import annotations

from typing import Any, Callable, Iterator, Protocol, Sequence

__all__ = ["TaskMap", "TaskRunner", "InProcess", "IN_PROCESS"]

#: ``map(function, jobs) -> [function(job) for job in jobs]``, in the order of ``jobs``.
TaskMap = Callable[[Callable[[Any], Any], Sequence[Any]], Sequence[Any]]


class TaskRunner(Protocol):
    """Runs tasks: a map of independent ones, or a graph of them through handles."""

    def map(self, function: Callable[[Any], Any], jobs: Sequence[Any], /) -> Sequence[Any]:
        """``[function(job) for job in jobs]``, in the order of ``jobs``."""
        ...

    def submit(self, function: Callable[..., Any], /, *args: Any) -> Any:
        """The handle of ``function(*args)``; an argument may be the handle of an earlier
        task (at the top level of ``args``), which stands for its value."""
        ...

    def done(self, handle: Any, /) -> bool:
        """Whether the task of ``handle`` has finished (without waiting)."""
        ...

    def completed(self, handles: Sequence[Any], /) -> Iterator[tuple[int, Any]]:
        """``(position, value)`` of every handle, as each task finishes (waiting for them);
        the values are brought here and the handles no longer keep them elsewhere."""
        ...

    def task_memory(self) -> int | None:
        """The bytes one task may hold where it runs (the least memory limit of a cluster's
        workers), or ``None``: no limit known (this process; workers without a limit)."""
        ...


class InProcess:
    """Every task in this process, at once: a handle is its value."""

    def map(self, function: Callable[[Any], Any], jobs: Sequence[Any], /) -> list[Any]:
        return [function(job) for job in jobs]

    def submit(self, function: Callable[..., Any], /, *args: Any) -> Any:
        return function(*args)

    def done(self, handle: Any, /) -> bool:
        return True

    def completed(self, handles: Sequence[Any], /) -> Iterator[tuple[int, Any]]:
        yield from enumerate(handles)

    def task_memory(self) -> int | None:
        return None


#: The runner used when none is given.
IN_PROCESS = InProcess()
