"""Axis labels in the case's units.

substruct is unit-consistent, not unit-aware: it computes with the numbers of the case file, so
the answers are in whatever consistent set the inputs were written in, and the case's
``units:`` note (conventionally ``"force, length, mass, time"``, e.g. ``"N, mm, t, s"``) says
which.  The pictures read that note to label their axes; nothing is converted.
"""

from __future__ import annotations

__all__ = ["unit_parts", "frf_axis_label"]

#: What ``H`` is, and its unit from the length, force and time units.
_QUANTITY = {
    "receptance": ("displacement / force", "{L}/{F}"),
    "mobility": ("velocity / force", "{L}/({F} {T})"),
    "accelerance": ("acceleration / force", "{L}/({F} {T}\u00b2)"),
}


def unit_parts(units: str) -> dict[str, str] | None:
    """The force, length, mass and time units of a ``units:`` note written as four comma-
    separated names (``"N, mm, t, s"``); ``None`` for any other note."""
    parts = [p.strip() for p in str(units).split(",")]
    if len(parts) != 4 or not all(parts) or any(" " in p for p in parts):
        return None
    return dict(zip("FLMT", parts))


def frf_axis_label(units: str | None, quantity: str = "receptance") -> str:
    """``|H| (mm/N)``: the magnitude axis of an FRF in the case's units.

    A note that is not four units is quoted as it is; no note gives the quantity alone
    (``|H| (displacement / force)``).
    """
    words, pattern = _QUANTITY.get(quantity, _QUANTITY["receptance"])
    if not units:
        return f"|H|  ({words})"
    parts = unit_parts(units)
    if parts is None:
        return f"|H|  ({words}; case units: {units})"
    return f"|H|  ({words}, {pattern.format(**parts)})"
