r"""The receptance peaks of two results side by side (``substruct compare A.h5 B.h5``).

For each output/input pair of ``/frf`` that both results hold (matched by name), and for each
recovered row and input of the recovered receptances (``/recovery/<i>/frf``, matched by
recovery ``<part>.<name>``, row label and input name), the peak of each result over its own
frequencies,

.. math:: P = \max_k |H(\omega_k)|, \qquad f_P = \omega_{k^*} / 2\pi

(the first frequency where it is reached), their ratio :math:`P_B / P_A` and the difference
in decibels :math:`20 \log_{10}(P_B / P_A)` (amplitude ratio). Largest :math:`|dB|` first: the
pairs whose resonance moved or grew the most.

Two ``/frf`` in different quantities (a receptance beside an accelerance) are not compared:
one line, exit code 2.
"""

from __future__ import annotations

import math
from typing import Any, TextIO

import numpy as np

from substruct.cli.errors import InputError

__all__ = ["compare_frf_peaks", "print_frf_comparison", "MAX_FRF_ROWS"]

#: Rows of the printed table (largest change first); ``--json`` holds all of them.
MAX_FRF_ROWS = 30


def _peak(h: np.ndarray, omega: np.ndarray) -> tuple[float, float]:
    """The largest ``|h|`` over the frequencies and its first frequency in Hz."""
    mag = np.abs(h)
    k = int(np.argmax(mag))
    return float(mag[k]), float(omega[k]) / (2.0 * math.pi)


def _row(kind: str, quantity: str, inp: str, ha: np.ndarray, wa: np.ndarray,
         hb: np.ndarray, wb: np.ndarray) -> dict[str, Any]:
    pa, fa = _peak(ha, wa)
    pb, fb = _peak(hb, wb)
    ratio = pb / pa if pa > 0.0 else None
    db = 20.0 * math.log10(ratio) if ratio is not None and ratio > 0.0 else None
    return {"kind": kind, "quantity": quantity, "input": inp, "peak_a": pa, "f_a_hz": fa,
            "peak_b": pb, "f_b_hz": fb, "ratio": ratio, "db": db}


def _plain(a: Any, b: Any) -> list[dict[str, Any]]:
    fa, fb = a.frf, b.frf
    if fa is None or fb is None or not len(fa.omega) or not len(fb.omega):
        return []
    if fa.quantity != fb.quantity:
        raise InputError(f"/frf: A's is {fa.quantity} and B's {fb.quantity}: peaks of "
                         "different quantities are not compared")
    out_b = {lab: k for k, lab in enumerate(fb.outputs)}
    in_b = {lab: k for k, lab in enumerate(fb.inputs)}
    rows = []
    for i, out in enumerate(fa.outputs):
        ib = out_b.get(out)
        if ib is None:
            continue
        for j, inp in enumerate(fa.inputs):
            jb = in_b.get(inp)
            if jb is None:
                continue
            rows.append(_row("frf", out, inp, fa.H[:, i, j], fa.omega, fb.H[:, ib, jb],
                             fb.omega))
    return rows


def _recovered(a: Any, b: Any) -> list[dict[str, Any]]:
    by_b = {r.title: r for r in b.recovery if r.omega.size}
    rows = []
    for ra in a.recovery:
        rb = by_b.get(ra.title)
        if rb is None or not ra.omega.size:
            continue
        lab_b = {lab: k for k, lab in enumerate(rb.labels)}
        in_b = {lab: k for k, lab in enumerate(rb.inputs)}
        for i, lab in enumerate(ra.labels):
            ib = lab_b.get(lab)
            if ib is None:
                continue
            for j, inp in enumerate(ra.inputs):
                jb = in_b.get(inp)
                if jb is None:
                    continue
                rows.append(_row("recovery", f"{ra.title}@{lab}", inp, ra.frf[:, i, j],
                                 ra.omega, rb.frf[:, ib, jb], rb.omega))
    return rows


def compare_frf_peaks(a: Any, b: Any) -> list[dict[str, Any]]:
    """One row per output/input pair of ``/frf`` and per recovered row and input that both
    results ``a`` and ``b`` hold (module docstring), the largest ``|dB|`` first (pairs whose
    peak is zero in A, without a ratio, last).

    Raises:
        InputError: the two ``/frf`` are of different quantities.
    """
    rows = _plain(a, b) + _recovered(a, b)
    rows.sort(key=lambda r: -abs(r["db"]) if r["db"] is not None else 0.0)
    return rows


def print_frf_comparison(rows: list[dict[str, Any]], out: TextIO) -> None:
    """The table of :func:`compare_frf_peaks` (up to :data:`MAX_FRF_ROWS` rows)."""
    if not rows:
        return
    width = max(8, max(len(f"{r['quantity']} / {r['input']}") for r in rows))
    out.write(f"receptance peaks ({len(rows)} output/input pairs in both; largest change "
              "first):\n")
    out.write(f"  {'output / input':<{width}s}  {'peak A':>11s}  {'f_A (Hz)':>10s}  "
              f"{'peak B':>11s}  {'f_B (Hz)':>10s}  {'B/A':>9s}  {'dB':>8s}\n")
    for r in rows[:MAX_FRF_ROWS]:
        ratio = f"{r['ratio']:9.4g}" if r["ratio"] is not None else f"{'-':>9s}"
        db = f"{r['db']:8.2f}" if r["db"] is not None else f"{'-':>8s}"
        out.write(f"  {r['quantity'] + ' / ' + r['input']:<{width}s}  {r['peak_a']:11.4g}  "
                  f"{r['f_a_hz']:10.4g}  {r['peak_b']:11.4g}  {r['f_b_hz']:10.4g}  {ratio}  "
                  f"{db}\n")
    if len(rows) > MAX_FRF_ROWS:
        out.write(f"  (+{len(rows) - MAX_FRF_ROWS} more with --json)\n")
