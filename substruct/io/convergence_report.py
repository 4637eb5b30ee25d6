"""Reporting a convergence study: the table, the HDF5 file, the log-log plot, the command.

The study itself (:func:`substruct.studies.convergence.convergence_study`) returns plain arrays
in a :class:`~substruct.studies.convergence_results.ConvergenceResult`; this module, in the output
layer above the studies, shows and keeps them:

* :func:`print_table`: per variant, the limit and its uncertainty, the relative error of every
  level and mode, the fitted orders (with the theoretical ones), the cost, and how many rod DOFs
  each series needs for a tolerance;
* :func:`summary_json`: the same numbers (without the per-level errors) for ``--json``;
* :func:`save_h5` / :func:`load_h5`: the whole result, round trip;
* :func:`plot`: relative error vs rod DOFs, log-log, one line per series;
* :func:`run_convergence`: study, files and table in one call (``substruct converge``), the
  files named by :func:`output_paths`.

Files are written atomically (:func:`substruct.io.hdf5.atomic_path`).
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from substruct.io.hdf5 import atomic_path
from substruct.studies.convergence import VARIANTS, Progress, convergence_study, dofs_to_reach
from substruct.studies.convergence_results import ConvergenceResult, SeriesResult, VariantResult
from substruct.studies.levels import StudyLevels, parse_levels
from substruct.builder.rod_system import RodSystemSpec

__all__ = [
    "output_paths",
    "print_table",
    "summary_json",
    "save_h5",
    "load_h5",
    "plot",
    "run_convergence",
]


def output_paths(out_dir: str | os.PathLike[str], name: str) -> tuple[Path, Path]:
    """``(DIR/<name>_convergence.h5, DIR/<name>_convergence.png)``: what a study writes."""
    out = Path(out_dir)
    return out / f"{name}_convergence.h5", out / f"{name}_convergence.png"


# --------------------------------------------------------------------------------- table


def _fmt(x: float, spec: str = ".1e") -> str:
    if np.isposinf(x):
        return "n/a"
    return "-" if not np.isfinite(x) else format(x, spec)


def _reach_text(s: SeriesResult, tol: float) -> str:
    n = dofs_to_reach(s, tol)
    if n is not None:
        return str(n)
    worst = s.worst_error[-1]
    if np.isposinf(worst):
        have = int(np.sum(np.isfinite(s.eigenvalues[-1])))
        return f"not reached (only {have} of {s.eigenvalues.shape[1]} roots)"
    return f"not reached (worst {_fmt(worst)} at {s.dofs[-1]} DOFs)"


def print_table(result: ConvergenceResult, tol: float = 1e-6, file: Any = None) -> str:
    """A text table: limits, errors per level and mode, fitted rates, cost; returns and prints it.

    Args:
        result: the study.
        tol: tolerance for the "DOFs to reach" summary.
        file: where to print (``sys.stdout`` if ``None``; ``False`` for no printing).
    """
    k = result.n_modes
    W, P = 11, 31  # column width, width of the row titles

    def cols(values: Any, spec: str = ".1e") -> str:
        return "".join(f"{_fmt(x, spec):>{W}}" for x in values)

    modes = "".join(f"{'mode ' + str(j + 1):>{W}}" for j in range(k))
    lines = [f"Convergence study: {result.name}   ({k} modes, total {result.seconds:.1f} s)"]
    for v in result.variants.values():
        ref = "Richardson" if result.attrs.get("reference") == "richardson" else "finest"
        lines += ["", f"== {v.label} ==  ({v.seconds:.1f} s)",
                  f"limit: {v.limit_source}; errors against {ref}",
                  f"{'':{P}}{modes}",
                  f"{'|lambda| finest (rad/s)':{P}}" + cols(abs(v.limit_finest), ".9g"),
                  f"{'|lambda| Richardson (rad/s)':{P}}" + cols(abs(v.limit_richardson), ".9g"),
                  f"{'relative difference':{P}}" + cols(v.limit_difference),
                  f"{'observed order (no limit)':{P}}" + cols(v.reference_order, ".2f"),
                  "",
                  f"{'method':12}{'level':>6}{'DOFs':>6}{'sec':>7}{modes}{'worst':>{W}}"]
        for s in v.series.values():
            for i in range(s.level.size):
                lines.append(f"{s.key:12}{s.level[i]:>6}{s.dofs[i]:>6}{s.seconds[i]:>7.3f}"
                             + cols(s.rel_error[i]) + f"{_fmt(s.worst_error[i]):>{W}}")
            theory = "" if not np.isfinite(s.theory_rate) else f" (theory {s.theory_rate:g})"
            lines.append(f"{'  fitted order' + theory:{P}}" + cols(s.rate, ".2f"))
            if np.any(np.isfinite(s.extrapolated_difference)):
                lines.append(f"{'  own extrapolation vs limit':{P}}"
                             + cols(s.extrapolated_difference))
        lines.append(f"DOFs for worst error <= {tol:g}: "
                     + "; ".join(f"{s.key} {_reach_text(s, tol)}" for s in v.series.values()))
    text = "\n".join(lines)
    if file is not False:
        print(text, file=file)
    return text


def _num(x: Any) -> Any:
    """A JSON-safe number (``null`` for NaN, ``"inf"``/``"-inf"``)."""
    x = float(x)
    return x if math.isfinite(x) else (None if math.isnan(x) else ("inf" if x > 0 else "-inf"))


def _nums(values: Any) -> list[Any]:
    return [_num(x) for x in np.ravel(values)]


def summary_json(result: ConvergenceResult, tol: float = 1e-6,
                 files: Sequence[str | os.PathLike[str]] = ()) -> dict[str, Any]:
    """The study in JSON-ready form: per variant the limit (``|lambda|``, rad/s) and its
    uncertainty, per series the sizes, worst error per level, fitted and theoretical orders,
    and the rod DOFs to reach ``tol`` (``null`` if not reached).  NaN is ``null``, infinity
    ``"inf"`` (a root the level does not have)."""
    variants = {}
    for v in result.variants.values():
        series = {}
        for s in v.series.values():
            series[s.key] = {
                "label": s.label, "level": [int(n) for n in s.level],
                "dofs": [int(n) for n in s.dofs], "seconds": _nums(s.seconds),
                "worst_error": _nums(s.worst_error), "rate": _nums(s.rate),
                "theory_rate": _num(s.theory_rate), "dofs_to_reach": dofs_to_reach(s, tol)}
        variants[v.key] = {
            "label": v.label, "limit_source": v.limit_source, "seconds": _num(v.seconds),
            "limit_omega": _nums(abs(v.limit)), "limit_difference": _nums(v.limit_difference),
            "reference_order": _nums(v.reference_order), "series": series}
    return {"name": result.name, "n_modes": int(result.n_modes), "tol": float(tol),
            "seconds": _num(result.seconds), "files": [str(f) for f in files],
            "attrs": result.attrs, "variants": variants}


# ------------------------------------------------------------------------------- HDF5


def save_h5(result: ConvergenceResult, path: str | os.PathLike[str]) -> Path:
    """Write ``result`` to HDF5 atomically (:func:`substruct.io.hdf5.atomic_path`: a temporary
    file in the same folder, then ``os.replace``): a reader never sees a half-written file, and
    an existing file is replaced only by a complete one.

    Layout: root attributes ``name``, ``n_modes``, ``seconds``, ``levels`` and ``attrs`` (JSON);
    a group per variant (attributes ``label``, ``limit_source``, ``seconds``; datasets
    ``limit_finest``, ``limit_richardson``, ``limit``, ``limit_difference``,
    ``reference_order``, ``floor``) holding a group per series (attributes ``label``,
    ``theory_rate``; datasets ``level``, ``dofs``, ``coupled_dofs``, ``seconds``,
    ``eigenvalues`` (complex), ``rel_error``, ``rate``, ``fit_mask``,
    ``extrapolated_difference``).
    """
    import h5py

    path = Path(path)
    with atomic_path(path, suffix=".h5.part") as tmp:
        with h5py.File(tmp, "w") as f:
            f.attrs["name"] = result.name
            f.attrs["n_modes"] = result.n_modes
            f.attrs["seconds"] = result.seconds
            f.attrs["levels"] = json.dumps(result.levels)
            f.attrs["attrs"] = json.dumps(result.attrs)
            f.attrs["variant_order"] = json.dumps(list(result.variants))
            for v in result.variants.values():
                g = f.create_group(v.key)
                g.attrs["label"] = v.label
                g.attrs["limit_source"] = v.limit_source
                g.attrs["seconds"] = v.seconds
                g.attrs["series_order"] = json.dumps(list(v.series))
                for name in ("limit_finest", "limit_richardson", "limit", "limit_difference",
                             "reference_order", "floor"):
                    g.create_dataset(name, data=getattr(v, name))
                for s in v.series.values():
                    h = g.create_group(s.key)
                    h.attrs["label"] = s.label
                    h.attrs["theory_rate"] = s.theory_rate
                    for name in ("level", "dofs", "coupled_dofs", "seconds", "eigenvalues",
                                 "rel_error", "rate", "fit_mask", "extrapolated_difference"):
                        h.create_dataset(name, data=getattr(s, name))
    return path


def load_h5(path: str | os.PathLike[str]) -> ConvergenceResult:
    """Read a file written by :func:`save_h5`."""
    import h5py

    with h5py.File(path, "r") as f:
        variants: dict[str, VariantResult] = {}
        for vkey in json.loads(f.attrs["variant_order"]):
            g = f[vkey]
            series: dict[str, SeriesResult] = {}
            for skey in json.loads(g.attrs["series_order"]):
                h = g[skey]
                series[skey] = SeriesResult(
                    key=skey, label=str(h.attrs["label"]),
                    theory_rate=float(h.attrs["theory_rate"]),
                    **{name: h[name][()] for name in (
                        "level", "dofs", "coupled_dofs", "seconds", "eigenvalues", "rel_error",
                        "rate", "fit_mask", "extrapolated_difference")})
            variants[vkey] = VariantResult(
                key=vkey, label=str(g.attrs["label"]), series=series,
                limit_source=str(g.attrs["limit_source"]), seconds=float(g.attrs["seconds"]),
                **{name: g[name][()] for name in ("limit_finest", "limit_richardson", "limit",
                                                  "limit_difference", "reference_order",
                                                  "floor")})
        return ConvergenceResult(name=str(f.attrs["name"]), n_modes=int(f.attrs["n_modes"]),
                                 variants=variants, levels=json.loads(f.attrs["levels"]),
                                 seconds=float(f.attrs["seconds"]),
                                 attrs=json.loads(f.attrs["attrs"]))



# ------------------------------------------------------------------------------- plot


_STYLE = {"assumed": ("C0", "o", "-"), "enriched": ("C2", "s", "-"), "fe-p1": ("C1", "^", "-"),
          "fe-p2": ("C3", "v", "-")}


def plot(result: ConvergenceResult, png: str | os.PathLike[str], tol: float | None = 1e-6
         ) -> Path:
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


def run_convergence(spec: RodSystemSpec, out_dir: str | os.PathLike[str],
                    levels: StudyLevels | str | None = None, *,
                    variants: Sequence[str] = VARIANTS,
                    progress: Progress | None = None, tol: float = 1e-6,
                    reference: str = "richardson", fit_points: int = 3,
                    echo: bool = True) -> tuple[ConvergenceResult, Path, Path]:
    """Study, table, ``<name>_convergence.h5`` and ``.png`` (:func:`output_paths`).

    Args:
        spec: the system.
        out_dir: output folder (created).
        levels: :class:`~substruct.studies.levels.StudyLevels`, a string for
            :func:`~substruct.studies.levels.parse_levels`, or ``None``.
        variants: see :func:`~substruct.studies.convergence.convergence_study`.
        progress: ``progress(done, total, description)`` after each level.
        tol: tolerance of the "DOFs to reach" summary and the plot's dotted line.
        reference, fit_points: see :func:`~substruct.studies.convergence.convergence_study`.
        echo: print the table.

    Returns:
        ``(result, h5_path, png_path)``.
    """
    lv = levels if isinstance(levels, StudyLevels) else parse_levels(levels)
    result = convergence_study(spec, lv, variants=variants, reference=reference,
                               fit_points=fit_points, progress=progress)
    h5, png = output_paths(out_dir, spec.name)
    save_h5(result, h5)
    plot(result, png, tol=tol)
    if echo:
        print_table(result, tol=tol)
    return result, h5, png
