"""The entry point of the ``substruct`` command and the one place where a failure becomes an
exit code and a message.

=====  ======================================================================================
code   meaning
=====  ======================================================================================
0      success
2      bad input: a case file, an argument, an output path (:class:`~substruct.case.errors.
       CaseError`, :class:`~substruct.cli.errors.InputError`), an output directory another
       process writes (:class:`~substruct.io.file_set.BusyError`), or a file the file system
       would not take (full disk, read-only folder: :class:`~substruct.io.paths.WriteError`);
       one line ``substruct: error: <message>``, no traceback, nothing written
1      the result failed its cross-checks (:class:`~substruct.analysis.errors.CheckError`):
       one line ``substruct: error: <message>``, nothing written
1      an internal error (any other exception): its traceback, then one closing line
       ``substruct: internal error: <type>: <message> (...)``
130    interrupted (Ctrl-C, at any point of the command: while its modules load too, see
       :mod:`substruct.cli`); one line ``substruct: interrupted``; partly written files removed
143    terminated (SIGTERM); partly written files removed; the line
       ``substruct: terminated`` also when SIGTERM comes after the command's files were
       committed (:func:`~substruct.cli.signals.terminate_until_exit`)
=====  ======================================================================================
"""

from __future__ import annotations

import argparse
import importlib
import signal
import sys
import threading
import traceback
from typing import Any, Callable, Sequence

from substruct.cli.arguments import COMMANDS, build_parser
from substruct.cli.errors import InputError
from substruct.cli.warning_lines import install_warning_lines
from substruct.cli.signals import (TERMINATED_LINE, Terminated, exit_without_teardown,
                                   silence_stdout, terminate_on_sigterm, terminate_until_exit)

__all__ = ["main", "BAD_INPUT", "FAILED"]

#: What Ctrl-C prints (exit code 130).
INTERRUPTED_LINE = "substruct: interrupted\n"
#: Exit code of bad input.
BAD_INPUT = 2
#: Exit code of a failed cross-check or an internal error.
FAILED = 1

#: Each command's module and function, imported only when that command runs (``info`` loads
#: no case layer, ``run`` no comparison or study code).
_RUN: dict[str, tuple[str, str]] = {
    "run": ("run_command", "run_command"), "converge": ("converge_command", "converge_command"),
    "info": ("result_commands", "info_command"), "export": ("uff_export", "export_dispatch"),
    "compare": ("compare_command", "compare_command"),
    "study": ("study_command", "study_command")}


def _command(name: str) -> Callable[[argparse.Namespace], int]:
    """The function of command ``name``, its module imported now (the collector paused:
    :func:`~substruct.cli.files.collector_paused`)."""
    from substruct.cli.files import collector_paused

    module, function = _RUN[name]
    with collector_paused():
        return getattr(importlib.import_module(f"substruct.cli.{module}"), function)


def _one_line(text: object) -> str:
    from substruct.case.text import printable

    return printable(" ".join(str(text).split()))


def _error(message: object, code: int) -> int:
    sys.stderr.write(f"substruct: error: {_one_line(message)}\n")
    return code


def _internal(err: BaseException) -> int:
    traceback.print_exc()
    text = _one_line(err)
    what = f"{type(err).__name__}: {text}" if text else type(err).__name__
    sys.stderr.write(f"substruct: internal error: {what} (a bug in substruct, not in the "
                     f"input; the traceback above says where)\n")
    return FAILED


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``substruct`` command line; return the exit code (see the module docstring).

    Args:
        argv: the arguments; ``None`` (the ``substruct`` program) reads ``sys.argv``, keeps
            SIGTERM's answer (``substruct: terminated``, 143) until the process ends, and ends
            it with the returned code once the exit handlers have run, without the
            interpreter's teardown (:func:`~substruct.cli.signals.exit_without_teardown`).
    """
    restore = terminate_on_sigterm()
    block = hasattr(signal, "pthread_sigmask") and \
        threading.current_thread() is threading.main_thread()
    held: Any = None
    try:
        try:
            code = _main(argv)
        finally:  # a C call first: no Python handler runs between it and the end of _main
            if block:
                held = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGTERM})
    except Terminated:  # arrived while another outcome was being reported
        sys.stderr.write(TERMINATED_LINE)
        code = 143
    except KeyboardInterrupt:  # before the command's own handling: parsing, late imports
        sys.stderr.write(INTERRUPTED_LINE)
        code = 130
    try:  # SIGTERM waits while the handler changes, then meets the new one
        try:
            restore()
        except Terminated:  # delivered just before it was held
            sys.stderr.write(TERMINATED_LINE)
            code = 143
        if argv is None:
            terminate_until_exit()
            exit_without_teardown(code)
    finally:
        if held is not None:
            signal.pthread_sigmask(signal.SIG_SETMASK, held)
    return code


def _main(argv: Sequence[str] | None) -> int:
    install_warning_lines()
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except InputError as err:
        return _error(err, BAD_INPUT)
    except SystemExit as exc:  # --help, --version
        return int(exc.code or 0)
    if args.command not in _RUN:
        return _error(f"choose a command: {', '.join(COMMANDS[:-1])} or {COMMANDS[-1]} "
                      "(see substruct --help)", BAD_INPUT)
    try:
        return int(_command(args.command)(args))
    except KeyboardInterrupt:
        sys.stderr.write(INTERRUPTED_LINE)
        return 130
    except Terminated:  # temporary files were removed on the way out
        sys.stderr.write(TERMINATED_LINE)
        return 143
    except BrokenPipeError:  # the reader went away (substruct info ... | head)
        silence_stdout()
        return 0
    except Exception as err:
        if isinstance(err, (InputError, *_loaded(_BAD_INPUT))):
            return _error(err, BAD_INPUT)
        if isinstance(err, _loaded(_FAILED_CHECK)):  # computed, but not to be trusted
            return _error(err, FAILED)
        return _internal(err)  # an internal error: show everything, then say so in one line


#: The exceptions that are bad input (besides InputError), and a failed cross-check, by module.
_BAD_INPUT = (("substruct.case.errors", "CaseError"), ("substruct.io.file_set", "BusyError"),
              ("substruct.io.paths", "WriteError"))
_FAILED_CHECK = (("substruct.analysis.errors", "CheckError"),)


def _loaded(classes: tuple[tuple[str, str], ...]) -> tuple[type, ...]:
    """The exception classes of ``classes`` whose modules are imported: an exception of a
    class whose module was never imported cannot have been raised, so a command need not
    import the case layer (pydantic) or the analysis layer only to be told apart from them."""
    found = []
    for module, name in classes:
        if module in sys.modules:
            found.append(getattr(sys.modules[module], name))
    return tuple(found)
