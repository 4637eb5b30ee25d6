"""What the command does when it is stopped from outside: SIGTERM unwinds like Ctrl-C (so that
partly written files are removed on the way out), and a closed pipe on stdout ends quietly.

SIGTERM has one answer for the whole life of the ``substruct`` process, also once the command
is done (its set committed, its table printed) and the interpreter shuts down: the line
``substruct: terminated`` and exit code 143 (:func:`terminate_until_exit`).  Before, a SIGTERM
in that window killed the process by the default action: exit status 143 to the shell, without
the line."""

from __future__ import annotations

import atexit
import os
import signal
import sys
import threading
from types import FrameType
from typing import Callable

__all__ = ["Terminated", "terminate_on_sigterm", "terminate_until_exit", "silence_stdout",
           "exit_without_teardown", "TERMINATED_LINE"]

#: What a terminated command writes on stderr (its exit code is 143).
TERMINATED_LINE = "substruct: terminated\n"
_armed = False
_exit_code: int | None = None


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


def _exit_terminated() -> None:
    """Write :data:`TERMINATED_LINE`, flush what the command printed, end with 143 at once."""
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except Exception:  # noqa: BLE001 - a closed pipe: nothing more to say there
            pass
    try:
        os.write(2, TERMINATED_LINE.encode())
    except OSError:
        pass
    os._exit(143)


def terminate_until_exit() -> None:
    """From now until the process ends, SIGTERM writes ``substruct: terminated`` and exits with
    143 (the command has returned; nothing is left to clean up).

    Python runs signal handlers only between bytecodes, and stops running them partway
    through its shutdown; so the last exit handler blocks SIGTERM and answers a pending one
    itself.  A SIGTERM after that moment (the interpreter freeing its modules) is held and
    dropped with the process: the command ends with its own exit code.  Only the main thread
    of the process that runs the command calls this (``substruct`` itself, not a program that
    calls :func:`substruct.cli.main` with arguments)."""
    global _armed
    if threading.current_thread() is not threading.main_thread():
        return
    signal.signal(signal.SIGTERM, lambda signum, frame: _exit_terminated())
    _armed = True


def exit_without_teardown(code: int) -> None:
    """End the process with ``code`` once its exit handlers have run, without the
    interpreter's teardown (freeing every module and object of NumPy, SciPy, h5py and the
    case layer: about 0.08 s of CPU, a tenth of a small run).  The command's files are closed
    and committed by then; the streams are flushed here.  Only for the ``substruct`` process
    itself, from its main thread, and only when no other thread runs (a study's workers end
    through the usual shutdown)."""
    global _exit_code
    if threading.current_thread() is threading.main_thread() and \
            threading.active_count() == 1:
        _exit_code = int(code)


def _at_exit() -> None:
    if _armed and hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGTERM})
        if signal.SIGTERM in signal.sigpending():
            _exit_terminated()
    if _exit_code is not None and threading.active_count() == 1:
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except Exception:  # noqa: BLE001 - a closed pipe: nothing more to say there
                pass
        os._exit(_exit_code)


atexit.register(_at_exit)  # registered at import, before the libraries: it runs last
