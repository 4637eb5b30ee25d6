"""Errors the command line finds itself (exit code 2)."""

from __future__ import annotations

__all__ = ["InputError"]


class InputError(Exception):
    """Bad input found by the command line itself (exit code 2)."""
