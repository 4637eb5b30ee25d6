"""Set-up of each worker process of the LocalCluster a study starts (``--workers N``), loaded
by Dask as the workers' preload: a worker writes nothing on the terminal.

The worker's standard output and error (tracebacks of a task or of its own shutdown, Dask's
log lines) go to ``worker-<pid>.log`` in the study's scratch directory, which is removed with
the cluster, and Ctrl-C is ignored by the workers: the terminal sends it to every process of
the foreground group, and the study itself closes its workers on the way out.
"""

from __future__ import annotations

import os
import signal
from typing import Any

__all__ = ["dask_setup"]


def dask_setup(worker: Any) -> None:
    """Dask's preload hook, in the worker process: stdout and stderr into a log file of the
    worker's ``local_directory``; SIGINT ignored."""
    try:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    except ValueError:  # not the main thread of the worker process: leave it
        pass
    log = os.path.join(str(worker.local_directory), f"worker-{os.getpid()}.log")
    fd = os.open(log, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o600)
    try:
        os.dup2(fd, 1)
        os.dup2(fd, 2)
    finally:
        os.close(fd)
