"""The recovered transient peaks of two results side by side (``substruct compare A.h5
B.h5``): for each recovery (``<part>.<name>``) and row label the two hold, the largest and
smallest values of A and B and the change of the peak magnitude (the largest absolute value,
the quantity a loads analysis sizes by), :math:`(|e_B| - |e_A|) / |e_A|`: a row whose extreme
moves from its minimum to its maximum, -9.8 to 11.0, changes by 12 %, not by 212 %."""

from __future__ import annotations

from typing import Any, TextIO

__all__ = ["compare_peaks", "print_peak_comparison", "MAX_PEAK_ROWS"]

#: Rows of the printed table (largest change first); ``--json`` holds all of them.
MAX_PEAK_ROWS = 30


def compare_peaks(a: Any, b: Any) -> list[dict[str, Any]]:
    """One row per recovered quantity with a transient history in both results ``a`` and
    ``b`` (matched by recovery title and row label), largest relative change first."""
    by_b = {r.title: r for r in b.recovery if r.t.size}
    rows = []
    for ra in a.recovery:
        rb = by_b.get(ra.title)
        if rb is None or not ra.t.size:
            continue
        pa, pb = ra.peaks(), rb.peaks()
        ea, eb = pa.extreme(), pb.extreme()
        index_b = {lab: k for k, lab in enumerate(rb.labels)}
        for i, lab in enumerate(ra.labels):
            k = index_b.get(lab)
            if k is None:
                continue
            change = (abs(float(eb[k])) - abs(float(ea[i]))) / abs(float(ea[i])) \
                if ea[i] else None
            rows.append({"recovery": ra.title, "row": lab,
                         "max_a": float(pa.max[i]), "min_a": float(pa.min[i]),
                         "max_b": float(pb.max[k]), "min_b": float(pb.min[k]),
                         "change": change})
    rows.sort(key=lambda r: -abs(r["change"]) if r["change"] is not None else 0.0)
    return rows


def print_peak_comparison(rows: list[dict[str, Any]], out: TextIO) -> None:
    """The table of :func:`compare_peaks` (up to :data:`MAX_PEAK_ROWS` rows)."""
    if not rows:
        return
    width = max(8, max(len(f"{r['recovery']}@{r['row']}") for r in rows))
    out.write(f"recovered peaks ({len(rows)} quantities in both; largest change first):\n")
    out.write(f"  {'quantity':<{width}s}  {'max A':>11s}  {'min A':>11s}  {'max B':>11s}  "
              f"{'min B':>11s}  {'change':>9s}\n")
    for r in rows[:MAX_PEAK_ROWS]:
        change = f"{100 * r['change']:8.2f}%" if r["change"] is not None else f"{'-':>9s}"
        out.write(f"  {r['recovery'] + '@' + r['row']:<{width}s}  {r['max_a']:11.4g}  "
                  f"{r['min_a']:11.4g}  {r['max_b']:11.4g}  {r['min_b']:11.4g}  {change}\n")
    if len(rows) > MAX_PEAK_ROWS:
        out.write(f"  (+{len(rows) - MAX_PEAK_ROWS} more with --json)\n")
