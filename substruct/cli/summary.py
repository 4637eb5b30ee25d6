"""What the commands print about a result: the tables of ``run`` and ``info``, and the
machine-readable summary of ``--json``."""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Any, Sequence, TextIO

import numpy as np

from substruct.cli.recovery_summary import print_recovery, recovery_json
from substruct.cli.spec_summary import (
    base_frf_json,
    print_base_frf,
    print_random,
    print_srs,
    random_json,
    srs_json,
)
from substruct.cli.testlab_summary import testlab_json, testlab_lines
from substruct.cli.transient_summary import print_transient, transient_json
from substruct.analysis.frf.stream import StreamedArray
from substruct.io.blocks import max_abs

if TYPE_CHECKING:
    from substruct.run.result import Result

__all__ = ["json_number", "complex_text", "needs_scientific", "spurious_counts", "modes_json",
           "summary_json", "print_modes", "print_frf", "print_summary"]


def json_number(x: float) -> Any:
    """A JSON-safe float (``null`` for nan, a string for inf)."""
    x = float(x)
    return x if math.isfinite(x) else (None if math.isnan(x) else ("inf" if x > 0 else "-inf"))


def complex_text(z: complex, digits: int = 4, scientific: bool = False) -> str:
    """``a+bi`` with ``digits`` decimals, or ``digits`` significant figures in scientific
    notation (``1.234e-09-5.678e-11i``)."""
    if scientific:
        return f"{z.real:.{digits - 1}e}{z.imag:+.{digits - 1}e}i"
    return f"{z.real:.{digits}f}{z.imag:+.{digits}f}i"


def needs_scientific(H: np.ndarray) -> bool:
    """Whether a receptance matrix needs scientific notation: fixed decimals would print
    the small receptances of stiff structures in SI units (``1e-9 m/N``) as ``0.0000``."""
    scale = float(np.abs(H).max()) if np.size(H) else 0.0
    return scale != 0.0 and not 0.1 <= scale < 1e5


def spurious_counts(modes: Any) -> dict[str, int]:
    """How many spurious roots of ``modes`` were set aside for each reason."""
    counts: dict[str, int] = {}
    for r in modes.spurious_reason:
        counts[r] = counts.get(r, 0) + 1
    return counts


def modes_json(modes: Any) -> dict[str, Any]:
    """The modes of a result (``result.modes`` or a variant) as JSON-safe data."""
    return {"method": modes.method, "omega": [json_number(w) for w in modes.omega],
            "freq_hz": [json_number(f) for f in modes.freq_hz],
            "damping_ratio": [json_number(z) for z in modes.damping_ratio],
            "residual": [json_number(r) for r in modes.residual],
            "eigenvalues": [[json_number(z.real), json_number(z.imag)]
                            for z in modes.eigenvalues],
            "spurious": {"count": int(len(modes.spurious)), "reasons": spurious_counts(modes)},
            "agreement": {k: json_number(v) for k, v in modes.agreement.items()}}


