r"""The ``analysis: transient:`` block of a case file: the constrained transient response
(eqs 5, 10; :mod:`substruct.analysis.transient`).

Loads act at points; each is ``amplitude`` times a shape of ``t`` (a signal); ``base`` moves
grounded supports by a signal (their acceleration or displacement):

=============  ===============================================================================
shape          value at ``t``
=============  ===============================================================================
``step``       1 for :math:`t \ge t_0` (``start``), else 0
``ramp``       :math:`\min((t - t_0)/T, 1)` after ``start``, ``T`` the ``duration``
``half-sine``  :math:`\sin(\pi (t - t_0)/T)` for :math:`t_0 \le t \le t_0 + T`, else 0
``harmonic``   :math:`\cos(\omega t + \varphi)` (``omega`` rad/s, ``phase`` rad)
``expression`` a safe expression of ``t`` and the parameters (:mod:`substruct.case.expressions`)
``table``      linear interpolation in a CSV (two columns ``t, value``) or NPZ (arrays ``t``
               and ``value``) file: finite values, strictly increasing times, at most
               :data:`MAX_TABLE_ROWS` rows; 0 outside the table
=============  ===============================================================================
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

import numpy as np
from pydantic import Field, model_validator

from substruct.case.errors import FieldError
from substruct.case.expressions import compile_expression
from substruct.case.npz_files import npz_members, read_npz
from substruct.case.fields import (
    MEMORY_LIMIT,
    Count,
    Number,
    Point,
    Positive,
    StrictModel,
    gigabytes,
)

__all__ = ["MAX_STEPS", "MAX_TABLE_ROWS", "Signal", "TransientLoad", "BaseExcitation", "InitialState", "TransientAnalysis",
           "load_values", "read_table"]

#: The most steps a run may take.
MAX_STEPS = 10_000_000
#: The most rows a load table may have.
MAX_TABLE_ROWS = 1_000_000
#: Default tolerance of the checks (as substruct.analysis.results.DEFAULT_TOLERANCE).
TOLERANCE = 1e-6


class Signal(StrictModel):
    """``amplitude`` times a shape of ``t`` (module docstring)."""

    amplitude: Number = 1.0
    shape: Literal["step", "ramp", "half-sine", "harmonic", "expression", "table"] = "step"
    start: Number = 0.0
    duration: Positive | None = None
    omega: Number = 0.0
    phase: Number = 0.0
    expression: str | None = None
    table: str | None = None

    @model_validator(mode="after")
    def _complete(self) -> "Signal":
        if self.shape in ("ramp", "half-sine") and self.duration is None:
            raise FieldError("duration", f"a {self.shape} load needs a duration")
        if self.shape == "expression":
            if self.expression is None:
                raise FieldError("expression", "an expression load needs an expression of t")
        if self.shape == "table" and self.table is None:
            raise FieldError("table", "a table load needs a CSV or NPZ file")
        return self


class TransientLoad(Signal):
    """A force at ``point``: ``amplitude`` times a shape of ``t`` (module docstring)."""

    point: Point


class BaseExcitation(StrictModel):
    r"""A prescribed ground motion :math:`g(t)` of the supports at the points ``at``: each
    point must be held by a constraint row on it alone (``terms: {p: c}``), which becomes
    :math:`c\, u(p) = \text{rhs} + c\, g(t)` (:mod:`substruct.analysis.transient_base`).
    Give the ``acceleration`` :math:`\ddot g` (the ground starts at rest) or the
    ``displacement`` :math:`g`, each a signal as a load's."""

    at: Annotated[list[Point], Field(min_length=1)]
    acceleration: Signal | None = None
    displacement: Signal | None = None

    @model_validator(mode="after")
    def _one(self) -> "BaseExcitation":
        if (self.acceleration is None) == (self.displacement is None):
            raise FieldError("acceleration", "give the ground's acceleration or its "
                             "displacement (one of the two)")
        return self

    @property
    def kind(self) -> str:
        """``"acceleration"`` or ``"displacement"``."""
        return "acceleration" if self.acceleration is not None else "displacement"

    @property
    def signal(self) -> Signal:
        """The signal given."""
        sig = self.acceleration if self.acceleration is not None else self.displacement
        assert sig is not None
        return sig


