r"""The samples of a study: the parameter table of a grid or of random draws, and the
``--set`` overrides that give one sample its values.

A grid of axes :math:`v^{(1)}, \dots, v^{(p)}` is their Cartesian product (the first axis varies
slowest, ``itertools.product`` order) or, zipped, the rows :math:`(v^{(1)}_s, \dots, v^{(p)}_s)`.
Random samples are drawn once, on the client, from ``Generator(PCG64(seed))``, one parameter
after the other (all ``count`` values of the first, then the second, ...):

.. math::  x = \mu + \sigma_x \xi, \qquad x = \tilde x\, e^{\sigma \xi}, \qquad
           x = a + (b - a)\, u,

for normal, lognormal (median :math:`\tilde x`) and uniform, :math:`\xi \sim N(0, 1)`,
:math:`u \sim U[0, 1)`.  The table does not depend on where the samples run.
"""

from __future__ import annotations

import itertools

import numpy as np

from substruct.case.study import GridAxis, RandomParameter, StudySpec

__all__ = ["axis_values", "samples", "overrides_of", "number_text"]


def axis_values(axis: GridAxis) -> np.ndarray:
    """The values of one grid axis (``values`` as given, or ``start, stop, num``)."""
    if axis.values is not None:
        return np.asarray(axis.values, dtype=float)
    start, stop, num = float(axis.start or 0.0), float(axis.stop or 0.0), int(axis.num or 1)
    if axis.spacing == "log":
        return np.geomspace(start, stop, num)
    return np.linspace(start, stop, num)


def _draw(rng: np.random.Generator, p: RandomParameter, count: int) -> np.ndarray:
    if p.distribution == "normal":
        return rng.normal(float(p.mean or 0.0), float(p.std or 0.0), count)
    if p.distribution == "lognormal":
        return float(p.median or 1.0) * np.exp(float(p.sigma or 0.0)
                                               * rng.standard_normal(count))
    return rng.uniform(float(p.low or 0.0), float(p.high or 0.0), count)


def samples(spec: StudySpec) -> tuple[list[str], np.ndarray]:
    """The parameter names and the ``(samples, parameters)`` table of values of a study."""
    names = spec.parameter_names()
    if spec.random is not None:
        rng = np.random.Generator(np.random.PCG64(int(spec.random.seed)))
        count = int(spec.random.count)
        columns = [_draw(rng, p, count) for p in spec.random.parameters]
        return names, np.column_stack(columns)
    assert spec.grid is not None
    axes = [axis_values(a) for a in spec.grid.parameters]
    if spec.grid.combine == "zip":
        n = min(len(a) for a in axes)
        return names, np.column_stack([a[:n] for a in axes])
    rows = list(itertools.product(*axes))
    return names, np.array(rows, dtype=float).reshape(len(rows), len(axes))


def number_text(value: float) -> str:
    """``value`` as text that reads back to the same float (``repr``), with a decimal point
    so that YAML reads it as a number (``1e-05`` is text to YAML 1.1, ``1.0e-05`` a float)."""
    text = repr(float(value))
    mantissa, e, exponent = text.partition("e")
    if e and "." not in mantissa:
        text = f"{mantissa}.0e{exponent}"
    return text


def overrides_of(names: list[str], row: np.ndarray) -> list[str]:
    """The ``--set`` overrides ``parameters.<name>=<value>`` of one sample."""
    return [f"parameters.{n}={number_text(v)}" for n, v in zip(names, row)]
