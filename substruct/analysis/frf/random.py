r"""Random vibration: response power spectral densities and RMS values from the receptances.

For stationary inputs with the one-sided cross-spectral matrix :math:`S_f(f)` (``p x p``,
Hermitian positive semidefinite; units of input squared per Hz, e.g. N^2/Hz for forces or
(m/s^2)^2/Hz, g^2/Hz, for base accelerations) and frequency responses :math:`H(f)` from the
inputs to the outputs (``q x p``), the response cross-spectral matrix is

.. math::  S_y(f) = H(f)\, S_f(f)\, H(f)^H

(auto-spectra on its diagonal, :func:`response_psd`).  ``H`` is any of the receptances: per
force (:func:`substruct.analysis.api.receptance_sweep`) or per base acceleration
(:func:`substruct.analysis.frf.base_drive.base_drive_sweep` with ``per="acceleration"``), as
displacement, velocity or acceleration (:func:`substruct.analysis.frf.quantity.quantity_factor`);
the units of :math:`S_y` are those of the output squared per unit of :math:`S_f`'s input
squared times :math:`S_f`'s, so g^2/Hz in gives (output per (m/s^2))^2 g^2/Hz out: convert
:math:`S_f` to SI first for SI outputs.

The mean square is :math:`\sigma^2 = \int S_y\, df` over the grid (:func:`mean_square`): the
trapezoid rule on the given frequencies (``rule="trapezoid"``), or each interval integrated
exactly for the power law through its end values (``rule="loglog"``: :math:`S = S_1
(f/f_1)^b`, :math:`b = \ln(S_2/S_1) / \ln(f_2/f_1)`, the rule of specification tables in
dB/octave; an interval with a zero level or starting at 0 Hz falls back to the trapezoid).
The RMS is :math:`\sigma`; for a Gaussian zero-mean response the 3-sigma level
:math:`3\sigma` is exceeded 0.27 % of the time.

Miles' equation (:func:`miles_rms`): a single-DOF oscillator, natural frequency :math:`f_n`,
:math:`Q = 1 / (2\zeta)`, under a white base acceleration of one-sided level ``W`` has

.. math::  \int_0^\infty \frac{df}{|\omega_n^2 - \omega^2 + 2 i \zeta \omega_n \omega|^2}
           = \frac{1}{2\pi} \frac{\pi}{4 \zeta \omega_n^3} = \frac{Q}{4 \omega_n^3},
           \qquad z_{rms} = \sqrt{\frac{Q W}{4 \omega_n^3}}
           = \sqrt{\frac{Q W}{32 \pi^3 f_n^3}}

for the relative displacement, so the pseudo-acceleration
:math:`\omega_n^2 z_{rms} = \sqrt{\tfrac{\pi}{2} f_n Q W}` (Miles), while the absolute
acceleration, with :math:`|T|^2 = (\omega_n^4 + 4\zeta^2\omega_n^2\omega^2)/|\cdot|^2` and
:math:`\int \omega^2 / |\cdot|^2\, d\omega = \pi / (4 \zeta \omega_n)`, is exactly
:math:`\sqrt{\tfrac{\pi}{2} f_n Q W (1 + 1/Q^2)}`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

__all__ = ["THREE_SIGMA_EXCEEDANCE", "check_spectral_matrix", "check_psd_table",
           "interpolate_psd", "response_psd", "mean_square", "rms", "miles_rms",
           "miles_absolute_rms", "MilesCheck", "miles_check"]

#: The fraction of time a zero-mean Gaussian response exceeds :math:`3\sigma` in magnitude.
THREE_SIGMA_EXCEEDANCE = 0.0027


def check_psd_table(freq: Sequence[float], level: Sequence[float], what: str = "psd") -> None:
    """Refuse a PSD table whose frequencies do not increase strictly or whose levels are
    negative or not finite.

    Raises:
        ValueError: a one-line message naming the first bad entry.
    """
    f = np.asarray(freq, dtype=float)
    s = np.asarray(level, dtype=float)
    if f.ndim != 1 or f.shape != s.shape[:1] or len(f) < 2:
        raise ValueError(f"{what}: a table needs at least two (frequency, level) rows")
    if not np.all(np.isfinite(f)) or np.any(f < 0):
        raise ValueError(f"{what}: frequencies must be finite and >= 0")
    if np.any(np.diff(f) <= 0):
        i = int(np.argmax(np.diff(f) <= 0)) + 1
        raise ValueError(f"{what}: frequencies must increase, got {f[i]:g} after {f[i - 1]:g}")
    if not np.all(np.isfinite(s)) or np.any(s < 0):
        raise ValueError(f"{what}: levels must be finite and >= 0")


def check_spectral_matrix(S: np.ndarray, rtol: float = 1e-10,
                          f: np.ndarray | None = None) -> None:
    r"""Refuse a cross-spectral matrix (``p x p`` or ``(k, p, p)``) that is not Hermitian
    positive semidefinite: :math:`|S - S^H| \le` ``rtol`` :math:`\max|S|` and every eigenvalue
    :math:`\ge -` ``rtol`` :math:`\max|S|` (at each frequency; the scale is the largest term
    of all frequencies).  ``f``: the frequencies of the stack, named in the message.

    Raises:
        ValueError: not finite, not Hermitian or not semidefinite (naming the first frequency
            where it fails and the smallest eigenvalue there).
    """
    S = np.asarray(S, dtype=complex)
    S3 = S.reshape(-1, S.shape[-2], S.shape[-1])
    if S3.shape[1] != S3.shape[2]:
        raise ValueError(f"a cross-spectral matrix must be square, got {S3.shape[1:]}")
    if not np.all(np.isfinite(S3)):
        raise ValueError("a cross-spectral matrix must be finite")
    scale = max(float(np.abs(S3).max(initial=0.0)), 1e-300)
    gap = np.abs(S3 - S3.conj().transpose(0, 2, 1)).max(axis=(1, 2), initial=0.0)
    at = (lambda k: "" if f is None else f" at {float(np.asarray(f)[k]):g} Hz")
    if gap.max(initial=0.0) > rtol * scale:
        k = int(np.argmax(gap > rtol * scale))
        raise ValueError(f"a cross-spectral matrix is not Hermitian{at(k)} (|S - S^H| = "
                         f"{gap[k]:.3g})")
    low = np.linalg.eigvalsh(S3).min(axis=1)
    if low.min(initial=0.0) < -rtol * scale:
        k = int(np.argmax(low < -rtol * scale))
        raise ValueError(f"a cross-spectral matrix is not positive semidefinite{at(k)} "
                         f"(smallest eigenvalue {low[k]:.4g})")


def interpolate_psd(freq: Sequence[float], level: Sequence[float], f: np.ndarray
                    ) -> np.ndarray:
    r"""A specification table's level at ``f`` by log-log interpolation between its rows
    (straight lines in dB/octave); 0 outside the table, linear where a level is 0 or a
    frequency is 0.

    Raises:
        ValueError: a bad table (:func:`check_psd_table`).
    """
    check_psd_table(freq, level)
    ft = np.asarray(freq, dtype=float)
    st = np.asarray(level, dtype=float)
    f = np.asarray(f, dtype=float)
    out = np.zeros_like(f)
    inside = (f >= ft[0]) & (f <= ft[-1])
    i = np.clip(np.searchsorted(ft, f[inside], side="right") - 1, 0, len(ft) - 2)
    f1, f2, s1, s2 = ft[i], ft[i + 1], st[i], st[i + 1]
    x = f[inside]
    loglog = (f1 > 0) & (s1 > 0) & (s2 > 0)
    t = (x - f1) / (f2 - f1)
    lin = s1 + t * (s2 - s1)
    with np.errstate(divide="ignore", invalid="ignore"):
        b = np.log(s2 / s1) / np.log(f2 / f1)
        pw = s1 * (x / f1) ** b
    out[inside] = np.where(loglog, pw, lin)
    return out


def response_psd(H: np.ndarray, S: np.ndarray) -> np.ndarray:
    r""":math:`S_y[k] = H[k]\, S[k]\, H[k]^H` (``(n_f, q, q)``) for ``H`` ``(n_f, q, p)`` and
    ``S`` ``(n_f, p, p)``, ``(p, p)`` (the same at every frequency) or ``(n_f,)`` (one input).

    Raises:
        ValueError: shapes that do not match.
    """
    H = np.asarray(H)
    S = np.asarray(S)
    nf, q, p = H.shape
    if S.ndim == 1:
        if p != 1 or S.shape[0] != nf:
            raise ValueError(f"a PSD vector needs one input and {nf} levels")
        S = S.reshape(nf, 1, 1)
    elif S.ndim == 2:
        S = np.broadcast_to(S, (nf, *S.shape))
    if S.shape != (nf, p, p):
        raise ValueError(f"a cross-spectral matrix of shape {S.shape} for {nf} frequencies "
                         f"and {p} inputs")
    return np.matmul(np.matmul(H, S), H.conj().transpose(0, 2, 1))


def mean_square(f: np.ndarray, S: np.ndarray, rule: str = "trapezoid") -> np.ndarray:
    r""":math:`\int S\, df` over the grid ``f`` (Hz, increasing) along the first axis of ``S``
    (module docstring for the rules; the real part of a cross-spectrum is integrated too).

    Raises:
        ValueError: an unknown rule, or ``f`` not increasing.
    """
    f = np.asarray(f, dtype=float)
    S = np.asarray(S)
    if np.any(np.diff(f) <= 0):
        raise ValueError("the frequencies must increase")
    df = np.diff(f).reshape(-1, *([1] * (S.ndim - 1)))
    s1, s2 = S[:-1], S[1:]
    trap = 0.5 * (s1 + s2) * df
    if rule == "trapezoid":
        return np.sum(trap, axis=0)
    if rule != "loglog":
        raise ValueError(f"unknown integration rule {rule!r}; expected trapezoid or loglog")
    f1 = f[:-1].reshape(df.shape)
    f2 = f[1:].reshape(df.shape)
    a1, a2 = np.abs(s1), np.abs(s2)
    ok = (f1 > 0) & (a1 > 0) & (a2 > 0) & np.isreal(S[:-1]) & np.isreal(S[1:])
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        b = np.log(a2 / a1) / np.log(f2 / f1)
        near = np.abs(b + 1) < 1e-9
        power = np.where(near, a1 * f1 * np.log(f2 / f1),
                         a1 * f1 / (b + 1) * ((f2 / f1) ** (b + 1) - 1))
    exact = np.where(ok & np.isfinite(power), np.sign(np.real(s1)) * power, trap)
    return np.sum(exact, axis=0)


def rms(f: np.ndarray, psd: np.ndarray, rule: str = "trapezoid") -> np.ndarray:
    r""":math:`\sigma = \sqrt{\int S\, df}` of auto-spectra ``psd`` (first axis frequency)."""
    return np.sqrt(np.maximum(np.real(mean_square(f, psd, rule)), 0.0))


def miles_rms(fn: float, Q: float, W: float) -> float:
    r"""Miles' equation: :math:`\sqrt{\tfrac{\pi}{2} f_n Q W}`, the RMS pseudo-acceleration
    :math:`\omega_n^2 z_{rms}` of a single-DOF oscillator under white base acceleration ``W``
    (one-sided, per Hz; the result in the unit of :math:`\sqrt{W \cdot Hz}`)."""
    return float(np.sqrt(np.pi / 2 * fn * Q * W))


def miles_absolute_rms(fn: float, Q: float, W: float) -> float:
    r"""The exact RMS absolute acceleration of the same oscillator:
    :math:`\sqrt{\tfrac{\pi}{2} f_n Q W (1 + 1/Q^2)}` (module docstring)."""
    return float(np.sqrt(np.pi / 2 * fn * Q * W * (1 + 1 / Q ** 2)))


@dataclass(frozen=True)
class MilesCheck:
    r"""Miles' estimate of one output's RMS from its highest transmissibility peak.

    Attributes:
        fn: the peak's frequency (Hz); ``Q`` the transmissibility's magnitude there;
        W: the input PSD there; ``miles``: :math:`\sqrt{\tfrac{\pi}{2} f_n Q W}`.
    """

    fn: float
    Q: float
    W: float
    miles: float


def miles_check(f: np.ndarray, input_psd: np.ndarray, output_psd: np.ndarray) -> MilesCheck:
    r"""Miles' equation applied to the peak of :math:`|T|^2 = S_y / S_{in}` (one base input):
    :math:`f_n` where :math:`|T|^2` is largest on the grid, :math:`Q = |T(f_n)|`,
    :math:`W = S_{in}(f_n)` and :func:`miles_rms`.  For a response dominated by one
    well-separated single-DOF-like mode on a locally flat input this is its RMS to within
    :math:`1/\sqrt{1 + 1/Q^2}` and the grid's resolution of the peak; several modes, or a
    steep input under the peak, make it an estimate only.

    Raises:
        ValueError: no frequency where the input is positive.
    """
    f = np.asarray(f, dtype=float)
    s_in = np.asarray(input_psd, dtype=float)
    s_out = np.real(np.asarray(output_psd))
    live = s_in > 0
    if not np.any(live):
        raise ValueError("the input PSD is 0 on the whole grid")
    t2 = np.where(live, s_out / np.where(live, s_in, 1.0), -np.inf)
    k = int(np.argmax(t2))
    Q = float(np.sqrt(max(t2[k], 0.0)))
    return MilesCheck(fn=float(f[k]), Q=Q, W=float(s_in[k]),
                      miles=miles_rms(float(f[k]), Q, float(s_in[k])))
