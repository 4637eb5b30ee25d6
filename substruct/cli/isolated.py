"""Long computations in a child process, so that SIGTERM and Ctrl-C act at once.

A signal handler of Python runs only between bytecodes of the main thread: during one long
LAPACK call (a dense eigenproblem of a few thousand coordinates takes tens of seconds, and
SciPy's wrappers keep the interpreter lock) nothing reacts.  :func:`call_isolated` therefore
runs the computation in a forked child and waits for its answer in the parent, where a signal
interrupts the wait at once: the parent kills the child (SIGKILL; the child writes no file),
and unwinds as usual (temporary files removed, exit code 130 or 143).

The child writes where the parent would: to the same file descriptors, or, when the parent's
``sys.stdout``/``sys.stderr`` are in-memory streams (tests), through pipes the parent copies
into them.  Its answer (the return value, or the exception with its traceback) comes back
pickled; the large arrays of a value (a receptance of 1,000 x 400 x 400 is 2.6 GB) as
out-of-band buffers (pickle protocol 5) written to an unnamed temporary file that the parent
maps into memory, so they are neither copied through the pipe nor unpickled.  (``substruct
run`` sends back no arrays at all: its child writes the result file itself and returns the
names of the files and the report, :func:`substruct.cli.run_command.stage_set`.)
Without ``os.fork`` (not POSIX) the function runs in-process, and so it does in a process
that has loaded CHOLMOD (scikit-sparse): a forked child of a process whose CHOLMOD has
run hangs in its next factorization (its thread pool does not survive the fork).  The command
line never loads it before forking; a program (or a test session) that has used CHOLMOD and
then calls the command in-process loses only the prompt reaction to signals.
"""

from __future__ import annotations

import io
import mmap
import os
import pickle
import select
import signal
import sys
import tempfile
import traceback
from typing import Any, Callable, TypeVar

from substruct.cli.errors import InputError
from substruct.cli.signals import Terminated

__all__ = ["call_isolated"]

T = TypeVar("T")
_STREAMS = ("stdout", "stderr")


def _has_fd(stream: Any) -> bool:
    try:
        stream.fileno()
    except (AttributeError, OSError, ValueError):
        return False
    return True


def _die_with_parent(parent: int) -> None:
    """Ask Linux to kill this child when the parent dies (a SIGKILLed parent)."""
    if sys.platform.startswith("linux"):
        try:
            import ctypes

            ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
        except (OSError, AttributeError):
            pass
    if os.getppid() != parent:
        os._exit(1)


