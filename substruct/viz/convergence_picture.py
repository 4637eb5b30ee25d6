"""The picture of a convergence study: relative error against rod DOFs, log-log, one line
per series (:func:`plot_convergence`)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from substruct.io.hdf5 import atomic_path
from substruct.studies.convergence_results import ConvergenceResult

__all__ = ["plot_convergence"]


_STYLE = {"assumed": ("C0", "o", "-"), "enriched": ("C2", "s", "-"), "fe-p1": ("C1", "^", "-"),
          "fe-p2": ("C3", "v", "-")}


def plot_convergence(result: ConvergenceResult, png: str | os.PathLike[str],
                     tol: float | None = 1e-6) -> Path:
    """Log-log relative error vs rod DOFs, one line per series; a row per variant, columns
    mode 1 and the worst mode (largest error over the modes at each level).  Levels used in the
    rate fits have filled markers; legends give the fitted orders (the range over the modes in
    the worst-mode column); ``tol`` is a dotted line.  A panel with nothing to draw (mode 1 of a
    free rod: a rigid-body mode, whose relative error is undefined) says so.
    Written atomically (:func:`substruct.io.hdf5.atomic_path`)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    vs = list(result.variants.values())
    fig, axes = plt.subplots(len(vs), 2, figsize=(16, 4.2 * len(vs)), squeeze=False,
                             layout="constrained")
    for row, v in zip(axes, vs):
        for col, (ax, which) in enumerate(zip(row, ("mode 1", "worst mode"))):
            drawn = False
            for s in v.series.values():
                color, marker, ls = _STYLE.get(s.key, ("C7", "x", "--"))
                err = s.rel_error[:, 0] if col == 0 else s.worst_error
                fitted = s.fit_mask[:, 0] if col == 0 else s.fit_mask.any(axis=1)
                ok = np.isfinite(err) & (err > 0)
                drawn |= bool(ok.any())
                rates = s.rate[:1] if col == 0 else s.rate
                rates = rates[np.isfinite(rates)]
                label = s.label
                if rates.size == 1 or (rates.size and np.ptp(rates) < 0.005):
                    label += f", order {rates[0]:.2f}"
                elif rates.size:
                    label += f", orders {rates.min():.2f}-{rates.max():.2f}"
                ax.loglog(s.dofs[ok], err[ok], ls, color=color, marker=marker, mfc="white",
                          label=label)
                sel = ok & fitted
                ax.loglog(s.dofs[sel], err[sel], "none", color=color, marker=marker)
            if tol:
                ax.axhline(tol, color="0.5", ls=":", lw=1, label=f"tolerance {tol:g} (--tol)")
            ax.plot([], [], "o", color="0.35", label="filled: levels of the order fit")
            ax.plot([], [], "o", color="0.35", mfc="white", label="open: the other levels")
            if not drawn:  # e.g. mode 1 a rigid-body mode: no relative error to show
                ax.set_ylim(1e-12, 1.0)
                ax.text(0.5, 0.5, "no finite nonzero errors\n(rigid-body mode?)",
                        transform=ax.transAxes, ha="center", va="center", color="0.4")
            ax.set_title(f"{v.label}: {which}", fontsize=10)
            ax.set_xlabel("rod DOFs (Ritz functions / FE unknowns)")
            ax.set_ylabel("relative error of the root")
            ax.grid(True, which="major", alpha=0.3)
            ax.legend(fontsize=9, loc="center left", bbox_to_anchor=(1.01, 0.5))
    fig.suptitle(f"{result.name}: convergence to the FE limit", fontsize=12)
    path = Path(png)
    try:
        with atomic_path(path, suffix=".png.part") as tmp:
            fig.savefig(tmp, dpi=90, format="png", bbox_inches="tight")
    finally:
        plt.close(fig)
    return path
