"""The ``check:`` list of an analysis: formulations other than its ``method``, each once.

A check is the same result computed by another formulation and compared with the main one
(:mod:`substruct.analysis.checks`).  The analyses run each check formulation other than the
method once (:func:`substruct.analysis.checks.check_methods`), so an entry naming the method
itself, or an entry named twice, would be dropped without a word: the case asked for a check
that never runs.  Both are refused here, naming the entry.
"""

from __future__ import annotations

from typing import Sequence

from substruct.case.errors import FieldError

__all__ = ["refuse_idle_checks"]


def refuse_idle_checks(method: str, checks: Sequence[str]) -> None:
    """Refuse a ``check`` entry that would not run: the ``method`` itself, or a repeat.

    Args:
        method: the analysis's main formulation (``generalized-inverse``, ``modal``, ...).
        checks: its ``check`` list, as written.

    Raises:
        FieldError: at ``check[k]``, the first such entry.

    Examples:
        >>> refuse_idle_checks("generalized-inverse", ["null-space", "kkt"])
        >>> refuse_idle_checks("kkt", ["null-space", "kkt"])
        Traceback (most recent call last):
        ...
        substruct.case.errors.FieldError: a formulation does not check itself: kkt is the method; name another formulation or leave it out
    """
    for k, name in enumerate(checks):
        if name == method:
            raise FieldError(("check", k), f"a formulation does not check itself: {name} is "
                             f"the method; name another formulation or leave it out", name)
        if name in checks[:k]:
            raise FieldError(("check", k), "a check named twice (each runs once)", name)