def _spill(value: Any, fd: int) -> bytes:
    """``value`` pickled with its out-of-band buffers written one after the other into the file
    ``fd`` (:func:`_unspill` reads them back)."""
    buffers: list[pickle.PickleBuffer] = []
    data = pickle.dumps(value, protocol=5, buffer_callback=buffers.append)
    layout, offset = [], 0
    for buf in buffers:
        raw = buf.raw()
        done = 0
        while done < raw.nbytes:
            done += os.pwrite(fd, raw[done:], offset + done)
        layout.append((offset, raw.nbytes))
        offset += -(-raw.nbytes // 64) * 64  # aligned as NumPy aligns its data
    return pickle.dumps(("ok", data, layout), protocol=pickle.HIGHEST_PROTOCOL)


def _unspill(data: bytes, layout: list[tuple[int, int]], fd: int) -> Any:
    """The value :func:`_spill` wrote: its buffers are views of a private (copy-on-write)
    mapping of the file ``fd``."""
    size = max((o + n for o, n in layout if n), default=0)
    view = memoryview(mmap.mmap(fd, size, access=mmap.ACCESS_COPY)) if size else None
    return pickle.loads(data, buffers=[view[o:o + n] if n and view is not None else
                                       bytearray() for o, n in layout])


def _answer(fn: Callable[[], Any], spill: int) -> bytes:
    from substruct.analysis.errors import CheckError
    from substruct.case.errors import CaseError

    try:
        return _spill(fn(), spill)
    except BaseException as err:  # noqa: BLE001 - every failure goes back to the parent
        kind = ("input" if isinstance(err, (CaseError, InputError)) else
                "check" if isinstance(err, CheckError) else "error")
        text = traceback.format_exc()
        if kind != "error":  # bad input or a failed check: its one-line message is enough
            return pickle.dumps(("error", kind, str(err), ""))
        try:
            data = pickle.dumps(("error", kind, err, text), protocol=pickle.HIGHEST_PROTOCOL)
            pickle.loads(data)
            return data
        except Exception:  # noqa: BLE001 - an exception that does not pickle
            plain = RuntimeError(f"{type(err).__name__}: {err}")
            return pickle.dumps(("error", kind, plain, text))


class _Relay(io.TextIOWrapper):
    """The child's end of a relayed stream; a terminal if the parent's stream is one (a
    progress bar draws the same in the child as it would in the parent)."""

    terminal = False

    def isatty(self) -> bool:
        return self.terminal


def _relay(fd: int, terminal: bool) -> _Relay:
    stream = _Relay(open(fd, "wb", buffering=0), encoding="utf-8", errors="backslashreplace",
                    line_buffering=True, write_through=True)
    stream.terminal = terminal
    return stream


def _child(fn: Callable[[], Any], parent: int, answer: int, relays: dict, spill: int) -> None:
    code = 0
    try:
        signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent decides what Ctrl-C does
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        _die_with_parent(parent)
        for name, (r, w, terminal) in relays.items():
            os.close(r)
            setattr(sys, name, _relay(w, terminal))
        data = _answer(fn, spill)
        view = memoryview(data)
        while view:
            view = view[os.write(answer, view):]
    except BaseException:  # noqa: BLE001 - never return into the parent's code
        code = 1
    finally:
        for name in _STREAMS:
            try:
                getattr(sys, name).flush()
            except Exception:  # noqa: BLE001
                pass
        os._exit(code)


def _collect(pid: int, answer: int, relays: dict) -> bytes:
    """Read the child's answer and relay its output until it closes everything."""
    chunks: list[bytes] = []
    streams = {r: getattr(sys, name) for name, (r, _, _) in relays.items()}
    open_fds = [answer, *streams]
    while open_fds:
        ready, _, _ = select.select(open_fds, [], [])
        for fd in ready:
            data = os.read(fd, 1 << 20)
            if not data:
                open_fds.remove(fd)
            elif fd == answer:
                chunks.append(data)
            else:
                streams[fd].write(data.decode("utf-8", errors="replace"))
                streams[fd].flush()
    return b"".join(chunks)


def _failure(status: int) -> BaseException:
    if os.WIFSIGNALED(status):
        sig = os.WTERMSIG(status)
        if sig == signal.SIGTERM:
            return Terminated()
        if sig == signal.SIGINT:
            return KeyboardInterrupt()
        name = signal.Signals(sig).name if sig in signal.Signals._value2member_map_ else sig
        return RuntimeError(f"the computation was killed by signal {name} (out of memory?)")
    return RuntimeError(f"the computation ended with exit status {os.WEXITSTATUS(status)} "
                        "without an answer")


def call_isolated(fn: Callable[[], T]) -> T:
    """``fn()`` computed in a child process; its value, or its exception raised here.

    Bad input (:class:`~substruct.case.errors.CaseError`, :class:`InputError`) comes back as
    :class:`InputError`, a failed cross-check as
    :class:`~substruct.analysis.errors.CheckError` with the same message; any other exception
    as itself with the child's traceback as a note.  SIGTERM or Ctrl-C in the parent kill the
    child at once (it is gone when this returns or raises), so ``fn`` may write only where the
    caller removes what is left on an error (a staging folder).
    """
    if not hasattr(os, "fork") or "sksparse.cholmod" in sys.modules:
        return fn()
    relays = {}
    for name in _STREAMS:
        stream = getattr(sys, name)
        stream.flush()
        if not _has_fd(stream):
            relays[name] = (*os.pipe(), bool(getattr(stream, "isatty", lambda: False)()))
    answer_r, answer_w = os.pipe()
    with tempfile.TemporaryFile(prefix="substruct-") as spill:
        parent = os.getpid()
        pid = os.fork()
        if pid == 0:
            os.close(answer_r)
            _child(fn, parent, answer_w, relays, spill.fileno())
        reply = _wait(pid, answer_r, answer_w, relays)
        if reply[0] == "ok":
            return _unspill(reply[1], reply[2], spill.fileno())
    from substruct.analysis.errors import CheckError

    _, kind, err, text = reply
    if kind == "input":
        raise InputError(str(err))
    if kind == "check":
        raise CheckError(str(err))
    if isinstance(err, BaseException):
        err.add_note("in the computation:\n" + text.rstrip())
        raise err
    raise RuntimeError(str(err))


def _wait(pid: int, answer_r: int, answer_w: int, relays: dict) -> Any:
    """The child's reply, unpickled (its output relayed meanwhile); the child is gone when
    this returns or raises."""
    os.close(answer_w)
    for _, w, _ in relays.values():
        os.close(w)
    waited = False
    try:
        data = _collect(pid, answer_r, relays)
        _, status = os.waitpid(pid, 0)
        waited = True
    finally:
        if not waited:  # interrupted: the child goes at once
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
        os.close(answer_r)
        for r, _, _ in relays.values():
            os.close(r)
    if not data:
        raise _failure(status)
    return pickle.loads(data)
