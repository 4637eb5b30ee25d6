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


def _peaks(H: np.ndarray, omega: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per output/input pair of ``H`` (``n_omega x outputs x inputs``): the largest ``|H|``
    over the frequencies and its first frequency in Hz."""
    mag = np.abs(np.asarray(H))
    k = np.argmax(mag, axis=0)
    peak = np.take_along_axis(mag, k[None], axis=0)[0]
    return peak, np.asarray(omega, dtype=float)[k] / (2.0 * math.pi)


def _rows(kind: str, names: list[str], inputs: list[str], A: tuple[np.ndarray, np.ndarray],
          B: tuple[np.ndarray, np.ndarray]) -> list[dict[str, Any]]:
    """The table rows of the matched pairs, ``A`` and ``B`` the receptances of the matched
    outputs and inputs (in the same order) and their frequencies."""
    (pa, fa), (pb, fb) = _peaks(*A), _peaks(*B)
    rows = []
    for i, name in enumerate(names):
        for j, inp in enumerate(inputs):
            a, b = float(pa[i, j]), float(pb[i, j])
            ratio = b / a if a > 0.0 else None
            db = 20.0 * math.log10(ratio) if ratio is not None and ratio > 0.0 else None
            rows.append({"kind": kind, "quantity": name, "input": inp, "peak_a": a,
                         "f_a_hz": float(fa[i, j]), "peak_b": b, "f_b_hz": float(fb[i, j]),
                         "ratio": ratio, "db": db})
    return rows


def _match(a: list[str], b: list[str]) -> tuple[list[int], list[int]]:
    """The positions in ``a`` and in ``b`` of the names both hold, in ``a``'s order."""
    where = {lab: k for k, lab in enumerate(b)}
    ia = [k for k, lab in enumerate(a) if lab in where]
    return ia, [where[a[k]] for k in ia]


def _plain(a: Any, b: Any) -> list[dict[str, Any]]:
    fa, fb = a.frf, b.frf
    if fa is None or fb is None or not len(fa.omega) or not len(fb.omega):
        return []
    if fa.quantity != fb.quantity:
        raise InputError(f"/frf: A's is {fa.quantity} and B's {fb.quantity}: peaks of "
                         "different quantities are not compared")
    oa, ob = _match(list(fa.outputs), list(fb.outputs))
    ia, ib = _match(list(fa.inputs), list(fb.inputs))
    if not oa or not ia:
        return []
    Ha, Hb = np.asarray(fa.H), np.asarray(fb.H)
    return _rows("frf", [fa.outputs[k] for k in oa], [fa.inputs[k] for k in ia],
                 (Ha[:, oa][:, :, ia], fa.omega), (Hb[:, ob][:, :, ib], fb.omega))


def _recovered(a: Any, b: Any) -> list[dict[str, Any]]:
    by_b = {r.title: r for r in b.recovery if r.omega.size}
    rows = []
    for ra in a.recovery:
        rb = by_b.get(ra.title)
        if rb is None or not ra.omega.size:
            continue
        la, lb = _match(list(ra.labels), list(rb.labels))
        ia, ib = _match(list(ra.inputs), list(rb.inputs))
        if not la or not ia:
            continue
        rows += _rows("recovery", [f"{ra.title}@{ra.labels[k]}" for k in la],
                      [ra.inputs[k] for k in ia], (ra.frf[:, la][:, :, ia], ra.omega),
                      (rb.frf[:, lb][:, :, ib], rb.omega))
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
