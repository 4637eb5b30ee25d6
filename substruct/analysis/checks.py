r"""Cross-checks: how far an independent formulation is from the main one, and when that fails
the result.

Every analysis is computed by a main formulation and, on request, by checks (DESIGN.md
section 4, rung 3: generalized inverse vs null space vs Lagrange multipliers).  The figures:

.. math::  \delta_{modes} = \max_j \frac{|\lambda^{check}_j - \lambda_j|}
                                        {\max(|\lambda_j|, 10^{-8} \max_i |\lambda_i|)}
           \qquad \text{(over the modes both have)},

.. math::  \delta_{receptance} = \frac{\max |H^{check} - H|}{\max |H|} .

A figure above the stated tolerance raises :class:`~substruct.analysis.errors.CheckError`
(:func:`require_agreement`): a result that its checks contradict is an error, never a print.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from substruct.analysis.errors import CheckError
from substruct.analysis.results import Modes

__all__ = ["check_methods", "modes_agreement", "receptance_difference", "require_agreement"]


def check_methods(main: str, checks: Sequence[str]) -> list[str]:
    """The check formulations of ``checks`` other than ``main``, each once, in order."""
    return [m for k, m in enumerate(checks) if m != main and m not in checks[:k]]


def modes_agreement(a: Modes, b: Modes) -> float:
    r"""Largest relative difference between the eigenvalues of two mode sets.

    .. math::  \delta = \max_j |\lambda^a_j - \lambda^b_j| / \max(|\lambda^b_j|, 10^{-8} s),
               \qquad s = \max_j |\lambda^b_j|

    over the common number of modes; ``inf`` if one set has no modes and the other has.
    """
    k = min(len(a), len(b))
    if k == 0:
        return 0.0 if len(a) == len(b) else float("inf")
    scale = max(np.abs(b.eigenvalues[:k]).max(), 1e-300)
    denom = np.maximum(np.abs(b.eigenvalues[:k]), 1e-8 * scale)
    return float(np.max(np.abs(a.eigenvalues[:k] - b.eigenvalues[:k]) / denom))


def receptance_difference(H_check: np.ndarray, H: np.ndarray) -> float:
    r"""``max |H_check - H| / max |H|`` (``max |H|`` taken as at least ``1e-300``)."""
    scale = max(float(np.abs(H).max(initial=0.0)), 1e-300)
    return float(np.abs(H_check - H).max(initial=0.0) / scale)


def require_agreement(what: str, main: str, agreement: dict[str, float],
                      tolerance: float) -> None:
    """Raise :class:`CheckError` if a check disagrees with the main formulation by more than
    ``tolerance`` (a NaN figure disagrees).

    The message is one line naming the formulations and the figure, e.g.
    ``modes: null-space disagrees with generalized-inverse by 8.0e-01 (tolerance 1e-06)``;
    with several failing checks, the worst one.

    Args:
        what: the analysis, as the message starts (``"modes"``, ``"frf"``, ...).
        main: the main formulation.
        agreement: check formulation -> figure.
        tolerance: the largest figure allowed.
    """
    bad = {m: v for m, v in agreement.items() if not v <= tolerance}
    if not bad:
        return
    worst = max(bad, key=lambda m: np.inf if np.isnan(bad[m]) else bad[m])
    others = [m for m in bad if m != worst]
    also = f"; also {', '.join(f'{m} by {bad[m]:.1e}' for m in others)}" if others else ""
    raise CheckError(f"{what}: {worst} disagrees with {main} by {bad[worst]:.1e} "
                     f"(tolerance {tolerance:g}){also}")
