"""What a convergence study produces, as plain data (HDF5 round trip in
:mod:`substruct.io.convergence_report`): one :class:`SeriesResult` per discretization,
grouped by version of the system (:class:`VariantResult`) in a :class:`ConvergenceResult`."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["SeriesResult", "VariantResult", "ConvergenceResult"]


@dataclass
class SeriesResult:
    """One discretization refined: plain arrays over levels (rows) and modes (columns).

    Attributes:
        key: ``"assumed"``, ``"assumed-g4"``, ``"enriched"``, ``"fe-p1"``, ``"fe-p2"``.
        label: for tables and legends.
        level: the size parameter (``n`` or target number of elements).
        dofs: Ritz functions or free FE DOFs of the rod (before modal reduction).
        coupled_dofs: coordinates of the assembled system.
        seconds: wall time of each level (build, assemble, solve; a rod model reused from
            another series or variant is charged the time its build took).
        eigenvalues: complex roots ``(levels, modes)`` (``i omega`` if undamped; NaN if the
            level has fewer roots).
        rel_error: ``|lambda - lambda_ref| / |lambda_ref|`` (``inf`` where the level has fewer
            roots than asked, NaN for a rigid-body reference root).
        rate: fitted order ``p`` per mode (``e ~ N^-p``; NaN if fewer than 2 levels fit).
        fit_mask: levels used in each fit ``(levels, modes)``.
        theory_rate: the expected order (NaN when there is none to state).
        extrapolated_difference: per mode, relative difference between this series'
            own Richardson extrapolation (with its fitted order) and the reference limit: the
            evidence that it converges to the same limit (NaN if the order is below 0.5).
    """

    key: str
    label: str
    level: np.ndarray
    dofs: np.ndarray
    coupled_dofs: np.ndarray
    seconds: np.ndarray
    eigenvalues: np.ndarray
    rel_error: np.ndarray
    rate: np.ndarray
    fit_mask: np.ndarray
    theory_rate: float
    extrapolated_difference: np.ndarray

    @property
    def omega(self) -> np.ndarray:
        """``|lambda|`` (rad/s), the natural frequencies of an undamped system."""
        return np.abs(self.eigenvalues)

    @property
    def worst_error(self) -> np.ndarray:
        """Largest error over the modes at each level (rigid-body NaN entries ignored; ``inf``
        if a root is missing)."""
        e = np.where(np.isnan(self.rel_error), -np.inf, self.rel_error)
        out = e.max(axis=1)
        return np.where(np.isneginf(out), np.nan, out)


@dataclass
class VariantResult:
    """The study of one version of the system (with constraints, without, bare rod).

    Attributes:
        key: ``"constrained"``, ``"unconstrained"`` or ``"bare"``.
        label: e.g. ``"with eq52"``.
        series: by series key, in run order.
        limit_finest: roots of the finest reference level.
        limit_richardson: Richardson estimate (NaN if the reference series has one level).
        limit: the reference used for the errors.
        limit_difference: :math:`\\delta_j`, relative difference between the two estimates.
        limit_source: e.g. ``"fe-p2 n_el=512 (Richardson with 256, order 4)"``.
        reference_order: observed order of the reference series from three levels, with no
            assumed limit (the finest triple whose last difference exceeds 10 error_floor).
        floor: error floor of the rate fits per mode.
        seconds: wall time of the variant.
    """

    key: str
    label: str
    series: dict[str, SeriesResult]
    limit_finest: np.ndarray
    limit_richardson: np.ndarray
    limit: np.ndarray
    limit_difference: np.ndarray
    limit_source: str
    reference_order: np.ndarray
    floor: np.ndarray
    seconds: float


@dataclass
class ConvergenceResult:
    """Everything a convergence study produced (plain data, HDF5 round trip).

    Attributes:
        name: system name.
        n_modes: modes studied.
        variants: by variant key.
        levels: the :class:`StudyLevels` as a dict.
        seconds: total wall time.
        attrs: settings (reference, fit points, floor, ...).
    """

    name: str
    n_modes: int
    variants: dict[str, VariantResult]
    levels: dict[str, Any]
    seconds: float
    attrs: dict[str, Any] = field(default_factory=dict)
