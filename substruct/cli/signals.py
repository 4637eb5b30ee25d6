"""What the command does when it is stopped from outside: SIGTERM unwinds like Ctrl-C (so that
partly written files are removed on the way out), and a closed pipe on stdout ends quietly."""

from __future__ import annotations

import os
import signal
import sys
import threading
from types import FrameType
from typing import Callable

__all__ = ["Terminated", "terminate_on_sigterm", "silence_stdout"]


class Terminated(BaseException):
    """SIGTERM arrived while a command ran; it unwinds like Ctrl-C, so that partly written
    files (``*.part``) are removed on the way out (exit code 143)."""


def terminate_on_sigterm() -> Callable[[], object]:
    """Turn SIGTERM into :class:`Terminated` until the returned undo function is called.

    Outside the main thread (where signal handlers cannot be set) nothing changes.
    """
    if threading.current_thread() is not threading.main_thread():
        return lambda: None

    def handler(signum: int, frame: FrameType | None) -> None:
        raise Terminated()
    previous = signal.signal(signal.SIGTERM, handler)
    return lambda: signal.signal(signal.SIGTERM, previous)


def silence_stdout() -> None:
    """Point stdout at /dev/null so that the interpreter's final flush does not fail (the
    reader of a pipe went away: ``substruct info RESULT.h5 | head``)."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):
        pass