def summary_json(result: Result, files: Sequence[Path] = ()) -> dict[str, Any]:
    """A result as JSON-safe data: case, files written, attributes, model, modes, variants and
    receptances (``H`` itself when it has at most 1000 entries; its largest magnitude taken a
    block of frequencies at a time, :func:`substruct.io.blocks.max_abs`)."""
    model = result.model
    out: dict[str, Any] = {"case": result.case_name, "files": [str(f) for f in files],
                           "attrs": {k: (v if isinstance(v, (str, int, float, bool)) else str(v))
                                     for k, v in result.attrs.items()},
                           "model": {"substructures": list(model.substructure_names),
                                     "kinds": list(model.substructure_kinds),
                                     "n_dof": int(model.offsets[-1]),
                                     "constraints": list(model.constraint_labels)}}
    if result.modes is not None:
        out["modes"] = modes_json(result.modes)
    if result.variants:
        out["variants"] = {k: modes_json(v) for k, v in result.variants.items()}
    if result.frf is not None:
        frf = result.frf
        H = frf.H if isinstance(frf.H, StreamedArray) else np.asarray(frf.H)
        out["frf"] = {"method": frf.method, "n_omega": int(len(frf.omega)),
                      "omega_range": [json_number(frf.omega.min()),
                                      json_number(frf.omega.max())],
                      "inputs": list(frf.inputs), "outputs": list(frf.outputs),
                      "max_abs_H": json_number(max_abs(H)),
                      "constraint_residual": json_number(frf.constraint_residual),
                      "agreement": {k: json_number(v) for k, v in frf.agreement.items()}}
        if H.size <= 1000:
            H = np.asarray(H)  # a streamed output this small is kept whole
            out["frf"]["H"] = {"real": H.real.tolist(), "imag": H.imag.tolist()}
    if result.transient is not None:
        out["transient"] = transient_json(result.transient)
    if result.random is not None:
        out["random"] = random_json(result.random)
    if result.base_frf is not None:
        out["base_frf"] = base_frf_json(result.base_frf)
    if result.srs is not None:
        out["srs"] = srs_json(result.srs)
    if result.recovery:
        out["recovery"] = recovery_json(result.recovery)
    out.update(testlab_json(result))
    return out


def vp_minima(ind: Any) -> str:
    """The smallest consistency indicators of a transformed part, over frequencies (and
    channels): overall and specific, sensors and impacts (1 when the adapter moves rigidly)."""
    def least(d: dict) -> str:
        return f"{min(float(np.min(v)) for v in d.values()):.4f}" if d else "-"
    return (f"min consistency, sensors {least(ind.overall_u)} (specific "
            f"{least(ind.specific_u)}), impacts {least(ind.overall_f)} (specific "
            f"{least(ind.specific_f)})")


def print_modes(modes: Any, out: TextIO, requested: int | None = None) -> None:
    """The table of physical modes, the spurious roots set aside and the check figures."""
    n = len(modes.omega)
    more = f" of {requested} requested" if requested is not None and requested > n else ""
    out.write(f"  {n} physical mode(s){more}, {modes.method}:\n")
    if str(modes.solver).startswith("amls"):
        out.write(f"  solver: {modes.solver}\n")
    if not n and "no free coordinate" in modes.solver:
        out.write(f"  no mode: {modes.solver.split('; ', 1)[-1]}\n")
    out.write(f"  {'mode':>4s}  {'omega (rad/s)':>14s}  {'f (Hz)':>12s}  "
              f"{'damping ratio':>13s}  {'|A u| residual':>14s}\n")
    for j in range(n):
        zeta = float(modes.damping_ratio[j])
        zeta = 0.0 if abs(zeta) < 5e-13 else zeta  # no "-0.0000" from round-off
        out.write(f"  {j + 1:4d}  {modes.omega[j]:14.4f}  {modes.freq_hz[j]:12.4f}  "
                  f"{zeta:13.4f}  {modes.residual[j]:14.1e}\n")
    if len(modes.spurious):
        out.write(f"  spurious roots set aside: {len(modes.spurious)}\n")
        for reason, count in spurious_counts(modes).items():
            out.write(f"    {count} x {reason}\n")
    if modes.agreement:
        figures = ", ".join(f"{k} {v:.1e}" for k, v in modes.agreement.items())
        what = "max relative eigenvalue difference; *-residual: relative residual of " \
            "these modes in that formulation's equations" if any(
                k.endswith("-residual") for k in modes.agreement) else \
            "max relative eigenvalue difference"
        out.write(f"  agreement with check formulations ({what}): {figures}\n")


