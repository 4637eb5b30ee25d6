r"""Does a frequency grid resolve the resonances of a response PSD?  An estimate of the
trapezoid rule's error on the mean square.

The RMS of a random response is the trapezoid rule over the analysis grid
(:func:`substruct.analysis.frf.random.mean_square`).  Near a lightly damped mode the response
PSD is a Lorentzian in the frequency,

.. math::  S(f) \approx \frac{S_0}{1 + (f - f_0)^2 / \gamma^2}, \qquad
           \gamma = \zeta f_0 \ \text{(the half-power half-width)},
           \qquad \int S\, df = \pi \gamma S_0 ,

so :math:`1/S` is a parabola in ``f``: the three samples around each interior local maximum
of ``S`` give :math:`f_0`, :math:`\gamma` and :math:`S_0` wherever they fall on the peak, even
when the grid steps over it.  The trapezoid rule with step ``h`` sums a Lorentzian to
:math:`\pi \gamma S_0 \sinh u / (\cosh u - \cos\varphi)`, :math:`u = 2\pi\gamma/h` (the sampled
Poisson kernel; :math:`\varphi` the peak's place between samples), whose relative error is at
most :math:`\coth(u/2) - 1 = 2 / (e^u - 1)`: :math:`4 \cdot 10^{-3}` at :math:`h = \gamma`,
:math:`1.6` at :math:`h = 5 \gamma` (a peak stepped over).  :func:`quadrature_error` sums that
bound times :math:`\pi\gamma S_0` over the peaks of each output, relative to its mean square.
A local maximum whose :math:`1/S` is not a parabola opening upwards (a corner of a
specification table, round-off on a flat spectrum) is not a resonance and adds nothing; one
whose parabola dips to 0 or below (the samples on the flanks of a peak far higher than any of
them) makes the error infinite, with ``gamma`` 0; the
ends of the grid are not peaks (the band stops there by choice).  The estimate does not depend
on the scale of ``S`` or of ``f``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["RMS_QUADRATURE_TOLERANCE", "PeakResolution", "quadrature_error"]

#: The largest estimated relative error of a mean square the random response accepts.
RMS_QUADRATURE_TOLERANCE = 1e-2


@dataclass(frozen=True)
class PeakResolution:
    """The estimate for one output.

    Attributes:
        error: the estimated error of the trapezoid mean square, relative to it.
        f0, gamma, step: the worst peak: its frequency, half-power half-width and the grid
            step there (Hz); ``nan`` without a peak.
    """

    error: float
    f0: float
    gamma: float
    step: float


def quadrature_error(f: np.ndarray, S: np.ndarray) -> list[PeakResolution]:
    """The estimated trapezoid error (module docstring) of each column of the auto-spectra
    ``S`` (``n_f x q``, real, ``>= 0``) on the grid ``f`` (increasing)."""
    f = np.asarray(f, dtype=float)
    S = np.asarray(S, dtype=float).reshape(len(f), -1)
    out = []
    for s in S.T:
        total = float(np.sum(0.5 * (s[:-1] + s[1:]) * np.diff(f))) if len(f) > 1 else 0.0
        error, worst, worst_at = 0.0, 0.0, (np.nan, np.nan, np.nan)
        k = np.flatnonzero((s[1:-1] >= s[:-2]) & (s[1:-1] > s[2:]) & (s[1:-1] > 0)) + 1
        for i in k:
            if s[i - 1] <= 0 or s[i + 1] <= 0:
                continue
            h = float(max(f[i + 1] - f[i], f[i] - f[i - 1]))
            t = (f[i - 1:i + 2] - f[i]) / h              # about -1, 0, 1
            A, B, C = np.polyfit(t, s[i] / s[i - 1:i + 2], 2)   # 1/S scaled by the peak
            if not A > 0:
                continue
            c = C - B * B / (4 * A)
            f0 = float(f[i] - B / (2 * A) * h)
            if not c > 0:       # the parabola's vertex at or below 0: a peak stepped over
                error, worst, worst_at = np.inf, np.inf, (f0, 0.0, h)
                continue
            gamma = h * float(np.sqrt(c / A))
            area = np.pi * gamma * float(s[i]) / c
            u = 2 * np.pi * gamma / h
            bound = area * (2 / np.expm1(u) if u < 700 else 0.0)
            error += bound
            if bound > worst:
                worst, worst_at = bound, (f0, gamma, h)
        ref = max(total, 1e-300)
        out.append(PeakResolution(error / ref if error > 0 else 0.0, *worst_at))
    return out
