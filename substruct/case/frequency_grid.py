"""The frequency grid of a case (``analysis.frf.omega``, ``analysis.random.omega``): given
values, or a linear or logarithmic range, in rad/s, its size checked before it is made."""

from __future__ import annotations

from typing import Annotated, Any, Literal

import numpy as np
from pydantic import Field, model_validator

from substruct.case.errors import FieldError
from substruct.case.fields import MAX_FREQUENCIES, Count, NonNegative, Positive, StrictModel

__all__ = ["Omega"]


class Omega(StrictModel):
    """A frequency grid: ``values`` or ``start``/``stop``/``num``/``spacing`` (rad/s)."""

    values: Annotated[list[NonNegative], Field(min_length=1)] | None = None
    start: NonNegative | None = None
    stop: Positive | None = None
    num: Count | None = None
    spacing: Literal["linear", "log"] = "linear"

    @model_validator(mode="before")
    @classmethod
    def _list(cls, value: Any) -> Any:
        if isinstance(value, list):
            return {"values": value}
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return {"values": [value]}
        if not isinstance(value, dict):
            raise ValueError("omega is a list of frequencies (rad/s) or "
                             "{start: .., stop: .., num: .., spacing: linear|log}")
        if "values" in value:
            raise FieldError("values", "unknown key: give omega as a list instead", value)
        return value

    @model_validator(mode="after")
    def _grid(self) -> "Omega":
        if self.values is not None:
            if len(self.values) > MAX_FREQUENCIES:
                raise FieldError((), f"at most {MAX_FREQUENCIES} frequencies",
                                 len(self.values))
            return self
        if self.start is None or self.stop is None or self.num is None:
            key = next(k for k in ("start", "stop", "num") if getattr(self, k) is None)
            raise FieldError(key, "a frequency grid needs start, stop and num")
        if self.stop <= self.start:
            raise FieldError("stop", f"must be > start ({self.start:g})", self.stop)
        if self.spacing == "log" and self.start <= 0:
            raise FieldError("start", "must be > 0 for a log grid", self.start)
        if self.num > MAX_FREQUENCIES:
            raise FieldError("num", f"at most {MAX_FREQUENCIES} frequencies", self.num)
        return self

    def grid(self) -> np.ndarray:
        """The circular frequencies (rad/s)."""
        if self.values is not None:
            return np.asarray(self.values, dtype=float)
        if self.start is None or self.stop is None or self.num is None:  # refused by _grid
            raise ValueError("a frequency grid needs start, stop and num")
        if self.spacing == "log":
            return np.geomspace(self.start, self.stop, self.num)
        return np.linspace(self.start, self.stop, self.num)
