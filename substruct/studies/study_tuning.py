r"""Den Hartog's closed-form tuning of a damped vibration absorber, to compare with a study.

A primary mode of natural frequency :math:`\omega_p` and mass-normalized shape :math:`\phi`
(:math:`\phi^T M \phi = 1`) seen at the absorber's point :math:`x_a` is a single oscillator of
equivalent modal mass :math:`M_{eq} = 1 / \phi(x_a)^2`.  An absorber of mass :math:`m_a`,
:math:`\mu = m_a / M_{eq}`, minimizes the peak of the primary's receptance (equal fixed points,
Den Hartog) with

.. math::  f_{opt} = \frac{\omega_a}{\omega_p} = \frac{1}{1 + \mu}, \qquad
           \zeta_{opt} = \sqrt{\frac{3 \mu}{8 (1 + \mu)^3}},

that is :math:`k_{opt} = m_a (f_{opt} \omega_p)^2` and
:math:`c_{opt} = 2 \zeta_{opt} m_a f_{opt} \omega_p`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

__all__ = ["DenHartog", "den_hartog", "grid_optimum"]


@dataclass(frozen=True)
class DenHartog:
    """The closed-form tuning: mass ratio, frequency ratio, damping ratio, stiffness, damping."""

    mu: float
    f_opt: float
    zeta_opt: float
    k_opt: float
    c_opt: float


def den_hartog(omega_p: float, modal_mass: float, absorber_mass: float) -> DenHartog:
    """Den Hartog's tuning of an absorber of ``absorber_mass`` on a mode of ``omega_p`` (rad/s)
    and equivalent ``modal_mass`` at the absorber's point."""
    mu = float(absorber_mass) / float(modal_mass)
    f = 1.0 / (1.0 + mu)
    zeta = math.sqrt(3.0 * mu / (8.0 * (1.0 + mu) ** 3))
    w = f * float(omega_p)
    m = float(absorber_mass)
    return DenHartog(mu=mu, f_opt=f, zeta_opt=zeta, k_opt=m * w * w,
                     c_opt=2.0 * zeta * m * w)


def grid_optimum(peaks: Sequence[float]) -> tuple[int, float]:
    """The sample of the smallest finite peak: ``(index, peak)``."""
    best, value = -1, math.inf
    for k, p in enumerate(peaks):
        if math.isfinite(p) and p < value:
            best, value = k, float(p)
    return best, value
