"""A convergence study shown: its text table (:func:`print_table`: per variant the limit and
its uncertainty, the relative error of every level and mode, the fitted orders with the
theoretical ones, the cost, and how many rod DOFs each series needs for a tolerance), and, for
scripts and notebooks, the study with its files and its table in one call
(:func:`run_convergence`).

``substruct converge`` (:mod:`substruct.cli.converge_command`) prints the same table; its
``--json`` is :func:`substruct.io.convergence_report.convergence_summary_json`.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from substruct.builder.rod_system import RodSystemSpec
from substruct.io.convergence_report import output_paths, save_h5
from substruct.studies.convergence import VARIANTS, Progress, convergence_study, dofs_to_reach
from substruct.studies.convergence_results import ConvergenceResult, SeriesResult
from substruct.studies.levels import StudyLevels, parse_levels
from substruct.viz.convergence_picture import plot_convergence

__all__ = ["print_table", "run_convergence"]


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
        ref = ("Richardson" if result.attrs.get("reference") == "richardson"
               and np.all(np.isfinite(v.limit_richardson)) else "the finest level")
        if result.attrs.get("reference") == "richardson" and ref != "Richardson":
            ref += " (no Richardson estimate: the limit series has one level)"
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


def run_convergence(spec: RodSystemSpec, out_dir: str | os.PathLike[str],
                    levels: StudyLevels | str | None = None, *,
                    variants: Sequence[str] = VARIANTS,
                    progress: Progress | None = None, tol: float = 1e-6,
                    reference: str = "richardson", fit_points: int = 3,
                    echo: bool = True) -> tuple[ConvergenceResult, Path, Path]:
    """Study, table, ``<name>_convergence.h5`` and ``.png``
    (:func:`~substruct.io.convergence_report.output_paths`).

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
    plot_convergence(result, png, tol=tol)
    if echo:
        print_table(result, tol=tol)
    return result, h5, png
