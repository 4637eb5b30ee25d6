"""What ``substruct run`` and ``substruct info`` print about a transient response (paper eqs 5,
10), and its part of ``--json``: the form and integrator, the steps, the drift figure
:math:`\\max_k |A q_k - b| / \\max_k |q_k|`, the checks' agreement and the peak values at the
output points."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, TextIO

import numpy as np

if TYPE_CHECKING:
    from substruct.analysis.transient.results import Transient

__all__ = ["peaks", "transient_json", "print_transient", "MAX_FORCES"]

#: Constraint forces whose peak the table shows (the first rows).
MAX_FORCES = 8

#: The recorded histories and the unit of each (the case's units).
HISTORIES = (("displacement", "length"), ("velocity", "length/time"),
             ("acceleration", "length/time^2"))


def _number(x: float) -> Any:
    x = float(x)
    return x if np.isfinite(x) else None


def peaks(values: np.ndarray, t: np.ndarray) -> list[tuple[float, float]]:
    r"""Per column of ``values`` (``n_samples x k``): ``(peak, t_peak)``, the value of largest
    magnitude (with its sign) and its instant, :math:`v_{k^*}`, :math:`k^* =
    \arg\max_k |v_k|`."""
    out = []
    for j in range(values.shape[1] if values.ndim == 2 and values.shape[0] else 0):
        k = int(np.argmax(np.abs(values[:, j])))
        out.append((float(values[k, j]), float(t[k])))
    return out


def transient_json(tr: Transient) -> dict[str, Any]:
    """The transient response as JSON-safe data (no histories: they are in the file)."""
    out: dict[str, Any] = {
        "method": tr.method, "integrator": tr.integrator, "rho_inf": _number(tr.rho_inf),
        "dt": _number(tr.dt), "steps": tr.steps, "samples": int(len(tr.t)),
        "t_end": _number(tr.t[-1]) if len(tr.t) else 0.0, "drift": _number(tr.drift),
        "agreement": {k: _number(v) for k, v in tr.agreement.items()},
        "tolerance": _number(tr.tolerance), "solver": tr.solver, "outputs": list(tr.outputs),
        "peaks": {}}
    for name, _ in HISTORIES:
        out["peaks"][name] = {o: {"value": _number(v), "t": _number(t)} for o, (v, t)
                              in zip(tr.outputs, peaks(getattr(tr, name), tr.t))}
    if tr.constraint_forces.size:
        out["peaks"]["constraint_forces"] = {
            c: {"value": _number(v), "t": _number(t)} for c, (v, t)
            in zip(tr.constraint_labels, peaks(tr.constraint_forces, tr.t))}
    if tr.energy.shape[0]:
        E = tr.energy_balance()
        scale = max(float(np.abs(tr.energy).max()), 1e-300)
        out["energy_balance_change"] = _number(np.abs(E - E[0]).max() / scale)
    return out


def print_transient(tr: Transient, out: TextIO, units: str = "") -> None:
    """The transient block of the run and info tables; ``units``: the case's units, shown
    with the peaks."""
    rho = f", rho_inf {tr.rho_inf:g}" if tr.integrator == "generalized-alpha" else ""
    out.write(f"transient ({tr.integrator}{rho}, {tr.method}): {tr.steps} steps of "
              f"dt = {tr.dt:g} to t = {tr.t[-1] if len(tr.t) else 0.0:g}, "
              f"{len(tr.t)} samples\n")
    out.write(f"  constraint drift max|A q - b| / max|q|: {tr.drift:.1e}\n")
    if tr.agreement:
        figures = ", ".join(f"{k} {v:.1e}" for k, v in tr.agreement.items())
        out.write(f"  agreement with check forms (max |y - y_check| / max |y|): {figures} "
                  f"(tolerance {tr.tolerance:.0e})\n")
    data = transient_json(tr)
    if "energy_balance_change" in data:
        held = (f"tolerance {tr.tolerance:.0e}" if tr.integrator == "newmark" or tr.rho_inf == 1
                else "not held: the scheme's numerical dissipation")
        out.write(f"  energy balance T + V - W + D: changes by "
                  f"{data['energy_balance_change']:.1e} of the largest energy ({held})\n")
    if tr.outputs:
        where = f" ({units})" if units else ""
        out.write(f"  peaks at the output points{where}: value (at t)\n")
        width = max(len(o) for o in tr.outputs)
        out.write(f"    {'point':<{width}s}  {'displacement':>22s}  {'velocity':>22s}  "
                  f"{'acceleration':>22s}\n")
        cols = [peaks(getattr(tr, name), tr.t) for name, _ in HISTORIES]
        for i, o in enumerate(tr.outputs):
            cells = "  ".join(f"{f'{c[i][0]:.4g} ({c[i][1]:.4g})':>22s}" for c in cols)
            out.write(f"    {o:<{width}s}  {cells}\n")
    shown = list(zip(tr.constraint_labels, peaks(tr.constraint_forces, tr.t)))
    for label, (v, t) in shown[:MAX_FORCES]:
        out.write(f"  peak constraint force {label}: {v:.4g} at t = {t:.4g}\n")
    if len(shown) > MAX_FORCES:
        out.write(f"  (+{len(shown) - MAX_FORCES} more constraint forces in the results file)\n")
