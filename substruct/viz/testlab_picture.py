r"""The test-lab pictures (matplotlib), drawn from a result's ``virtual_points``, ``tpa``:

* :func:`draw_consistency`: the consistency indicators of every transformed part against
  :math:`\omega` (overall sensor and impact consistency per virtual point, solid and dashed;
  the specific sensor and impact consistency of each channel, thin), 1 for a rigid adapter and
  a right channel table;
* :func:`draw_paths`: per validation target, the magnitudes of the path contributions
  :math:`|Y_{tc_j} f^{bl}_j|` stacked (filled bands; the top of each band a curve, the
  cumulative sum), with the magnitude of the prediction :math:`|\hat u_t|` (black), which is
  below the stack's top where paths cancel;
* :func:`draw_validation`: measured :math:`|u_t|` and predicted :math:`|\hat u_t|` at every
  target, and the relative error per frequency;
* :func:`draw_monte_carlo`: per chosen output/input pair of ``virtual_points.monte_carlo``
  (the first :data:`MAX_PAIRS`), the nominal coupled :math:`|H_{oi}(\omega)|` (black) and the
  percentiles of :math:`|H_{oi}|` over the noisy samples (thin lines), the band between the
  lowest and the highest percentile filled;
* :func:`draw_semm`: the model mixing's coherence against :math:`\omega`: each measured
  entry off the boundary (thin) and their mean, the validation indicator (black); with the
  extended form, each measured output's channel coherence (left out of the boundary and
  predicted by the others) on a second axis.

``plot_*`` write the figure as PNG (atomically) and return the path.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from substruct.io.hdf5 import atomic_path
from substruct.run.result import Result

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["draw_consistency", "draw_paths", "draw_validation", "plot_consistency",
           "plot_paths", "plot_validation", "draw_monte_carlo", "plot_monte_carlo",
           "draw_semm", "plot_semm",
           "MAX_TARGETS", "MAX_PAIRS"]

#: Targets drawn in the path-contribution picture (the first ones).
MAX_TARGETS = 6
#: Output/input pairs drawn in the Monte Carlo picture (the first ones, outputs first).
MAX_PAIRS = 6


def _omega(result: Result) -> np.ndarray:
    if result.frf is None:
        raise ValueError(f"result {result.case_name!r} holds no receptances (no frequencies)")
    return np.asarray(result.frf.omega, dtype=float)


def _save(fig: Figure, png_path: str | os.PathLike) -> Path:
    path = Path(png_path)
    with atomic_path(path, suffix=".png.part") as tmp:
        fig.savefig(tmp, format="png")
    return path


def draw_consistency(result: Result) -> Figure:
    """One axis per transformed part: the overall indicators per virtual point (sensors
    solid, impacts dashed) and each channel's specific indicator (thin), against omega.

    Raises:
        ValueError: the result holds no virtual points.
    """
    from matplotlib.figure import Figure

    if not result.virtual_points:
        raise ValueError(f"result {result.case_name!r} holds no virtual points")
    w = _omega(result)
    parts = list(result.virtual_points.items())
    fig = Figure(figsize=(10, 3.2 * len(parts) + 0.8), dpi=110, layout="constrained")
    axes = fig.subplots(len(parts), 1, sharex=True, squeeze=False)[:, 0]
    for ax, (part, ind) in zip(axes, parts):
        for c, (point, v) in enumerate(ind.overall_u.items()):
            ax.plot(w, v, color=f"C{c}", lw=2, label=f"{point}: sensors (overall)")
            ax.plot(w, ind.overall_f[point], color=f"C{c}", lw=2, ls="--",
                    label=f"{point}: impacts (overall)")
        for name, v in ind.specific_u.items():
            ax.plot(w, v, color="0.45", lw=0.7, label=f"_sensor {name}")
        for name, v in ind.specific_f.items():
            ax.plot(w, v, color="0.7", lw=0.7, ls=":", label=f"_impact {name}")
        ax.set_title(f"consistency of the virtual points of {part} (thin: each channel)")
        ax.set_ylabel("consistency")
        ax.set_ylim(-0.02, 1.05)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize="small", loc="lower left")
    axes[-1].set_xlabel("\u03c9 (rad/s)")
    return fig


def plot_consistency(result: Result, png_path: str | os.PathLike) -> Path:
    """:func:`draw_consistency` written as PNG; return the path."""
    return _save(draw_consistency(result), png_path)


def _tpa(result: Result):  # noqa: ANN202 - the TpaResult of the result
    if result.tpa is None:
        raise ValueError(f"result {result.case_name!r} holds no transfer path analysis")
    return result.tpa


def _positive(v: np.ndarray) -> np.ndarray:
    return np.where(v > 0, v, np.nan)


def draw_paths(result: Result, max_targets: int = MAX_TARGETS) -> Figure:
    """Per target (the first ``max_targets``), the path contributions' magnitudes stacked
    over omega and the prediction's magnitude (module docstring).

    Raises:
        ValueError: the result holds no transfer path analysis.
    """
    from matplotlib.figure import Figure

    tpa = _tpa(result)
    w = _omega(result)
    n = min(len(tpa.targets), max(1, int(max_targets)))
    fig = Figure(figsize=(10, 2.8 * n + 0.8), dpi=110, layout="constrained")
    axes = fig.subplots(n, 1, sharex=True, squeeze=False)[:, 0]
    for t, ax in enumerate(axes):
        mags = np.abs(tpa.contributions[:, t, :])          # n_omega x n_c
        top = np.cumsum(mags, axis=1)
        below = np.zeros(len(w))
        for j, path in enumerate(tpa.interface):
            ax.fill_between(w, below, top[:, j], color=f"C{j % 10}", alpha=0.55, lw=0)
            ax.plot(w, top[:, j], color=f"C{j % 10}", lw=0.8, label=path)
            below = top[:, j]
        ax.plot(w, np.abs(tpa.predicted[:, t]), color="k", lw=1.5,
                label="|prediction| (sum with phases)")
        ax.set_yscale("log")
        first = top[:, 0][top[:, 0] > 0]
        if first.size:  # the smallest path would otherwise stretch the log axis
            ax.set_ylim(bottom=float(first.min()) / 3)
        ax.set_title(f"path contributions at {tpa.targets[t]} (stacked magnitudes)")
        ax.set_ylabel("|response|")
        ax.grid(True, alpha=0.3, which="both")
    axes[0].legend(fontsize="small", ncol=2, loc="upper right")
    if len(tpa.targets) > n:
        axes[-1].text(0.01, 0.02, f"{len(tpa.targets) - n} more target(s) not drawn",
                      transform=axes[-1].transAxes, fontsize="small")
    axes[-1].set_xlabel("\u03c9 (rad/s)")
    return fig


def plot_paths(result: Result, png_path: str | os.PathLike) -> Path:
    """:func:`draw_paths` written as PNG; return the path."""
    return _save(draw_paths(result), png_path)


def draw_validation(result: Result) -> Figure:
    """Measured (solid) and predicted (dashed) response magnitudes at every target, and the
    relative validation error, against omega.

    Raises:
        ValueError: the result holds no transfer path analysis.
    """
    from matplotlib.figure import Figure

    tpa = _tpa(result)
    w = _omega(result)
    fig = Figure(figsize=(10, 7), dpi=110, layout="constrained")
    ax, ax_err = fig.subplots(2, 1, sharex=True, height_ratios=[2, 1])
    for t, name in enumerate(tpa.targets):
        ax.plot(w, _positive(np.abs(tpa.measured[:, t])), color=f"C{t % 10}", lw=1.6,
                label=f"{name} measured")
        ax.plot(w, _positive(np.abs(tpa.predicted[:, t])), color=f"C{t % 10}", lw=1.2,
                ls="--", label=f"{name} predicted")
    ax.set_yscale("log")
    ax.set_ylabel("|response|")
    if tpa.transmissibility is not None:
        ax.set_title(f"operational TPA: condition {tpa.validation_condition} predicted by "
                     f"the transmissibility from {len(tpa.indicators)} indicator(s)")
    else:
        ax.set_title(f"on-board validation: blocked forces ({tpa.method}) at "
                     f"{len(tpa.interface)} interface coordinate(s)")
    ax.grid(True, alpha=0.3, which="both")
    ax.legend(fontsize="small", ncol=2)
    ax_err.plot(w, _positive(tpa.error), color="k", lw=1.2, label="relative error")
    ax_err.set_yscale("log")
    ax_err.set_ylabel("|u\u0302 - u| / |u|")
    ax_err.grid(True, alpha=0.3, which="both")
    ax_err.set_xlabel("\u03c9 (rad/s)")
    return fig


def plot_validation(result: Result, png_path: str | os.PathLike) -> Path:
    """:func:`draw_validation` written as PNG; return the path."""
    return _save(draw_validation(result), png_path)


def draw_monte_carlo(result: Result, max_pairs: int = MAX_PAIRS) -> Figure:
    """Per output/input pair of the Monte Carlo study (the first ``max_pairs``, output by
    output), the nominal magnitude and the percentile band of the magnitude over the samples,
    against omega (module docstring).  Lines are labelled ``nominal |H|`` and
    ``<q>th percentile``.

    Raises:
        ValueError: the result holds no Monte Carlo study.
    """
    from matplotlib.figure import Figure

    mc = result.monte_carlo
    if mc is None:
        raise ValueError(f"result {result.case_name!r} holds no Monte Carlo study")
    w = np.asarray(mc.omega, dtype=float)
    pairs = [(o, i) for o in range(len(mc.outputs)) for i in range(len(mc.inputs))]
    n = min(len(pairs), max(1, int(max_pairs)))
    fig = Figure(figsize=(10, 2.8 * n + 0.8), dpi=110, layout="constrained")
    axes = fig.subplots(n, 1, sharex=True, squeeze=False)[:, 0]
    q = list(mc.percentiles)
    for ax, (o, i) in zip(axes, pairs):
        if q:
            lo, hi = int(np.argmin(q)), int(np.argmax(q))
            ax.fill_between(w, mc.bands[lo][:, o, i], mc.bands[hi][:, o, i], color="C0",
                            alpha=0.3, lw=0, label=f"{q[lo]:g} to {q[hi]:g}th percentiles")
            for k, p in enumerate(q):
                ax.plot(w, mc.bands[k][:, o, i], color="C0", lw=0.7,
                        ls="-" if k in (lo, hi) else "--", label=f"{p:g}th percentile")
        ax.plot(w, _positive(np.abs(mc.nominal[:, o, i])), color="k", lw=1.4,
                label="nominal |H|")
        ax.set_yscale("log")
        ax.set_title(f"{mc.outputs[o]} / {mc.inputs[i]}: noise {mc.level:g} (relative), "
                     f"{mc.samples} samples, seed {mc.seed}")
        ax.set_ylabel("|H|")
        ax.grid(True, alpha=0.3, which="both")
    axes[0].legend(fontsize="small", loc="upper right")
    if len(pairs) > n:
        axes[-1].text(0.01, 0.02, f"{len(pairs) - n} more pair(s) not drawn",
                      transform=axes[-1].transAxes, fontsize="small")
    axes[-1].set_xlabel("\u03c9 (rad/s)")
    return fig


def plot_monte_carlo(result: Result, png_path: str | os.PathLike) -> Path:
    """:func:`draw_monte_carlo` written as PNG; return the path."""
    return _save(draw_monte_carlo(result), png_path)


def draw_semm(result: Result) -> Figure:
    """The coherence of the mixed model with the measurement (module docstring): lines
    labelled ``<output> / <input>`` per validation entry, ``validation indicator``, and, on
    the second axis of the extended form, one per measured output.

    Raises:
        ValueError: the result holds no model mixing.
    """
    from matplotlib.figure import Figure

    semm = result.semm
    if semm is None:
        raise ValueError(f"result {result.case_name!r} holds no model mixing")
    w = _omega(result)
    chan = semm.channel_coherence
    fig = Figure(figsize=(10, 7 if chan is not None else 4.5), dpi=110, layout="constrained")
    axes = fig.subplots(2 if chan is not None else 1, 1, sharex=True, squeeze=False)[:, 0]
    ax = axes[0]
    rows, cols = np.nonzero(semm.validation)
    for o, i in zip(rows, cols):
        ax.plot(w, semm.coherence[:, o, i], lw=0.7, alpha=0.7,
                label=f"{semm.measured_outputs[o]} / {semm.measured_inputs[i]}")
    if rows.size:
        ax.plot(w, semm.indicator, color="k", lw=1.6, label="validation indicator")
    else:
        ax.text(0.5, 0.5, "every measured entry is on the boundary: nothing validates",
                transform=ax.transAxes, ha="center")
    ax.set_ylim(-0.02, 1.05)
    ax.set_ylabel("coherence")
    ax.set_title(f"model mixing ({semm.form}): boundary {len(semm.boundary_outputs)} x "
                 f"{len(semm.boundary_inputs)} of {len(semm.measured_outputs)} x "
                 f"{len(semm.measured_inputs)} measured")
    ax.grid(True, alpha=0.3)
    if rows.size:
        ax.legend(fontsize="small", ncol=2)
    if chan is not None:
        ax2 = axes[1]
        for j, name in enumerate(semm.measured_outputs):
            ax2.plot(w, chan[:, j], lw=1.1, label=name)
        ax2.set_ylim(-0.02, 1.05)
        ax2.set_ylabel("channel coherence")
        ax2.set_title("each measured output left out of the boundary and predicted")
        ax2.grid(True, alpha=0.3)
        ax2.legend(fontsize="small", ncol=2)
    axes[-1].set_xlabel("\u03c9 (rad/s)")
    return fig


def plot_semm(result: Result, png_path: str | os.PathLike) -> Path:
    """:func:`draw_semm` written as PNG; return the path."""
    return _save(draw_semm(result), png_path)
