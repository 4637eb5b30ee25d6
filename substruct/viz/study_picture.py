"""Pictures of a study (matplotlib, written atomically beside the study file):

* ``<name>_study_frequencies.png``: a grid's frequencies against its first parameter, one
  curve per mode (and, on a product grid, per value of a second parameter, lighter; a zip's
  samples are one curve);
* ``<name>_study_histogram.png``: random samples, a histogram of each collected frequency;
* ``<name>_study_tuning.png``: a two-parameter product grid with an FRF peak (a zip's points,
  on one line through the plane, make no map), the peak as a colour map over the two
  parameters (an absorber's stiffness and damping), the smallest marked, and
  optionally a closed-form optimum (Den Hartog's) marked beside it;
* ``<name>_study_tracked.png``: the modes followed through a one-parameter study
  (:mod:`substruct.viz.tracking_picture`).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from substruct.io.hdf5 import atomic_path
from substruct.studies.study_run import StudyResult
from substruct.studies.study_tracking import TrackedStudy
from substruct.viz.tracking_picture import tracking_figure

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["frequency_figure", "histogram_figure", "tuning_figure", "study_pictures",
           "is_product"]


def _save(fig: "Figure", path: Path) -> Path:
    with atomic_path(path, suffix=".png.part") as tmp:
        fig.savefig(tmp, format="png")
    return path


def is_product(table: np.ndarray) -> bool:
    """Whether the samples ``table`` (samples x parameters) are every combination of the
    parameters' distinct values, once each: a product grid (a zip is not, but for one sample
    or one parameter)."""
    if table.shape[1] < 2:
        return True
    size = int(np.prod([len(np.unique(column)) for column in table.T]))
    return size == len(table) == len(np.unique(table, axis=0))


def frequency_figure(result: StudyResult) -> "Figure":
    """Frequencies (rad/s) against the first parameter of a grid."""
    from matplotlib.figure import Figure

    freq = result.values["frequency"]
    x = result.table[:, 0]
    fig = Figure(figsize=(8, 5), dpi=110, layout="constrained")
    ax = fig.add_subplot()
    groups = [np.arange(len(x))]
    if result.table.shape[1] > 1 and is_product(result.table):
        others = result.table[:, 1:]
        keys = np.unique(others, axis=0)
        groups = [np.flatnonzero(np.all(others == key, axis=1)) for key in keys]
    for g, rows in enumerate(groups):
        order = rows[np.argsort(x[rows], kind="stable")]
        for i in range(freq.shape[1]):
            ax.plot(x[order], freq[order, i], "-", color=f"C{i}", lw=1.2,
                    alpha=1.0 if g == 0 else 0.35,
                    label=f"mode {i + 1}" if g == 0 else None)
    ax.set_xlabel(result.parameters[0])
    ax.set_ylabel("natural frequency (rad/s)")
    ax.set_title(f"{result.case_name}: frequencies against {result.parameters[0]}"
                 + (f" ({len(groups)} values of {', '.join(result.parameters[1:])})"
                    if len(groups) > 1 else ""))
    ax.legend()
    ax.grid(True, alpha=0.3)
    return fig


def histogram_figure(result: StudyResult) -> "Figure":
    """A histogram of each collected frequency over the random samples."""
    from matplotlib.figure import Figure

    freq = result.values["frequency"]
    n = freq.shape[1]
    fig = Figure(figsize=(4 * min(n, 4), 3.5 * ((n + 3) // 4)), dpi=110, layout="constrained")
    for i in range(n):
        ax = fig.add_subplot((n + 3) // 4, min(n, 4), i + 1)
        v = freq[:, i][np.isfinite(freq[:, i])]
        ax.hist(v, bins=max(5, int(np.sqrt(max(len(v), 1)))), color=f"C{i}")
        if len(v):
            ax.set_title(f"mode {i + 1}: {v.mean():.4g} +- {v.std():.2g} rad/s", fontsize=9)
        ax.set_xlabel("rad/s")
    fig.suptitle(f"{result.case_name}: {len(freq)} samples of "
                 f"{', '.join(result.parameters)}")
    return fig


def tuning_figure(result: StudyResult, peak: int = 0,
                  marked: tuple[float, float, str] | None = None) -> "Figure":
    """The FRF peak ``peak`` over a two-parameter grid (log colour scale), the smallest marked
    with a star and ``marked = (x, y, label)`` with a cross."""
    from matplotlib.colors import LogNorm
    from matplotlib.figure import Figure

    x, y = result.table[:, 0], result.table[:, 1]
    xs, ys = np.unique(x), np.unique(y)
    Z = np.full((len(ys), len(xs)), np.nan)
    Z[np.searchsorted(ys, y), np.searchsorted(xs, x)] = result.values["frf_peak"][:, peak]
    fig = Figure(figsize=(7.5, 5.5), dpi=110, layout="constrained")
    ax = fig.add_subplot()
    finite = Z[np.isfinite(Z)]
    norm = LogNorm(finite.min(), finite.max()) if finite.size and finite.min() > 0 else None
    mesh = ax.pcolormesh(xs, ys, Z, shading="nearest", norm=norm, cmap="viridis")
    fig.colorbar(mesh, ax=ax, label=f"peak |H| {result.peaks[peak] if result.peaks else ''}")
    k = int(np.nanargmin(result.values["frf_peak"][:, peak]))
    ax.plot(x[k], y[k], "*", color="w", mec="k", ms=14,
            label=f"grid optimum ({x[k]:.4g}, {y[k]:.4g})")
    if marked is not None:
        ax.plot(marked[0], marked[1], "X", color="r", mec="k", ms=11, label=marked[2])
    ax.set_xlabel(result.parameters[0])
    ax.set_ylabel(result.parameters[1])
    ax.set_title(f"{result.case_name}: FRF peak over {result.parameters[0]} x "
                 f"{result.parameters[1]}")
    ax.legend(loc="upper right", fontsize=8)
    return fig


def study_pictures(result: StudyResult, folder: str | os.PathLike,
                   marked: tuple[float, float, str] | None = None) -> list[Path]:
    """The pictures that apply to ``result``, written into ``folder``; their paths."""
    folder = Path(folder)
    stem = f"{result.case_name}_study"
    out = []
    if "frequency" in result.values and np.isfinite(result.values["frequency"]).any():
        if result.kind == "grid":
            out.append(_save(frequency_figure(result), folder / f"{stem}_frequencies.png"))
        else:
            out.append(_save(histogram_figure(result), folder / f"{stem}_histogram.png"))
    if (result.kind == "grid" and result.table.shape[1] == 2 and is_product(result.table)
            and "frf_peak" in result.values and np.isfinite(result.values["frf_peak"]).any()):
        out.append(_save(tuning_figure(result, marked=marked), folder / f"{stem}_tuning.png"))
    if isinstance(result.tracking, TrackedStudy):
        out.append(_save(tracking_figure(result.tracking, result.case_name),
                         folder / f"{stem}_tracked.png"))
    return out
