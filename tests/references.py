"""References that share no code with substruct, for numbers the tests would otherwise pin.

The tapered rod of the paper's section 6 (eq 50), fixed at ``x = 0`` and free at ``x = L``:

.. math::  (EA(x)\\, u')' + \\omega^2 m(x)\\, u = 0, \\qquad u(0) = 0, \\qquad EA\\, u'(L) = 0,
           \\qquad EA(x) = \\tfrac65 EA_0 (1 - \\tfrac12 (x/L)^2), \\;
           m(x) = \\tfrac65 m_0 (1 - \\tfrac12 (x/L)^2),

solved by shooting: the first-order system ``u' = N / EA``, ``N' = -omega^2 m u`` from
``u(0) = 0, N(0) = 1`` is integrated by an adaptive Runge-Kutta method (DOP853, relative
tolerance 1e-12), and ``omega`` is the root of the tip force ``N(L)`` in a bracket.
"""

from functools import lru_cache

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

__all__ = ["tapered_rod_frequency", "TAPERED_ROD"]

#: ``(L, EA0, m0)`` of the paper's tapered rod (Table 1).
TAPERED_ROD = (200.0, 6e6, 1.0)

#: Brackets (rad/s) of the first two natural frequencies of the fixed-free tapered rod.
_BRACKETS = ((15.0, 30.0), (50.0, 70.0))


def _tip_force(omega: float, L: float, EA0: float, m0: float) -> float:
    def taper(x: float) -> float:
        return 1.2 * (1.0 - 0.5 * (x / L) ** 2)

    def rhs(x: float, y: np.ndarray) -> list[float]:
        return [y[1] / (EA0 * taper(x)), -omega**2 * m0 * taper(x) * y[0]]

    sol = solve_ivp(rhs, (0.0, L), [0.0, 1.0], method="DOP853", rtol=1e-12, atol=1e-14)
    return float(sol.y[1, -1])


@lru_cache(maxsize=None)
def tapered_rod_frequency(k: int = 1) -> float:
    """The ``k``-th (1 or 2) natural frequency in rad/s of the fixed-free tapered rod of
    :data:`TAPERED_ROD`, to about 1e-12 relative (21.72977912..., 59.0517409...)."""
    lo, hi = _BRACKETS[k - 1]
    return float(brentq(_tip_force, lo, hi, args=TAPERED_ROD, xtol=1e-13, rtol=1e-14))
