"""The two kinds of failure of an analysis that are not bugs.

* :class:`AnalysisInputError`: the numbers cannot be analysed as given (a singular system at a
  frequency asked for, more modes than free coordinates, a mass matrix singular where there is
  mass, an inconsistent constraint).  Bad input: the run layer names the case field that asked
  for the analysis (:class:`~substruct.case.errors.CaseError`, exit 2).
* :class:`CheckError`: independent formulations of one result disagree beyond the stated
  tolerance (exit 1).

Anything else an analysis raises (a plain ``ValueError`` included: an unknown method name is
something the case schema refuses first) is an internal error, never passed off as bad input.
:data:`INPUT_ERRORS` holds the input errors of the analyses and of the linear algebra below
them (:class:`~substruct.linalg.constraints.ConstraintError`,
:class:`~substruct.linalg.scaling.ZeroRowError`), the one tuple a caller catches.
"""

from __future__ import annotations

from substruct.linalg.constraints import ConstraintError
from substruct.linalg.memory import require_memory
from substruct.linalg.scaling import ZeroRowError

__all__ = ["AnalysisInputError", "CheckError", "INPUT_ERRORS", "require_analysis_memory",
           "singular_model"]


class AnalysisInputError(ValueError):
    """The analysis cannot take this input: a property of the model or of what was asked of
    it (a singular system, too few free coordinates, ...), not of the code.

    The message says what is wrong in the model's terms, on one line; the caller adds where
    (the case field).
    """


class CheckError(RuntimeError):
    """Independent formulations of one result disagree beyond the stated tolerance.

    The result is not trusted: the run fails (exit 1) and nothing is written, unless the user
    raises the tolerance explicitly (``analysis.modes.tolerance``, ``analysis.frf.tolerance``).
    """


#: Every exception type that means "the input cannot be analysed" (catch this, never
#: ``ValueError``: a ``ValueError`` of any other type is a bug).
INPUT_ERRORS: tuple[type[ValueError], ...] = (AnalysisInputError, ConstraintError, ZeroRowError)


def require_analysis_memory(need: float, what: str) -> None:
    """:func:`substruct.linalg.memory.require_memory` for an analysis: work estimated to need
    more than the machine has is refused as :class:`AnalysisInputError` (a model too large for
    this machine is the input's property, not a bug).

    Raises:
        AnalysisInputError: one line, e.g. ``the sparse eigensolve of 300000 coordinates
            (CHOLMOD) needs about 31.0 GB; 22.9 GB are available on this machine``.
    """
    try:
        require_memory(need, what)
    except ValueError as err:
        raise AnalysisInputError(str(err)) from None


def singular_model(why: str) -> AnalysisInputError:
    """The error of a pencil with a motion that has neither mass nor stiffness nor constraint
    (a massless coordinate or a mechanism held by nothing): no eigenvalue is defined for it.

    Args:
        why: how it was found, in a few words (``"a block's pencil is not definite"``).
    """
    return AnalysisInputError(f"singular model: a motion with no mass, no stiffness and no "
                              f"constraint (a massless coordinate or mechanism held by "
                              f"nothing: {why})")
