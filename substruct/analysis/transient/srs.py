r"""Shock response spectra of a base-acceleration time history.

A single-DOF oscillator of natural frequency :math:`f_n` and damping ratio :math:`\zeta`
(:math:`Q = 1/(2\zeta)`) on a base with acceleration :math:`\ddot u(t)` has the relative
displacement :math:`z` and absolute acceleration :math:`\ddot x = \ddot u + \ddot z`:

.. math::  \ddot z + 2\zeta\omega_n \dot z + \omega_n^2 z = -\ddot u, \qquad
           \ddot x = -2\zeta\omega_n \dot z - \omega_n^2 z .

The absolute-acceleration response is computed by Smallwood's ramp-invariant digital filter
(the input taken as straight lines between samples), with
:math:`E = e^{-\zeta\omega_n h}`, :math:`K = \omega_d h`, :math:`\omega_d = \omega_n
\sqrt{1-\zeta^2}`, :math:`C = E\cos K`, :math:`S = E\sin K`, :math:`S' = S/K`:

.. math::  \ddot x_k = 2C \ddot x_{k-1} - E^2 \ddot x_{k-2}
           + (1 - S') \ddot u_k + 2(S' - C) \ddot u_{k-1} + (E^2 - S') \ddot u_{k-2} ,

(:func:`smallwood_coefficients`), and the pseudo-velocity :math:`\omega_n |z|_{max}` by the
ramp-invariant discretization of the relative-displacement equation (the exact solution for a
piecewise-linear input, :func:`relative_displacement`).  The spectrum is the largest positive
(``"pos"``), the largest negative in magnitude (``"neg"``) and the largest absolute
(``"maxabs"``, maximax) response over the history followed by ``pad`` seconds of zero input
(the residual response; by default one period of the lowest frequency).

Error (stated): the filter is exact for the piecewise-linear input; the spectrum's peaks are
read at the samples, which underestimates a peak by at most :math:`1 - \cos(\pi f_n h)
\approx (\pi f_n h)^2 / 2` (0.05 % at 100 samples a period, 0.5 % at 30), and the
straight-line input differs from a smooth one by :math:`O((f h)^2)`; :func:`srs` refuses
frequencies above a tenth of the sample rate (:data:`MAX_FN_DT`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["MAX_FN_DT", "Srs", "check_damping", "smallwood_coefficients",
           "relative_displacement", "srs"]

#: The largest :math:`f_n h` a spectrum is computed at (10 samples a period: peak error below
#: 5 %, module docstring).
MAX_FN_DT = 0.1


@dataclass(frozen=True)
class Srs:
    """A shock response spectrum.

    Attributes:
        fn: natural frequencies (Hz).
        zeta: damping ratio (``Q = 1 / (2 zeta)``).
        pos, neg, maxabs: largest positive, largest negative (as a magnitude) and largest
            absolute acceleration of the oscillator (the input's unit).
        pv: pseudo-velocity :math:`\\omega_n \\max |z|` (input unit x s).
    """

    fn: np.ndarray
    zeta: float
    pos: np.ndarray
    neg: np.ndarray
    maxabs: np.ndarray
    pv: np.ndarray


def check_damping(zeta: float) -> None:
    """Refuse a damping ratio outside (0, 1).

    Raises:
        ValueError: ``zeta`` not in (0, 1).
    """
    if not np.isfinite(zeta) or not 0 < zeta < 1:
        raise ValueError(f"an SRS damping ratio must be in (0, 1), got {zeta!r}")


def smallwood_coefficients(fn: float, zeta: float, dt: float
                           ) -> tuple[np.ndarray, np.ndarray]:
    """``(b, a)`` of Smallwood's absolute-acceleration filter (module docstring), for
    :func:`scipy.signal.lfilter`."""
    wn = 2 * np.pi * fn
    wd = wn * np.sqrt(1 - zeta ** 2)
    E = np.exp(-zeta * wn * dt)
    K = wd * dt
    C = E * np.cos(K)
    Sp = E * np.sin(K) / K
    return np.array([1 - Sp, 2 * (Sp - C), E * E - Sp]), np.array([1.0, -2 * C, E * E])


def relative_displacement(acc: np.ndarray, fn: float, zeta: float, dt: float) -> np.ndarray:
    r""":math:`z_k` of :math:`\ddot z + 2\zeta\omega_n\dot z + \omega_n^2 z = -\ddot u`, from
    rest, exact for :math:`\ddot u` linear between samples (the ramp-invariant discretization
    of the state :math:`(z, \dot z)` by :func:`scipy.signal.cont2discrete`, ``foh``)."""
    import scipy.signal as ss  # on first use: about 0.9 s of start-up for every run otherwise

    wn = 2 * np.pi * fn
    A = np.array([[0.0, 1.0], [-wn * wn, -2 * zeta * wn]])
    B = np.array([[0.0], [-1.0]])
    Ad, Bd, Cd, Dd, _ = ss.cont2discrete((A, B, np.array([[1.0, 0.0]]), np.zeros((1, 1))),
                                         dt, method="foh")
    num, den = ss.ss2tf(Ad, Bd, Cd, Dd)
    return ss.lfilter(num[0], den, acc)


def srs(acc: np.ndarray, dt: float, fn: np.ndarray, zeta: float = 0.05,
        pad: float | None = None) -> Srs:
    r"""The shock response spectrum of the base acceleration ``acc`` sampled every ``dt``
    (from rest) at the natural frequencies ``fn`` (Hz), damping ratio ``zeta``.

    Args:
        pad: seconds of zero input appended for the residual response (default
            ``1 / min(fn)``).

    Raises:
        ValueError: ``zeta`` outside (0, 1), ``dt <= 0``, a frequency <= 0 or above
            :data:`MAX_FN_DT` / ``dt``, or a history that is empty or not finite.
    """
    check_damping(zeta)
    acc = np.asarray(acc, dtype=float)
    fn = np.atleast_1d(np.asarray(fn, dtype=float))
    if not dt > 0 or not np.isfinite(dt):
        raise ValueError(f"the time step must be > 0, got {dt!r}")
    if acc.ndim != 1 or acc.size == 0 or not np.all(np.isfinite(acc)):
        raise ValueError("an SRS needs a finite, non-empty history")
    if fn.size == 0 or np.any(~np.isfinite(fn)) or np.any(fn <= 0):
        raise ValueError("SRS frequencies must be > 0")
    if float(fn.max()) * dt > MAX_FN_DT:
        raise ValueError(f"SRS frequency {fn.max():g} Hz needs a time step <= "
                         f"{MAX_FN_DT / fn.max():.3g} s (10 samples a period), got {dt:g}")
    import scipy.signal as ss  # on first use (above)

    extra = int(np.ceil((1 / fn.min() if pad is None else max(pad, 0.0)) / dt))
    x = np.concatenate([acc, np.zeros(extra)])
    out = np.empty((4, fn.size))
    for i, f in enumerate(fn):
        b, a = smallwood_coefficients(float(f), zeta, dt)
        y = ss.lfilter(b, a, x)
        z = relative_displacement(x, float(f), zeta, dt)
        out[:, i] = (max(float(y.max()), 0.0), max(-float(y.min()), 0.0),
                     float(np.abs(y).max()), 2 * np.pi * f * float(np.abs(z).max()))
    return Srs(fn=fn, zeta=float(zeta), pos=out[0], neg=out[1], maxabs=out[2], pv=out[3])
