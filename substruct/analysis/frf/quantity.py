r"""What a frequency response is reported as: receptance, mobility or accelerance.

.. math::  \alpha = \frac{u}{F}, \qquad Y = \frac{\dot u}{F} = i \omega\, \alpha, \qquad
           A = \frac{\ddot u}{F} = -\omega^2 \alpha

(harmonic motion :math:`u e^{i \omega t}`, ``omega`` in rad/s whatever unit the grid was given
in).  The analyses compute receptances; :func:`as_quantity` converts a
:class:`~substruct.analysis.results.Receptance` once, at the end, and records the quantity.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from substruct.analysis.results import Receptance

__all__ = ["QUANTITY_POWER", "quantity_factor", "as_quantity", "quantity_units"]

#: The quantities, each with its power of ``i omega``.
QUANTITY_POWER = {"receptance": 0, "mobility": 1, "accelerance": 2}


def quantity_factor(omega: np.ndarray, quantity: str) -> np.ndarray:
    r"""``(i omega)^p``: the factor from receptance to ``quantity``.

    Raises:
        ValueError: an unknown quantity.
    """
    if quantity not in QUANTITY_POWER:
        raise ValueError(f"unknown quantity {quantity!r}; expected one of "
                         f"{', '.join(QUANTITY_POWER)}")
    return (1j * np.asarray(omega, dtype=float)) ** QUANTITY_POWER[quantity]


def as_quantity(frf: Receptance, quantity: str) -> Receptance:
    """``frf`` (receptances) as ``quantity``; the same object for ``"receptance"``.

    Raises:
        ValueError: an unknown quantity, or ``frf`` already converted.
    """
    if frf.quantity != "receptance":
        raise ValueError(f"the responses are already {frf.quantity}")
    if quantity == "receptance":
        return frf
    H = frf.H * quantity_factor(frf.omega, quantity)[:, None, None]
    return dataclasses.replace(frf, H=H, quantity=quantity)


def quantity_units(quantity: str, units: str = "") -> str:
    """The unit of a quantity from the case's units ``"N, m, kg, s"`` (``"m/N"``,
    ``"m/(N s)"``, ``"m/(N s^2)"``); generic (``"length/force"``) if they are not given."""
    parts = [p.strip() for p in units.split(",")] if units else []
    force, length = (parts[0], parts[1]) if len(parts) >= 2 else ("force", "length")
    time = parts[3] if len(parts) >= 4 else "s"
    per = {"receptance": f"{length}/{force}", "mobility": f"{length}/({force} {time})",
           "accelerance": f"{length}/({force} {time}^2)"}
    if quantity not in per:
        raise ValueError(f"unknown quantity {quantity!r}")
    return per[quantity]
