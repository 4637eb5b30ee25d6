"""The printed tables of the specification analyses: the RMS of each random-response output
(with its 3-sigma level) and the peaks of each shock response spectrum."""

from __future__ import annotations

from typing import Any, TextIO

import numpy as np

from substruct.analysis.frf.random import miles_check
from substruct.run.spec_results import (
    THREE_SIGMA_EXCEEDANCE,
    BaseFrf,
    RandomResponse,
    ShockSpectra,
)

__all__ = ["print_random", "print_base_frf", "print_srs", "random_json", "base_frf_json",
           "srs_json"]


def print_random(r: RandomResponse, out: TextIO) -> None:
    """``output  rms  3 rms`` for each output, then the 3-sigma note."""
    out.write(f"random response ({r.quantity}, {len(r.f)} frequencies "
              f"{r.f[0]:.4g}-{r.f[-1]:.4g} Hz, inputs: {', '.join(r.inputs)}; {r.method})\n")
    width = max(len("output"), *(len(o) for o in r.outputs))
    out.write(f"  {'output':<{width}}  {'rms':>11}  {'3 rms':>11}\n")
    for name, value in zip(r.outputs, r.rms):
        out.write(f"  {name:<{width}}  {value:11.4e}  {3 * value:11.4e}\n")
    out.write(f"  (a Gaussian response exceeds 3 rms {100 * THREE_SIGMA_EXCEEDANCE:.2f} % of "
              f"the time)\n")
    if r.quantity == "acceleration" and r.base and len(r.inputs) == 1:
        out.write("  Miles' check, sqrt(pi/2 f_n Q W) at each output's highest transmissibility "
                  "peak (one dominant mode: close to rms):\n")
        out.write(f"  {'output':<{width}}  {'f_n (Hz)':>9}  {'Q':>8}  {'W':>11}  "
                  f"{'Miles':>11}  {'Miles/rms':>9}\n")
        for i, name in enumerate(r.outputs):
            m = miles_check(r.f, r.input_psd[:, 0], r.psd[:, i, i])
            if m.Q < 1.5:
                out.write(f"  {name:<{width}}  (no resonant peak: |T| <= {m.Q:.3g})\n")
                continue
            ratio = m.miles / r.rms[i] if r.rms[i] > 0 else float("nan")
            out.write(f"  {name:<{width}}  {m.fn:9.4g}  {m.Q:8.4g}  {m.W:11.4e}  "
                      f"{m.miles:11.4e}  {ratio:9.3f}\n")


def _peaks(r: BaseFrf) -> list[tuple[str, str, float, float]]:
    """``(output, input, max |T|, its frequency in Hz)`` of each output and base input."""
    mag = np.abs(r.T)
    rows = []
    for i, name in enumerate(r.outputs):
        for j, base in enumerate(r.inputs):
            k = int(np.argmax(mag[:, i, j]))
            rows.append((name, base, float(mag[k, i, j]), float(r.omega[k] / (2 * np.pi))))
    return rows


def print_base_frf(r: BaseFrf, out: TextIO) -> None:
    """``output  input  peak |T|  at (Hz)`` for each output and base input."""
    f = r.omega / (2 * np.pi)
    out.write(f"base-driven frequency response ({r.quantity} per base acceleration, "
              f"{len(f)} frequencies {f[0]:.4g}-{f[-1]:.4g} Hz; {r.method}")
    checks = ", ".join(f"{k} {v:.2g}" for k, v in r.agreement.items())
    out.write(f"; agreement: {checks})\n" if checks else ")\n")
    width = max(len("output"), *(len(o) for o in r.outputs))
    bw = max(len("input"), *(len(b) for b in r.inputs))
    out.write(f"  {'output':<{width}}  {'input':<{bw}}  {'peak |T|':>11}  {'at (Hz)':>9}\n")
    for name, base, peak, at in _peaks(r):
        out.write(f"  {name:<{width}}  {base:<{bw}}  {peak:11.4e}  {at:9.4g}\n")


def print_srs(s: ShockSpectra, out: TextIO) -> None:
    """For each output, the largest of its spectrum and where it is."""
    out.write(f"shock response spectra (Q = {1 / (2 * s.zeta):.4g}, {len(s.fn)} frequencies "
              f"{s.fn[0]:.4g}-{s.fn[-1]:.4g} Hz, absolute acceleration, maximax)\n")
    width = max(len("output"), *(len(o) for o in s.outputs))
    out.write(f"  {'output':<{width}}  {'peak':>11}  {'at (Hz)':>9}  {'pos':>11}  "
              f"{'neg':>11}  {'max pv':>11}\n")
    for i, name in enumerate(s.outputs):
        k = int(np.argmax(s.maxabs[i]))
        out.write(f"  {name:<{width}}  {s.maxabs[i, k]:11.4e}  {s.fn[k]:9.4g}  "
                  f"{s.pos[i].max():11.4e}  {s.neg[i].max():11.4e}  {s.pv[i].max():11.4e}\n")


def random_json(r: RandomResponse) -> dict[str, Any]:
    """The RMS table as JSON."""
    return {"quantity": r.quantity, "rms": dict(zip(r.outputs, map(float, r.rms)))}


def base_frf_json(r: BaseFrf) -> dict[str, Any]:
    """The peak of each transmissibility (``output/input``) and its frequency (Hz) as JSON."""
    return {"quantity": r.quantity,
            "peaks": {f"{o}/{b}": {"peak": peak, "f": at} for o, b, peak, at in _peaks(r)}}


def srs_json(s: ShockSpectra) -> dict[str, Any]:
    """The peak of each spectrum as JSON."""
    return {"zeta": s.zeta, "peaks": {o: float(s.maxabs[i].max())
                                      for i, o in enumerate(s.outputs)}}
