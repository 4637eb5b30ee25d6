"""The sizes of a convergence study: one tuple of levels per discretization
(:class:`StudyLevels`), presets, and the command-line form (:func:`parse_levels`)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

__all__ = ["StudyLevels", "parse_levels", "MAX_RITZ", "MAX_LEVEL_ELEMENTS"]

#: Largest number of sine functions a level may ask for (the mass and stiffness quadrature is
#: dense: about ``1250 n^2`` bytes, 1.3 GB at this size).
MAX_RITZ = 1024
#: Largest number of finite elements a level of the study may ask for (not the case file's own
#: limit on the elements of a rod or a mesh, ``MAX_ELEMENTS`` of the case layer).
MAX_LEVEL_ELEMENTS = 1_000_000


@dataclass(frozen=True)
class StudyLevels:
    """Sizes of each series.

    Attributes:
        assumed: numbers ``n`` of sine functions (``g = n``).
        fixed_g: also run the sines reduced to this many rod modes (levels ``n >= g``);
            ``None`` for no such series.
        enriched: numbers ``n`` of sines of the enriched basis (plus one static shape per point).
        fe_p1, fe_p2: target numbers of elements.
    """

    assumed: tuple[int, ...] = (4, 8, 16, 32, 64, 128, 256)
    fixed_g: int | None = 4
    enriched: tuple[int, ...] = (1, 2, 4, 6, 8, 12, 16, 24, 32, 48, 64)
    fe_p1: tuple[int, ...] = (8, 16, 32, 64, 128, 256, 512, 1024)
    fe_p2: tuple[int, ...] = (4, 8, 16, 32, 64, 128, 256, 512)

    PRESETS = ("quick", "default", "fine")

    @classmethod
    def preset(cls, name: str) -> "StudyLevels":
        """``"quick"`` (a few seconds, coarse), ``"default"``, ``"fine"`` (longer series)."""
        if name == "default":
            return cls()
        if name == "quick":
            return cls(assumed=(4, 8, 16, 32, 64), enriched=(1, 2, 4, 8, 16, 32),
                       fe_p1=(8, 16, 32, 64, 128, 256), fe_p2=(4, 8, 16, 32, 64, 128))
        if name == "fine":
            return cls(assumed=(4, 8, 16, 32, 64, 128, 256, 512),
                       enriched=(1, 2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64, 96),
                       fe_p1=(8, 16, 32, 64, 128, 256, 512, 1024, 2048),
                       fe_p2=(4, 8, 16, 32, 64, 128, 256, 512, 1024))
        raise ValueError(f"unknown levels preset {name!r}; expected one of {cls.PRESETS}")


_LEVEL_KEYS = {"assumed": "assumed", "am": "assumed", "enriched": "enriched",
               "p1": "fe_p1", "fe_p1": "fe_p1", "fe-p1": "fe_p1",
               "p2": "fe_p2", "fe_p2": "fe_p2", "fe-p2": "fe_p2", "g": "fixed_g",
               "fixed_g": "fixed_g"}


def parse_levels(text: str | None, *, fixed_g: int | None = 4) -> StudyLevels:
    """Levels from a command-line string.

    A preset name (``quick``, ``default``, ``fine``), or ``;``-separated items ``key=values``
    over the default levels (or over a preset named as the first item), ``values`` a comma
    list or ``a:b`` (powers of two from ``a`` up to ``b``), ``key`` one of ``assumed``,
    ``enriched``, ``p1``, ``p2``, ``g`` (``g=none`` drops the fixed-g series, an empty list
    drops a series)::

        "assumed=4:256; p1=8:1024; p2=4,8,16,32,64; g=4"
        "quick; g=none"

    Args:
        text: the string (``None`` or blank: the default levels).
        fixed_g: ``g`` of the fixed-g series unless ``text`` sets one (``None``: no such
            series); a case file's ``reduce: {modes: g}``.

    Raises:
        ValueError: an unknown key, a value that is not a positive integer, a range ``a:b``
            with ``a > b``, more than :data:`MAX_RITZ` functions or :data:`MAX_LEVEL_ELEMENTS`
            elements.
    """
    if fixed_g is not None:
        fixed_g = _positive_int(str(fixed_g), f"g={fixed_g}")
    items = [s.strip() for s in (text or "").split(";") if s.strip()]
    base = StudyLevels()
    if items and items[0] in StudyLevels.PRESETS:
        base = StudyLevels.preset(items.pop(0))
    changes: dict[str, Any] = {"fixed_g": fixed_g}
    for item in items:
        key, sep, value = item.partition("=")
        key = key.strip().lower()
        if not sep or key not in _LEVEL_KEYS:
            raise ValueError(f"levels: bad item {item!r}; expected key=values with key one of "
                             "assumed, enriched, p1, p2, g, or a preset " f"{StudyLevels.PRESETS}"
                             " first")
        field_name = _LEVEL_KEYS[key]
        value = value.strip()
        if field_name == "fixed_g":
            changes[field_name] = None if value.lower() in ("", "none", "off") else \
                _positive_int(value, item)
            continue
        if ":" in value:
            lo, hi = (_positive_int(v, item) for v in value.split(":", 1))
            if lo > hi:
                raise ValueError(f"levels: empty range {value!r} in {item!r} (a:b needs a <= b)")
            vals = [lo]
            while vals[-1] * 2 <= hi:
                vals.append(vals[-1] * 2)
        else:
            vals = [_positive_int(v, item) for v in value.split(",") if v.strip()]
        most = MAX_RITZ if field_name in ("assumed", "enriched") else MAX_LEVEL_ELEMENTS
        if vals and max(vals) > most:
            what = "functions" if most == MAX_RITZ else "elements"
            raise ValueError(f"levels: {max(vals)} in {item!r} is more than the {most} {what} "
                             "a level may have")
        changes[field_name] = tuple(sorted(set(vals)))
    return dataclasses.replace(base, **changes)


def _positive_int(text: str, item: str) -> int:
    try:
        v = int(text.strip())
    except ValueError:
        raise ValueError(f"levels: {text!r} in {item!r} is not an integer") from None
    if v < 1:
        raise ValueError(f"levels: {v} in {item!r} must be positive")
    return v
