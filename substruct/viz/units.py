"""Axis labels in the case's units.

substruct is unit-consistent, not unit-aware: it computes with the numbers of the case file, so
the answers are in whatever consistent set the inputs were written in, and the case's
``units:`` note (conventionally ``"force, length, mass, time"``, e.g. ``"N, mm, t, s"``) says
which.  The pictures read that note to label their axes; nothing is converted.
"""

from __future__ import annotations

__all__ = ["unit_parts", "frf_axis_label", "frf_unit"]

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


def frf_unit(units: str | None, quantity: str = "receptance") -> str | None:
    """The unit of ``H`` in the case's units (``mm/N``; ``m/(N s)`` for a mobility), or
    ``None`` if the note is not four units."""
    parts = unit_parts(units) if units else None
    if parts is None:
        return None
    return _QUANTITY.get(quantity, _QUANTITY["receptance"])[1].format(**parts)


def frf_axis_label(units: str | None, quantity: str = "receptance", db: bool = False) -> str:
    """``|H| (mm/N)``: the magnitude axis of an FRF in the case's units.

    A note that is not four units is quoted as it is; no note gives the quantity alone
    (``|H| (displacement / force)``).  With ``db`` the axis is
    ``20 log10 (|H| / H_ref)`` with ``H_ref = 1`` of the unit, stated on the label:
    ``|H|  (dB re 1 mm/N; displacement / force)``.
    """
    words, _ = _QUANTITY.get(quantity, _QUANTITY["receptance"])
    unit = frf_unit(units, quantity)
    if db:
        if unit is not None:
            return f"|H|  (dB re 1 {unit}; {words})"
        note = f"; case units: {units}" if units else ""
        return f"|H|  (dB re 1 {words}{note})"
    if not units:
        return f"|H|  ({words})"
    if unit is None:
        return f"|H|  ({words}; case units: {units})"
    return f"|H|  ({words}, {unit})"
