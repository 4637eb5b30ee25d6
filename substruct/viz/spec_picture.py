"""Pictures of the specification analyses (matplotlib, written atomically beside the result):

* ``<name>_random.png``: the response auto-PSD of each output of ``analysis.random`` against
  frequency (log-log; its RMS in the legend), and the input PSDs below;
* ``<name>_srs.png``: the shock response spectra of ``analysis.srs`` (maximax absolute
  acceleration, the positive and negative ones dashed and dotted), and the pseudo-velocity
  below.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from substruct.io.hdf5 import atomic_path
from substruct.run.spec_results import RandomResponse, ShockSpectra

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["random_figure", "srs_figure", "plot_random", "plot_srs"]


def _save(fig: "Figure", path: str | os.PathLike) -> Path:
    out = Path(path)
    with atomic_path(out, suffix=".png.part") as tmp:
        fig.savefig(tmp, format="png")
    return out


def _positive(y: np.ndarray) -> np.ndarray:
    """Levels for a log axis: zeros left out (NaN)."""
    y = np.asarray(y, dtype=float)
    return np.where(y > 0, y, np.nan)


def random_figure(r: RandomResponse, case_name: str) -> "Figure":
    """The response and input PSDs of a random response (module docstring)."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(8, 7), dpi=110, layout="constrained")
    top, bottom = fig.subplots(2, 1, sharex=True, height_ratios=[2, 1])
    for i, name in enumerate(r.outputs):
        top.loglog(r.f, _positive(np.real(r.psd[:, i, i])), lw=1.2,
                   label=f"{name}: rms {r.rms[i]:.4g}")
    top.set_ylabel(f"{r.quantity} PSD (unit^2/Hz)")
    top.set_title(f"{case_name}: random response ({r.quantity}; "
                  f"{'correlated' if r.input_csd is not None else 'uncorrelated'} inputs)")
    top.legend(fontsize=8)
    top.grid(True, which="both", alpha=0.3)
    for j, name in enumerate(r.inputs):
        bottom.loglog(r.f, _positive(r.input_psd[:, j]), lw=1.2, label=name)
    bottom.set_xlabel("frequency (Hz)")
    bottom.set_ylabel("input PSD")
    bottom.legend(fontsize=8)
    bottom.grid(True, which="both", alpha=0.3)
    return fig


def srs_figure(s: ShockSpectra, case_name: str) -> "Figure":
    """The shock response spectra (module docstring)."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(8, 7), dpi=110, layout="constrained")
    top, bottom = fig.subplots(2, 1, sharex=True)
    for i, name in enumerate(s.outputs):
        top.loglog(s.fn, _positive(s.maxabs[i]), "-", color=f"C{i}", lw=1.4,
                   label=f"{name} maximax")
        top.loglog(s.fn, _positive(s.pos[i]), "--", color=f"C{i}", lw=0.8)
        top.loglog(s.fn, _positive(s.neg[i]), ":", color=f"C{i}", lw=0.8)
        bottom.loglog(s.fn, _positive(s.pv[i]), "-", color=f"C{i}", lw=1.2, label=name)
    top.set_ylabel("peak absolute acceleration")
    top.set_title(f"{case_name}: shock response spectra (Q = {1 / (2 * s.zeta):.4g}; "
                  "dashed positive, dotted negative)")
    top.legend(fontsize=8)
    top.grid(True, which="both", alpha=0.3)
    bottom.set_xlabel("natural frequency (Hz)")
    bottom.set_ylabel("pseudo-velocity")
    bottom.legend(fontsize=8)
    bottom.grid(True, which="both", alpha=0.3)
    return fig


def plot_random(r: RandomResponse, case_name: str, png_path: str | os.PathLike) -> Path:
    """:func:`random_figure` written atomically as a PNG; its path."""
    return _save(random_figure(r, case_name), png_path)


def plot_srs(s: ShockSpectra, case_name: str, png_path: str | os.PathLike) -> Path:
    """:func:`srs_figure` written atomically as a PNG; its path."""
    return _save(srs_figure(s, case_name), png_path)
