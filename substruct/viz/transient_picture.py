r"""The transient picture (matplotlib): the response histories at the output points
(displacement, velocity, acceleration against time) and the constraint forces of eq (5),
:math:`Q^c = A^T \lambda`, one panel each, axis labels in the case's units; the title gives
the form, the integrator, the drift figure :math:`\max_k |A q_k - b| / \max_k |q_k|` and the
checks' agreement."""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from substruct.io.hdf5 import atomic_path
from substruct.run.result import Result

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = ["transient_figure", "plot_transient", "unit_names", "MAX_TRANSIENT_CURVES"]

#: Curves drawn per panel (the first outputs or constraint rows; the legend says how many are
#: left out).
MAX_TRANSIENT_CURVES = 8


def unit_names(units: str) -> dict[str, str]:
    """``{"force", "length", "time"}`` of a case's ``units`` (``"N, mm, t, s"``: force,
    length, mass, time); generic names when the string is not of that form."""
    parts = [p.strip() for p in str(units).split(",")]
    if len(parts) == 4 and all(parts) and all(len(p) <= 12 for p in parts):
        return {"force": parts[0], "length": parts[1], "time": parts[3]}
    return {"force": "force", "length": "length", "time": "time"}


def _panel(ax: Axes, t: np.ndarray, values: np.ndarray, names: list[str], ylabel: str,
           max_curves: int) -> None:
    for j, name in enumerate(names[:max_curves]):
        ax.plot(t, values[:, j], lw=1.2, label=name)
    if len(names) > max_curves:
        ax.plot([], [], " ", label=f"(+{len(names) - max_curves} more)")
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)
    ax.ticklabel_format(axis="y", style="sci", scilimits=(-3, 4))
    if names:
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)


def transient_figure(result: Result, *, max_curves: int = MAX_TRANSIENT_CURVES) -> Figure:
    """The transient figure of ``result``, not yet written (see :func:`plot_transient`).

    Raises:
        ValueError: the result holds no transient response, or no samples.
    """
    from matplotlib.figure import Figure

    tr = result.transient
    if tr is None or tr.t.size == 0:
        raise ValueError(f"result {result.case_name!r} holds no transient response to plot")
    u = unit_names(str(result.attrs.get("units", "")))
    L, T, F = u["length"], u["time"], u["force"]
    panels = [("displacement", f"displacement [{L}]"), ("velocity", f"velocity [{L}/{T}]"),
              ("acceleration", f"acceleration [{L}/{T}²]")] if tr.outputs else []
    forces = tr.constraint_forces.shape[0] == tr.t.size and tr.constraint_forces.shape[1] > 0
    rows = len(panels) + (1 if forces else 0)
    if rows == 0:
        raise ValueError(f"result {result.case_name!r}: the transient response has no outputs "
                         "and no constraint forces to plot")
    fig = Figure(figsize=(12, 2.3 * rows + 1.2), dpi=110, layout="constrained")
    axes = fig.subplots(rows, 1, sharex=True, squeeze=False)[:, 0]
    for ax, (name, label) in zip(axes, panels):
        _panel(ax, tr.t, getattr(tr, name), tr.outputs, label, max_curves)
    if forces:
        _panel(axes[-1], tr.t, tr.constraint_forces, tr.constraint_labels,
               f"constraint force λ [{F}]", max_curves)
    axes[-1].set_xlabel(f"time [{T}]")
    axes[-1].set_xlim(float(tr.t[0]), float(tr.t[-1]))
    rho = f", ρ∞ = {tr.rho_inf:g}" if tr.integrator == "generalized-alpha" else ""
    checks = ", ".join(f"{k} {v:.1e}" for k, v in tr.agreement.items())
    sub = (f"{tr.integrator}{rho}, {tr.steps} steps of {tr.dt:g} {T}; drift "
           f"max|A q - b| / max|q| = {tr.drift:.1e}" + (f"; agreement {checks}" if checks
                                                         else ""))
    fig.suptitle(f"{result.case_name}: transient response ({tr.method})\n{sub}", fontsize=12)
    return fig


def plot_transient(result: Result, png_path: str | os.PathLike, *,
                   max_curves: int = MAX_TRANSIENT_CURVES) -> Path:
    """Displacement, velocity and acceleration at the output points and the constraint
    forces against time, at most ``max_curves`` curves a panel; written atomically as a PNG;
    return its path.

    Raises:
        ValueError: the result holds no transient response (or nothing to draw).
    """
    fig = transient_figure(result, max_curves=max_curves)
    path = Path(png_path)
    with atomic_path(path, suffix=".png.part") as tmp:
        fig.savefig(tmp, format="png")
    return path
