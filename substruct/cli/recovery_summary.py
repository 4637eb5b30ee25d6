"""What ``substruct run`` and ``substruct info`` print about the responses recovered inside
superelements (:mod:`substruct.run.recovered`), and their part of ``--json``: per recovery
matrix the rows recovered and, with a transient response, the table of peaks (largest and
smallest value of each row and their instants); with receptances, the table of their peaks
(largest magnitude of each row over the frequencies and inputs, its frequency and input)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, TextIO

import numpy as np

if TYPE_CHECKING:
    from substruct.run.recovered import Recovered

__all__ = ["recovery_json", "print_recovery", "print_frf_peaks", "MAX_ROWS"]

#: Rows of a peaks table printed (the largest in magnitude first); all are in the file.
MAX_ROWS = 20


def _number(x: float) -> Any:
    x = float(x)
    return x if np.isfinite(x) else None


def recovery_json(recovered: list[Recovered]) -> list[dict[str, Any]]:
    """Each recovery as JSON-safe data: part, name, histories, labels, and the peaks of the
    transient history by label (no histories: they are in the file)."""
    out = []
    for rec in recovered:
        item: dict[str, Any] = {"part": rec.part, "name": rec.name, "of": list(rec.of),
                                "rows": len(rec.labels),
                                "modes": int(rec.modes.shape[1]) if rec.modes.size else 0}
        if rec.t.size:
            p = rec.peaks()
            item["peaks"] = {lab: {"max": _number(p.max[i]), "t_max": _number(p.t_max[i]),
                                   "min": _number(p.min[i]), "t_min": _number(p.t_min[i])}
                             for i, lab in enumerate(rec.labels)}
        if rec.omega.size:
            fp = rec.frf_peaks()
            item["frf_peaks"] = {lab: {"abs": _number(fp.abs[i]),
                                       "omega": _number(fp.omega[i]),
                                       "input": rec.inputs[int(fp.input[i])]
                                       if rec.inputs else None}
                                 for i, lab in enumerate(rec.labels)}
        out.append(item)
    return out


def print_recovery(recovered: list[Recovered], out: TextIO) -> None:
    """One line per recovery matrix, then its peaks table (up to :data:`MAX_ROWS` rows, the
    largest in magnitude first)."""
    for rec in recovered:
        what = []
        if rec.modes.size:
            what.append(f"{rec.modes.shape[1]} mode shape(s)")
        if rec.t.size:
            what.append(f"{len(rec.t)} samples")
        if rec.omega.size:
            what.append(f"receptances at {len(rec.omega)} frequencies")
        out.write(f"recovery {rec.title} ({' + '.join(rec.of)}): {len(rec.labels)} row(s)"
                  f"{', ' if what else ''}{', '.join(what)}\n")
        if rec.omega.size and rec.labels:
            print_frf_peaks(rec, out)
        if not rec.t.size or not rec.labels:
            continue
        p = rec.peaks()
        order = np.argsort(-np.abs(p.extreme()), kind="stable")
        width = max(5, max(len(lab) for lab in rec.labels))
        out.write(f"    {'row':<{width}s}  {'max':>12s}  {'t_max':>10s}  {'min':>12s}  "
                  f"{'t_min':>10s}\n")
        for i in order[:MAX_ROWS]:
            out.write(f"    {rec.labels[i]:<{width}s}  {p.max[i]:12.5g}  {p.t_max[i]:10.4g}  "
                      f"{p.min[i]:12.5g}  {p.t_min[i]:10.4g}\n")
        if len(order) > MAX_ROWS:
            out.write(f"    (+{len(order) - MAX_ROWS} more rows in the results file)\n")


def print_frf_peaks(rec: Recovered, out: TextIO) -> None:
    """The receptance peaks of ``rec``: per row the largest :math:`|H|`, its frequency (Hz)
    and input, up to :data:`MAX_ROWS` rows, the largest first."""
    fp = rec.frf_peaks()
    order = np.argsort(-fp.abs, kind="stable")
    width = max(5, max(len(lab) for lab in rec.labels))
    out.write(f"    {'row':<{width}s}  {'max |H|':>12s}  {'f (Hz)':>10s}  input\n")
    for i in order[:MAX_ROWS]:
        name = rec.inputs[int(fp.input[i])] if rec.inputs else str(int(fp.input[i]))
        out.write(f"    {rec.labels[i]:<{width}s}  {fp.abs[i]:12.5g}  "
                  f"{fp.omega[i] / (2 * np.pi):10.4g}  {name}\n")
    if len(order) > MAX_ROWS:
        out.write(f"    (+{len(order) - MAX_ROWS} more rows in the results file)\n")
