"""The Campbell-style picture of a tracked study, ``<name>_study_tracked.png``: each mode's
natural frequency along its track against the parameter (one colour a track, so a track that
crosses another keeps its colour), crossings marked with circles and veerings with diamonds,
the slope ``d omega / d p`` from the formulation drawn as a short tangent at each sample when
collected, and the damping ratios along the tracks below when collected."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from substruct.studies.study_tracking import TrackedStudy

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["tracking_figure"]


def tracking_figure(t: TrackedStudy, case_name: str) -> "Figure":
    """The picture of the module docstring."""
    from matplotlib.figure import Figure

    damping = t.tracked.get("damping_ratio")
    slope = t.tracked.get("frequency_derivative")
    fig = Figure(figsize=(8, 7 if damping is not None else 5), dpi=110, layout="constrained")
    axes = fig.subplots(2 if damping is not None else 1, 1, sharex=True, squeeze=False)[:, 0]
    ax = axes[0]
    x = t.values
    span = 0.35 * float(np.min(np.diff(x))) if len(x) > 1 else 0.0
    for k in range(t.frequency.shape[1]):
        ax.plot(x, t.frequency[:, k], "-", color=f"C{k}", lw=1.4, label=f"track {k + 1}")
        if slope is not None and span:
            for xs, f, d in zip(x, t.frequency[:, k], slope[:, k]):
                ax.plot([xs - span, xs + span], [f - d * span, f + d * span], "-",
                        color="k", lw=0.7, alpha=0.6)
    for n, (s, a, b) in enumerate(t.crossings):
        xm = 0.5 * (x[s] + x[min(s + 1, len(x) - 1)])
        fm = 0.25 * (t.frequency[s, a] + t.frequency[s, b] + t.frequency[min(s + 1, len(x) - 1), a]
                     + t.frequency[min(s + 1, len(x) - 1), b])
        ax.plot(xm, fm, "o", mfc="none", mec="k", ms=11, label="crossing" if n == 0 else None)
    for n, (s, a, b) in enumerate(t.veerings):
        ax.plot([x[s], x[s]], [t.frequency[s, a], t.frequency[s, b]], "D", color="r", ms=6,
                label="veering" if n == 0 else None)
    ax.set_ylabel("natural frequency (rad/s)")
    ax.set_title(f"{case_name}: modes tracked by MAC against {t.parameter}"
                 + ("\n(black ticks: d omega / d p from the formulation)" if slope is not None
                    else ""), fontsize=11)
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    if damping is not None:
        for k in range(damping.shape[1]):
            axes[1].plot(x, damping[:, k], "-", color=f"C{k}", lw=1.4)
        axes[1].set_ylabel("damping ratio")
        axes[1].grid(True, alpha=0.3)
    axes[-1].set_xlabel(t.parameter)
    return fig
