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
import signal
import sys
import threading
import traceback
from typing import Any, Callable, Sequence

from substruct.cli.arguments import COMMANDS, build_parser
from substruct.cli.compare_command import compare_command
from substruct.cli.converge_command import converge_command
from substruct.cli.errors import InputError
from substruct.cli.result_commands import info_command
from substruct.cli.run_command import run_command
from substruct.cli.signals import (TERMINATED_LINE, Terminated, silence_stdout,
                                   terminate_on_sigterm, terminate_until_exit)
from substruct.cli.study_command import study_command
from substruct.cli.uff_export import export_dispatch

__all__ = ["main", "BAD_INPUT", "FAILED"]

#: What Ctrl-C prints (exit code 130).
INTERRUPTED_LINE = "substruct: interrupted\n"
#: Exit code of bad input.
BAD_INPUT = 2
#: Exit code of a failed cross-check or an internal error.
FAILED = 1

_RUN: dict[str, Callable[[argparse.Namespace], int]] = {
    "run": run_command, "converge": converge_command, "info": info_command,
    "export": export_dispatch, "compare": compare_command, "study": study_command}


def _one_line(text: object) -> str:
    from substruct.case.errors import printable

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
        argv: the arguments; ``None`` (the ``substruct`` program) reads ``sys.argv`` and keeps
            SIGTERM's answer (``substruct: terminated``, 143) until the process ends.
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
    finally:
        if held is not None:
            signal.pthread_sigmask(signal.SIG_SETMASK, held)
    return code


def _main(argv: Sequence[str] | None) -> int:
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
    from substruct.analysis.errors import CheckError
    from substruct.case.errors import CaseError
    from substruct.io.file_set import BusyError
    from substruct.io.paths import WriteError

    try:
        return int(_RUN[args.command](args))
    except (InputError, CaseError, BusyError, WriteError) as err:
        return _error(err, BAD_INPUT)
    except CheckError as err:  # computed, but not to be trusted: nothing was written
        return _error(err, FAILED)
    except KeyboardInterrupt:
        sys.stderr.write(INTERRUPTED_LINE)
        return 130
    except Terminated:  # temporary files were removed on the way out
        sys.stderr.write(TERMINATED_LINE)
        return 143
    except BrokenPipeError:  # the reader went away (substruct info ... | head)
        silence_stdout()
        return 0
    except Exception as err:  # an internal error: show everything, then say so in one line
        return _internal(err)
