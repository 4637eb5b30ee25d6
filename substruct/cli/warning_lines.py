"""Python warnings on the command line: one ``substruct: warning: ...`` line each, the
floating-point notices of NumPy left out.

Python's default shows a warning as two lines (where, then the source line), which breaks the
rule of one line per message on stderr; a backend's fall-back (a factorization that failed and
was replaced, :class:`~substruct.linalg.backends.FactorizationFallback`) says something the
user may act on, so it keeps its one line.  NumPy's ``invalid value / divide by zero /
overflow / underflow encountered`` notices come from intermediate arrays that the program
checks itself (results that are not finite are refused), and are not shown.
"""

from __future__ import annotations

import sys
import warnings
from typing import Any, TextIO

__all__ = ["install_warning_lines"]

_FLOATING_POINT = r".*(invalid value|divide by zero|overflow|underflow) encountered"


def _show(message: Warning | str, category: type[Warning], filename: str, lineno: int,
          file: TextIO | None = None, line: str | None = None) -> None:
    from substruct.case.text import printable

    text = printable(" ".join(str(message).split()))
    (file or sys.stderr).write(f"substruct: warning: {text}\n")


def install_warning_lines() -> Any:
    """Show warnings as one line each from now on, NumPy's floating-point notices ignored;
    returns the previous ``warnings.showwarning``."""
    previous = warnings.showwarning
    warnings.showwarning = _show
    warnings.filterwarnings("ignore", message=_FLOATING_POINT, category=RuntimeWarning)
    return previous
