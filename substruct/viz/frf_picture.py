"""The receptance picture (matplotlib): magnitude (log axis, or decibels with
``analysis.frf.magnitude: db``) and phase against ``omega``, one curve per output/input pair,
natural frequencies marked; a single frequency is drawn as matrices of ``|H|`` and phase with
the values written in."""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from substruct.analysis.frf.stream import StreamedArray
from substruct.case.yaml_io import load_yaml
from substruct.io.hdf5 import atomic_path
from substruct.run.result import Result
from substruct.viz.units import frf_axis_label

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["plot_frf", "draw_frf", "MAX_FRF_CURVES", "MAGNITUDES", "case_magnitude", "decibels"]

#: Output/input pairs drawn by default (the first ones, outputs varying slowest).
MAX_FRF_CURVES = 9
#: Grids of at most this many frequencies are drawn with a marker at each.
SPARSE_GRID = 60
#: How the magnitude is drawn: ``log`` (|H| on a log axis) or ``db`` (20 log10 |H| re 1 unit).
MAGNITUDES = ("log", "db")


def decibels(H: np.ndarray) -> np.ndarray:
    r"""The level of ``|H|`` in decibels re 1 unit, NaN where ``H = 0``:

    .. math::  L = 20 \log_{10} (|H| / H_{ref}), \qquad H_{ref} = 1
    """
    mag = np.abs(np.asarray(H))
    with np.errstate(divide="ignore"):
        return np.where(mag > 0, 20.0 * np.log10(np.where(mag > 0, mag, 1.0)), np.nan)


def case_magnitude(result: Result) -> str:
    """``analysis.frf.magnitude`` of the case the result was computed from (its stored YAML
    text); ``"log"`` when the case does not say, or cannot be read."""
    if not result.case_yaml:
        return "log"
    try:
        value = load_yaml(result.case_yaml, result.case_name)["analysis"]["frf"] \
            .get("magnitude", "log")
    except Exception:  # a hand-made result, or a case text that is not the usual mapping
        return "log"
    return value if value in MAGNITUDES else "log"


def draw_frf(result: Result, *, max_curves: int = MAX_FRF_CURVES,
             magnitude: str | None = None) -> Figure:
    """The receptance figure of ``result``, drawn and not written (see :func:`plot_frf`; the
    public :func:`substruct.viz.plotting.frf_figure` returns it and writes it on request).

    ``magnitude``: ``"log"`` or ``"db"`` (:func:`decibels`); ``None`` takes the case's
    ``analysis.frf.magnitude`` (:func:`case_magnitude`).

    Raises:
        ValueError: the result holds no FRF, its array does not match its frequencies, or an
            unknown ``magnitude``.
    """
    from matplotlib.figure import Figure

    frf = result.frf
    if frf is None:
        raise ValueError(f"result {result.case_name!r} holds no FRF to plot")
    # a streamed output (never whole in memory) gives its selections
    H = frf.H if isinstance(frf.H, StreamedArray) else np.asarray(frf.H)
    omega = np.asarray(frf.omega, dtype=float)
    if H.ndim != 3 or H.shape[0] != omega.size or omega.size == 0:
        raise ValueError(f"FRF array has shape {H.shape}, expected ({omega.size}, n_out, n_in)")
    db = (case_magnitude(result) if magnitude is None else magnitude) == "db"
    if magnitude not in (None, *MAGNITUDES):
        raise ValueError(f"unknown magnitude {magnitude!r}; expected log or db")
    label = frf_axis_label(result.attrs.get("units"), getattr(frf, "quantity", "receptance"),
                           db=db)
    fig = Figure(figsize=(11, 7.5), dpi=110, layout="constrained")
    title = f"{result.case_name}: receptance H ({frf.method})"
    notes = [f"{m}: {v:.1e}" for m, v in frf.agreement.items()]
    sub = ("agreement " + ", ".join(notes) + "; " if notes else "") + \
        f"constraint residual {frf.constraint_residual:.1e}"
    if omega.size == 1:
        _frf_matrix(fig, frf, H[0], float(omega[0]), label, db)
    else:
        _frf_curves(fig, result, frf, H, omega, max_curves, label, db)
    fig.suptitle(f"{title}\n{sub}", fontsize=12)
    return fig


def plot_frf(result: Result, png_path: str | os.PathLike, *,
             max_curves: int = MAX_FRF_CURVES, magnitude: str | None = None) -> Path:
    """Receptance magnitude (log axis, or dB re 1 unit with ``magnitude="db"`` or the case's
    ``analysis.frf.magnitude: db``) and phase against ``omega``, one curve per output/input
    pair.

    At most ``max_curves`` pairs are drawn (the first ones, outputs varying slowest; the legend
    says how many are left out); natural frequencies of ``result.modes`` inside the range are
    marked.  A single-frequency grid is drawn as matrices of ``|H|`` and phase with the values
    written in.  The PNG is written atomically; return its path.

    Raises:
        ValueError: the result holds no FRF.
    """
    fig = draw_frf(result, max_curves=max_curves, magnitude=magnitude)
    path = Path(png_path)
    with atomic_path(path, suffix=".png.part") as tmp:
        fig.savefig(tmp, format="png")
    return path


