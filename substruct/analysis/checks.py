r"""Cross-checks: how far an independent formulation is from the main one, and when that fails
the result.

Every analysis is computed by a main formulation and, on request, by checks (generalized
inverse vs null space vs Lagrange multipliers).  The figures:

.. math::  \delta_{modes} = \max_j \frac{|\lambda^{check}_j - \lambda_j|}
                                        {\max(|\lambda_j|, 10^{-8} \max_i |\lambda_i|)}
           \qquad \text{(over the modes both have)},

.. math::  \delta_{receptance} = \frac{\max |H^{check} - H|}{\max(\max |H|, h_0)} ,

where :math:`h_0` is ``0`` unless the exact receptance is zero (the constraints hold every
coordinate): the formulations then return rounding of zero, and their differences are measured
against the compliance scale of the problem (:func:`compliance_scale`), never against
``max |H|`` (itself rounding: a relative figure of 1.0 between 1e-17 and 0).

A figure above the stated tolerance raises :class:`~substruct.analysis.errors.CheckError`
(:func:`require_agreement`): a result that its checks contradict is an error, never a print.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
import scipy.sparse as sp

from substruct.analysis.errors import CheckError
from substruct.analysis.results import Modes
from substruct.linalg.constraints import independent_rows

__all__ = ["check_methods", "modes_agreement", "receptance_difference", "require_agreement",
           "compliance_scale", "holds_every_coordinate", "require_finite"]


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


def receptance_difference(H_check: np.ndarray, H: np.ndarray, floor: float = 0.0) -> float:
    r"""``max |H_check - H| / max(max |H|, floor)`` (the denominator at least ``1e-300``).

    ``floor`` is ``0`` for a relative figure; :func:`compliance_scale` when the exact ``H`` is
    zero (:func:`holds_every_coordinate`), so that rounding of zero is judged in absolute
    terms against the problem's scale.
    """
    scale = max(float(np.abs(H).max(initial=0.0)), float(floor), 1e-300)
    return float(np.abs(H_check - H).max(initial=0.0) / scale)


def _norm_inf(X: sp.sparray | np.ndarray | None) -> float:
    """The largest absolute row sum of ``X`` (``0`` for ``None`` or empty)."""
    if X is None or min(X.shape) == 0:
        return 0.0
    return float(np.abs(sp.csr_array(X)).sum(axis=1).max())


def compliance_scale(K: sp.sparray | np.ndarray, M: sp.sparray | np.ndarray,
                     C: sp.sparray | np.ndarray | None, omegas: np.ndarray,
                     inputs: sp.sparray | np.ndarray, outputs: sp.sparray | np.ndarray
                     ) -> float:
    r"""The receptance scale of a problem, from its data alone:

    .. math::  h_0 = \frac{\max_i \|o_i\|_1 \, \max_j \|e_j\|_1}
                          {\min_k \|Z(\omega_k)\|_\infty}, \qquad
               \|Z(\omega)\|_\infty \le \|K\|_\infty + \omega^2 \|M\|_\infty
                                      + \omega \|C\|_\infty

    (the displacement a unit input gives through the stiffest part of the impedance: the
    size below which a receptance is rounding of zero for a backward-stable solve).  Scaling
    ``K, M, C`` by ``c`` scales ``h_0`` by ``1/c``, the inputs or outputs by ``c`` by ``c``.
    ``inf`` for a zero impedance (no data: nothing can be compared against it).
    """
    w = np.abs(np.atleast_1d(np.asarray(omegas, dtype=float)))
    if w.size == 0:
        return 0.0
    k, m, c = _norm_inf(K), _norm_inf(M), _norm_inf(C)
    z = float(np.min(k + w ** 2 * m + w * c))
    o = _norm_inf(outputs)
    e = _norm_inf(sp.csr_array(inputs).T)
    return o * e / z if z > 0 else float("inf")


def holds_every_coordinate(A: sp.sparray, R: sp.sparray | None, n: int) -> bool:
    r"""Whether ``A q = 0`` (``R`` absent) leaves no free coordinate: ``rank A = n``, so the
    exact receptance is zero at every frequency (eq 15 with an empty null space)."""
    if n == 0 or A.shape[0] < n or (R is not None and sp.csr_array(R).nnz):
        return False
    return independent_rows(A).rank == n


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


def require_finite(what: str, **arrays: np.ndarray) -> None:
    """Raise :class:`CheckError` if a computed array holds ``inf`` or ``NaN`` (an overflow, a
    division by zero): such a result is not to be trusted, and is never written or printed as a
    table of ``inf``.

    The message is one line, e.g. ``frf: 4 of 18 values of H are inf or NaN (an overflow: the
    model's numbers span more than double precision carries); nothing written``.

    Args:
        what: the analysis, as the message starts.
        arrays: name -> computed array (or a
            :class:`~substruct.analysis.frf.stream.StreamedArray`, whose blocks were counted as
            they passed).
    """
    for name, values in arrays.items():
        counted = getattr(values, "nonfinite", None)  # a streamed output counted its blocks
        if counted is not None:
            bad, size = int(counted), int(values.size)
        else:
            a = np.asarray(values)
            size = a.size
            bad = int(a.size - np.count_nonzero(np.isfinite(a))) \
                if a.size and a.dtype.kind in "fc" else 0
        if bad:
            raise CheckError(f"{what}: {bad} of {size} values of {name} are inf or NaN (an "
                             f"overflow: the model's numbers span more than double precision "
                             f"carries); nothing written")
