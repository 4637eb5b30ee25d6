r"""Signals of the ``analysis: transient:`` block: a load at a point, or the ground's motion, is
``amplitude`` times a shape of ``t``, one of

=============  ====================================  =========================================
shape          value at ``t``                        keys besides ``amplitude``
=============  ====================================  =========================================
``step``       1 for :math:`t \ge t_0`, else 0        ``start`` (:math:`t_0`, default 0)
``ramp``       :math:`\min((t - t_0)/T, 1)` after     ``start``, ``duration`` (:math:`T`)
               :math:`t_0`, else 0
``half-sine``  :math:`\sin(\pi (t - t_0)/T)` for      ``start``, ``duration``
               :math:`t_0 \le t \le t_0 + T`, else 0
``harmonic``   :math:`\cos(\omega t + \varphi)`       ``omega`` (rad/s), ``phase`` (rad)
``expression`` a safe expression of ``t`` and the     ``expression``
               parameters (:mod:`.expressions`)
``table``      linear interpolation in a table, 0     ``table`` (:mod:`.transient_files`)
               outside it
=============  ====================================  =========================================

Each shape is its own model and the shapes form a union discriminated by ``shape`` (``step``
when it is left out): a key that belongs to another shape is refused in one line that names
the shape it belongs to, so ``{point: p, expression: "sin(t)"}`` is refused with "add shape:
expression" instead of running as a unit step; any other key is refused as unknown.

:func:`waveform` gives a signal's values and its breakpoints, the instants where it or its
slope jumps (the start of a step; the start and end of a ramp, of a half-sine, of a table), so
that the integration can treat them exactly (:mod:`substruct.analysis.transient.loads`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any, Callable, ClassVar, Literal, Union

import numpy as np
from pydantic import BeforeValidator, Discriminator, Tag, model_validator

from substruct.case.errors import FieldError
from substruct.case.expressions import compile_expression
from substruct.case.fields import Number, Point, Positive, StrictModel
from substruct.case.transient_files import read_table

__all__ = ["SHAPES", "SHAPE_KEYS", "Step", "Ramp", "HalfSine", "Harmonic", "ExpressionShape", "TableShape",
           "Signal", "StepLoad", "RampLoad", "HalfSineLoad", "HarmonicLoad", "ExpressionLoad",
           "TableLoad", "TransientLoad", "AnySignal", "Waveform", "waveform", "load_values"]

#: The shapes a signal may have.
SHAPES = ("step", "ramp", "half-sine", "harmonic", "expression", "table")
#: The keys of each shape besides ``amplitude`` and ``shape`` (for "a key of shape: ..." hints).
SHAPE_KEYS = {"step": ("start",), "ramp": ("start", "duration"), "half-sine": ("start", "duration"),
         "harmonic": ("omega", "phase"), "expression": ("expression",), "table": ("table",)}


def _owners(key: str) -> list[str]:
    return [s for s, keys in SHAPE_KEYS.items() if key in keys]


def _known_shape(value: Any) -> Any:
    """Refuse an unknown ``shape`` at its key (before the union picks a member)."""
    if isinstance(value, dict) and "shape" in value and value["shape"] not in SHAPES:
        raise FieldError("shape", f"must be one of {', '.join(SHAPES)}", value["shape"])
    return value


class _Shape(StrictModel):
    """``amplitude`` times a shape of ``t`` (module docstring)."""

    SHAPE: ClassVar[str] = ""
    amplitude: Number = 1.0

    @model_validator(mode="before")
    @classmethod
    def _foreign_keys(cls, data: Any) -> Any:
        """Refuse a key of another shape, naming the shape it belongs to."""
        if not isinstance(data, dict):
            return data
        for key, value in data.items():
            owners = _owners(str(key))
            if key in cls.model_fields or not owners:
                continue  # an unknown key is refused by extra="forbid" (with "did you mean")
            shapes = " or ".join(owners)
            if "shape" not in data:
                raise FieldError(key, f"a signal without a shape is a step, which has no "
                                 f"{key}: add shape: {shapes}", value)
            raise FieldError(key, f"not a key of shape: {cls.SHAPE} ({key} belongs to "
                             f"shape: {shapes})", value)
        return data


class Step(_Shape):
    """1 from ``start`` on (the default shape)."""

    SHAPE: ClassVar[str] = "step"
    shape: Literal["step"] = "step"
    start: Number = 0.0


class Ramp(_Shape):
    """From 0 at ``start`` to 1 at ``start + duration``, then 1."""

    SHAPE: ClassVar[str] = "ramp"
    shape: Literal["ramp"]
    start: Number = 0.0
    duration: Positive


class HalfSine(_Shape):
    """One half-period of a sine from ``start``, lasting ``duration``."""

    SHAPE: ClassVar[str] = "half-sine"
    shape: Literal["half-sine"]
    start: Number = 0.0
    duration: Positive


class Harmonic(_Shape):
    """``cos(omega t + phase)`` from ``t = 0``."""

    SHAPE: ClassVar[str] = "harmonic"
    shape: Literal["harmonic"]
    omega: Number
    phase: Number = 0.0


class ExpressionShape(_Shape):
    """A safe expression of ``t`` and the case parameters."""

    SHAPE: ClassVar[str] = "expression"
    shape: Literal["expression"]
    expression: str


class TableShape(_Shape):
    """Linear interpolation in a ``.csv``/``.npz`` table, 0 outside it."""

    SHAPE: ClassVar[str] = "table"
    shape: Literal["table"]
    table: str


class StepLoad(Step):
    """A step force at ``point``."""

    point: Point


class RampLoad(Ramp):
    """A ramp force at ``point``."""

    point: Point


class HalfSineLoad(HalfSine):
    """A half-sine force pulse at ``point``."""

    point: Point


class HarmonicLoad(Harmonic):
    """A harmonic force at ``point``."""

    point: Point


class ExpressionLoad(ExpressionShape):
    """A force at ``point`` given by an expression of ``t``."""

    point: Point


class TableLoad(TableShape):
    """A force at ``point`` given by a table."""

    point: Point


def _shape_of(value: Any) -> Any:
    """The discriminator: the ``shape`` key (``step`` when left out)."""
    if isinstance(value, dict):
        return value.get("shape", "step")
    return getattr(value, "shape", None)


#: A signal (the ground's motion): one of the shapes, discriminated by ``shape``.
Signal = Annotated[Union[Annotated[Step, Tag("step")], Annotated[Ramp, Tag("ramp")],
                         Annotated[HalfSine, Tag("half-sine")],
                         Annotated[Harmonic, Tag("harmonic")],
                         Annotated[ExpressionShape, Tag("expression")],
                         Annotated[TableShape, Tag("table")]],
                   Discriminator(_shape_of), BeforeValidator(_known_shape)]
#: A force at a point: a signal with a ``point``.
TransientLoad = Annotated[Union[Annotated[StepLoad, Tag("step")],
                                Annotated[RampLoad, Tag("ramp")],
                                Annotated[HalfSineLoad, Tag("half-sine")],
                                Annotated[HarmonicLoad, Tag("harmonic")],
                                Annotated[ExpressionLoad, Tag("expression")],
                                Annotated[TableLoad, Tag("table")]],
                          Discriminator(_shape_of), BeforeValidator(_known_shape)]
#: Any signal, as the functions below take it.
AnySignal = Union[Step, Ramp, HalfSine, Harmonic, ExpressionShape, TableShape]


@dataclass(frozen=True)
class Waveform:
    """A signal ready to evaluate: ``values(t)`` and its ``breaks``, the instants where its
    value or its slope jumps (sorted)."""

    values: Callable[[np.ndarray], np.ndarray]
    breaks: list[float] = field(default_factory=list)
    #: where the value itself jumps (a subset of ``breaks``)
    jumps: list[float] = field(default_factory=list)


def waveform(sig: AnySignal, base_dir: Path, parameters: dict[str, float]) -> Waveform:
    """The signal's values and breakpoints (module docstring).

    Raises:
        ValueError: an expression that cannot be compiled, a table that cannot be read.
    """
    a = sig.amplitude
    if isinstance(sig, Step):
        t0 = sig.start
        return Waveform(lambda t: a * (np.asarray(t) - t0 >= 0).astype(float), [t0], [t0])
    if isinstance(sig, (Ramp, HalfSine)):
        t0, T = sig.start, sig.duration
        if isinstance(sig, Ramp):
            def ramp(t: np.ndarray) -> np.ndarray:
                return a * np.clip((np.asarray(t) - t0) / T, 0.0, 1.0)
            return Waveform(ramp, [t0, t0 + T])

        def half_sine(t: np.ndarray) -> np.ndarray:
            s = np.asarray(t) - t0
            return a * np.where((s >= 0) & (s <= T), np.sin(np.pi * np.clip(s, 0, T) / T), 0.0)
        return Waveform(half_sine, [t0, t0 + T])
    if isinstance(sig, Harmonic):
        w, phi = sig.omega, sig.phase
        return Waveform(lambda t: a * np.cos(w * np.asarray(t) + phi))
    if isinstance(sig, ExpressionShape):
        expr = compile_expression(sig.expression, ["t", *parameters])
        named = {k: parameters[k] for k in expr.names if k != "t"}

        def expression(t: np.ndarray) -> np.ndarray:
            t = np.asarray(t, dtype=float)
            return a * np.broadcast_to(expr(t=t, **named), t.shape).astype(float)
        return Waveform(expression)
    tt, vv = read_table(base_dir / sig.table)
    first, last = float(tt[0]), float(tt[-1])
    return Waveform(lambda t: a * np.interp(t, tt, vv, left=0.0, right=0.0), [first, last],
                    [x for x, v in ((first, vv[0]), (last, vv[-1])) if v != 0.0])


def load_values(sig: AnySignal, t: np.ndarray, base_dir: Path,
                parameters: dict[str, float]) -> np.ndarray:
    """The signal's values at the times ``t`` (module docstring).

    Raises:
        ValueError: a bad expression or table, or a value that is not finite.
    """
    out = np.asarray(waveform(sig, base_dir, parameters).values(np.asarray(t, dtype=float)),
                     dtype=float)
    if not np.all(np.isfinite(out)):
        raise ValueError("the load is not finite at some time")
    return out