def print_frf(frf: Any, out: TextIO) -> None:
    """The receptances: span, residual and checks; ``H`` itself for up to three frequencies
    and 64 pairs, else the peak of each of the first 6 x 6 pairs (from selections: a streamed
    output gives the curves it kept)."""
    H = frf.H if isinstance(frf.H, StreamedArray) else np.asarray(frf.H)
    w = np.asarray(frf.omega)
    span = f"omega = {w[0]:g} rad/s" if len(w) == 1 else \
        f"{len(w)} frequencies, {w.min():g} to {w.max():g} rad/s"
    out.write(f"FRF ({frf.method}): {span}, {len(frf.outputs)} output(s) x "
              f"{len(frf.inputs)} input(s)\n")
    out.write("  constraint residual, rows at unit norm, max|A q - R F| / max|H|: "
              f"{frf.constraint_residual:.1e}\n")
    zero = "exact-zero" in frf.agreement
    if zero:
        out.write("  no free coordinate: the constraints hold every coordinate, every "
                  "receptance is exactly zero\n")
    if frf.agreement:
        figures = ", ".join(f"{k} {v:.1e}" for k, v in frf.agreement.items())
        what = "max |H - H_check| / h0, h0 = max|o| max|e| / min|Z|: the compliance scale" \
            if zero else "max |H - H_check| / max |H|"
        out.write(f"  agreement with check formulations ({what}): {figures}\n")
    if len(w) <= 3 and H.shape[1] * H.shape[2] <= 64:
        width = max(len(s) for s in frf.outputs)
        for k, wk in enumerate(w):
            out.write(f"  H at omega = {wk:g} rad/s (rows: outputs, columns: inputs "
                      f"{', '.join(frf.inputs)}):\n")
            sci = needs_scientific(H[k])
            for i, name in enumerate(frf.outputs):
                row = "  ".join(f"{complex_text(z, scientific=sci):>{22 if sci else 16}s}"
                                for z in H[k, i])
                out.write(f"    {name:<{width}s}  {row}\n")
        return
    for i, o in enumerate(frf.outputs[:6]):
        for j, inp in enumerate(frf.inputs[:6]):
            mag = np.abs(H[:, i, j])
            k = int(np.argmax(mag))
            out.write(f"  {o} / {inp}: max |H| = {mag[k]:.4g} at omega = {w[k]:.4g} rad/s\n")


def print_summary(result: Result, out: TextIO, requested: int | None = None,
                  drops: dict[str, list[str]] | None = None) -> None:
    """The model in one line, then the modes, each variant (with the constraints it drops)
    and the receptances."""
    model = result.model
    names = model.substructure_names
    out.write(f"{result.case_name}: {int(model.offsets[-1])} coordinates in {len(names)} "
              f"substructure(s) ({', '.join(names)}), {len(model.constraint_labels)} "
              f"constraint row(s)\n")
    if any(str(k).startswith("rigid_body:") for k in result.attrs):  # superelements only
        from substruct.builder.superelements import rigid_body_lines

        for line in rigid_body_lines(result.attrs):
            out.write(line + "\n")
    if result.modes is not None:
        out.write("modes\n")
        print_modes(result.modes, out, requested)
    for name, modes in result.variants.items():
        dropped = f" (drops {', '.join(drops[name])})" if drops and name in drops else ""
        out.write(f"variant {name}{dropped}\n")
        print_modes(modes, out, requested)
    if result.frf is not None:
        print_frf(result.frf, out)
    for part, ind in result.virtual_points.items():
        out.write(f"  virtual points of {part}: " + vp_minima(ind) + "\n")
    mc = result.monte_carlo
    if mc is not None:
        spread = mc.relative_spread()
        out.write(f"  noise {mc.level:g} on the measured receptances, {mc.samples} samples: "
                  f"relative spread of the coupled result median {np.median(spread):.3g}, "
                  f"max {spread.max():.3g}\n")
    for line in testlab_lines(result):
        out.write(line + "\n")
    if result.transient is not None:
        print_transient(result.transient, out, str(result.attrs.get("units", "")))
    if result.random is not None:
        print_random(result.random, out)
    if result.base_frf is not None:
        print_base_frf(result.base_frf, out)
    if result.srs is not None:
        print_srs(result.srs, out)
    print_recovery(result.recovery, out)