def _frf_curves(fig: Figure, result: Result, frf: Any, H: np.ndarray, omega: np.ndarray,
                max_curves: int, label: str, db: bool) -> None:
    n_pairs = H.shape[1] * H.shape[2]
    shown = [divmod(p, H.shape[2]) for p in range(min(n_pairs, max(1, int(max_curves))))]
    # the curves drawn, a selection (n_omega x shown): never a copy of the whole array
    curves = H[:, [i for i, _ in shown], [j for _, j in shown]]
    ax_mag, ax_ph = fig.subplots(2, 1, sharex=True, height_ratios=[2, 1])
    colors = [f"C{c}" for c in range(10)]
    for c, (i, j) in enumerate(shown):
        h = curves[:, c]
        mag = decibels(h) if db else np.where(abs(h) > 0, abs(h), np.nan)
        name = f"{frf.outputs[i]} \u2190 {frf.inputs[j]}"
        marker = "o" if omega.size <= SPARSE_GRID else None  # a sparse grid shows its points
        ax_mag.plot(omega, mag, color=colors[c % 10], lw=1.4, label=name, marker=marker,
                    ms=3)
        phase = np.degrees(np.angle(h))
        phase[phase < -179.9999] = 180.0  # one side for real negative values (+-0 imaginary)
        ax_ph.plot(omega, phase, color=colors[c % 10], lw=1.2)
    if not db and np.any(abs(curves) > 0):
        ax_mag.set_yscale("log")
    steps = np.diff(np.log(omega)) if omega.min() > 0 else np.zeros(0)
    geometric = steps.size > 1 and np.allclose(steps, steps[0], rtol=1e-6)  # a log grid
    if omega.min() > 0 and (geometric or omega.max() / omega.min() > 100):
        ax_mag.set_xscale("log")
    ax_mag.set_ylabel(label)
    ax_ph.set_ylabel("phase (deg)")
    ax_ph.set_xlabel("\u03c9 (rad/s)")
    ax_ph.set_ylim(-185, 185)
    ax_ph.set_yticks([-180, -90, 0, 90, 180])
    for ax in (ax_mag, ax_ph):
        ax.grid(True, which="major", alpha=0.35)
        ax.grid(True, which="minor", alpha=0.12)
        ax.set_xlim(omega.min(), omega.max())
    if result.modes is not None:
        w = np.asarray(result.modes.omega, dtype=float)
        inside = w[(w >= omega.min()) & (w <= omega.max())]
        for c, wn in enumerate(inside):
            for ax in (ax_mag, ax_ph):
                ax.axvline(wn, color="0.55", lw=0.8, ls=":",
                           label="natural frequencies" if (c == 0 and ax is ax_mag) else None)
    secondary = ax_mag.secondary_xaxis("top", functions=(lambda w: w / (2 * np.pi),
                                                         lambda f: f * 2 * np.pi))
    secondary.set_xlabel("frequency (Hz)")
    more = n_pairs - len(shown)
    ax_mag.legend(fontsize=8.5, loc="best", ncols=1 if len(shown) < 5 else 2,
                  title=f"output \u2190 input (+{more} pairs not shown)" if more else
                  "output \u2190 input", title_fontsize=8.5)


def _frf_matrix(fig: Figure, frf: Any, H: np.ndarray, w: float, unit: str, db: bool) -> None:
    from matplotlib.colors import LogNorm

    ax_mag, ax_ph = fig.subplots(1, 2)
    mag = decibels(H) if db else abs(H)
    positive = abs(H)[abs(H) > 0]
    norm = LogNorm(positive.min(), positive.max()) if not db and positive.size and \
        positive.max() > positive.min() else None
    im = ax_mag.imshow(mag if db else np.where(mag > 0, mag, np.nan), cmap="viridis",
                       norm=norm, aspect="auto")
    fig.colorbar(im, ax=ax_mag, shrink=0.8, label=unit)
    ph = ax_ph.imshow(np.degrees(np.angle(H)), cmap="twilight_shifted", vmin=-180, vmax=180,
                      aspect="auto")
    fig.colorbar(ph, ax=ax_ph, shrink=0.8, label="phase (deg)", ticks=[-180, -90, 0, 90, 180])
    big = H.size <= 64
    phase = np.degrees(np.angle(H)) + 0.0  # + 0.0: no "-0.0"
    phase[abs(phase) < 0.05] = 0.0
    for ax, values, fmt in ((ax_mag, mag, "{:.1f} dB" if db else "{:.4g}"), (ax_ph, phase, "{:.1f}\u00b0")):
        ax.set_xticks(range(H.shape[1]), frf.inputs, rotation=30, ha="right")
        ax.set_yticks(range(H.shape[0]), frf.outputs)
        ax.set_xlabel("input (unit force at)")
        ax.set_ylabel("output (displacement at)")
        if big:
            for (i, j), v in np.ndenumerate(values):
                ax.text(j, i, fmt.format(v), ha="center", va="center", fontsize=9,
                        color="white", fontweight="bold",
                        bbox=dict(boxstyle="round,pad=0.2", fc="black", alpha=0.35, lw=0))
    ax_mag.set_title(f"{'level of ' if db else ''}|H| at \u03c9 = {w:.5g} rad/s ({w / (2 * np.pi):.4g} Hz)")
    ax_ph.set_title("phase")
