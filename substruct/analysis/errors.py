"""Errors of the analyses that are not bad input."""

from __future__ import annotations

__all__ = ["CheckError"]


class CheckError(RuntimeError):
    """Independent formulations of one result disagree beyond the stated tolerance.

    The result is not trusted: the run fails (exit 1) and nothing is written, unless the user
    raises the tolerance explicitly (``analysis.modes.tolerance``, ``analysis.frf.tolerance``).
    """