def read_table(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """``(t, value)`` of a load table (CSV ``t, value`` rows or NPZ arrays ``t``, ``value``).

    Raises:
        ValueError: not a regular file, too many rows, non-finite values, times not strictly
            increasing.
    """
    if not path.is_file():
        raise ValueError(f"no such table file {path.name!r}")
    if path.suffix == ".npz":
        members = npz_members(path)
        if "t" not in members or "value" not in members:
            raise ValueError("an NPZ table needs arrays t and value")
        if max(members["t"].count, members["value"].count) > MAX_TABLE_ROWS:
            raise ValueError(f"more than {MAX_TABLE_ROWS} rows")
        z = read_npz(path, ["t", "value"], {"t": np.float64, "value": np.float64})
        t, v = z["t"].ravel(), z["value"].ravel()
    elif path.suffix == ".csv":
        if path.stat().st_size > 64 * MAX_TABLE_ROWS:
            raise ValueError(f"more than {MAX_TABLE_ROWS} rows")
        data = np.loadtxt(path, delimiter=",", ndmin=2, comments="#")
        if data.shape[1] != 2:
            raise ValueError("a CSV table has two columns, t and value")
        t, v = data[:, 0], data[:, 1]
    else:
        raise ValueError("a table is a .csv or .npz file")
    if t.size != v.size or t.size < 2 or t.size > MAX_TABLE_ROWS:
        raise ValueError(f"a table needs 2 to {MAX_TABLE_ROWS} rows of t and value")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(v))):
        raise ValueError("a table with a value that is not finite (NaN or inf)")
    if np.any(np.diff(t) <= 0):
        k = int(np.flatnonzero(np.diff(t) <= 0)[0])
        raise ValueError(f"times not strictly increasing at row {k + 1} (t = {t[k + 1]:g} "
                         f"after {t[k]:g})")
    return t, v


def load_values(load: Signal, t: np.ndarray, base_dir: Path,
                parameters: dict[str, float]) -> np.ndarray:
    """The load's values at the times ``t`` (module docstring)."""
    s = t - load.start
    T = load.duration or 1.0
    if load.shape == "step":
        shape = (s >= 0).astype(float)
    elif load.shape == "ramp":
        shape = np.clip(s / T, 0.0, 1.0)
    elif load.shape == "half-sine":
        shape = np.where((s >= 0) & (s <= T), np.sin(np.pi * np.clip(s, 0, T) / T), 0.0)
    elif load.shape == "harmonic":
        shape = np.cos(load.omega * t + load.phase)
    elif load.shape == "expression":
        expr = compile_expression(str(load.expression), ["t", *parameters])
        shape = np.broadcast_to(expr(t=t, **{k: parameters[k] for k in expr.names if k != "t"}),
                                t.shape).astype(float)
    else:
        tt, vv = read_table(base_dir / str(load.table))
        shape = np.interp(t, tt, vv, left=0.0, right=0.0)
    out = load.amplitude * shape
    if not np.all(np.isfinite(out)):
        raise ValueError("the load is not finite at some time")
    return out


class InitialState(StrictModel):
    """The initial displacement: ``scale`` times coupled mode ``mode`` (1-based, M-normalized);
    the initial velocity likewise (``velocity_mode``, ``velocity_scale``)."""

    mode: Count | None = None
    scale: Number = 1.0
    velocity_mode: Count | None = None
    velocity_scale: Number = 1.0


class TransientAnalysis(StrictModel):
    """Time histories (eqs 5, 10) from 0 to ``t_end`` with the constant step ``dt``."""

    t_end: Positive
    dt: Positive
    integrator: Literal["newmark", "generalized-alpha"] = "newmark"
    rho_inf: Annotated[float, Field(ge=0, le=1)] = 0.9
    method: Literal["generalized-inverse", "null-space", "modal"] = "generalized-inverse"
    check: list[Literal["generalized-inverse", "null-space", "modal"]] = Field(
        default_factory=list)
    tolerance: Positive = TOLERANCE
    loads: list[TransientLoad] = Field(default_factory=list)
    #: a prescribed ground motion of grounded supports
    base: BaseExcitation | None = None
    initial: InitialState = Field(default_factory=InitialState)
    outputs: list[Point] = Field(default_factory=list)
    constraint_forces: bool = True
    #: record every this many steps
    every: Annotated[int, Field(ge=1, le=MAX_STEPS)] = 1
    #: keep the full displacement field every this many steps (0: never)
    field_every: Annotated[int, Field(ge=0, le=MAX_STEPS)] = 0
    #: modes of the modal form (default: all of a small model)
    modal_count: Count | None = None

    @property
    def steps(self) -> int:
        """The number of steps, ``ceil(t_end / dt)`` (to rounding)."""
        return int(np.ceil(self.t_end / self.dt - 1e-9))

    @model_validator(mode="after")
    def _sizes(self) -> "TransientAnalysis":
        if self.dt > self.t_end:
            raise FieldError("dt", f"must be at most t_end ({self.t_end:g})", self.dt)
        if self.t_end / self.dt > MAX_STEPS:
            raise FieldError("dt", f"t_end / dt is more than {MAX_STEPS} steps", self.dt)
        samples = self.steps // self.every + 2
        need = 8.0 * samples * (3 * len(self.outputs) + 6) * (1 + len(self.check))
        if need > MEMORY_LIMIT:
            raise FieldError("every", f"{samples} recorded samples of {len(self.outputs)} "
                             f"outputs would need about {gigabytes(need)}, more than the "
                             f"{gigabytes(MEMORY_LIMIT)} allowed: record every more steps",
                             self.every)
        return self
