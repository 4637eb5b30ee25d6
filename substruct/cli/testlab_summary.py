"""The summary lines of the test-lab analyses (``analysis.tpa``, ``analysis.semm``), printed by
``substruct run`` and ``substruct info``."""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["testlab_lines", "testlab_json"]


def testlab_lines(result: Any) -> list[str]:
    """One line for the transfer path analysis and one for the model mixing of ``result``
    (none for what it does not hold)."""
    out = []
    tpa = getattr(result, "tpa", None)
    if tpa is not None and getattr(tpa, "transmissibility", None) is not None:
        out.append(f"  transfer paths (operational): transmissibility from "
                   f"{len(tpa.indicators)} indicator(s) to {len(tpa.targets)} target(s); "
                   f"operating condition {tpa.validation_condition} predicted, validation "
                   f"error median {float(np.median(tpa.error)):.3g}, "
                   f"max {float(np.max(tpa.error)):.3g}")
    elif tpa is not None:
        out.append(f"  transfer paths ({tpa.method}): blocked forces at {len(tpa.interface)} "
                   f"interface coordinate(s) from {len(tpa.indicators)} response(s); "
                   f"validation error at {len(tpa.targets)} target(s): median "
                   f"{float(np.median(tpa.error)):.3g}, max {float(np.max(tpa.error)):.3g}")
    semm = getattr(result, "semm", None)
    if semm is not None:
        ind = semm.indicator[np.isfinite(semm.indicator)]
        quality = (f"validation coherence min {float(ind.min()):.4f}, median "
                   f"{float(np.median(ind)):.4f}") if ind.size else \
            "no measured entry off the boundary to validate with"
        if getattr(semm, "channel_coherence", None) is not None:
            med = np.median(semm.channel_coherence, axis=0)
            quality += (f"; channel coherence (median) lowest {float(med.min()):.4f} at "
                        f"{semm.measured_outputs[int(np.argmin(med))]}")
        form = getattr(semm, "form", "standard")
        out.append(f"  model mixing{' (extended)' if form == 'extended' else ''}: "
                   f"{len(semm.outputs)} x {len(semm.inputs)} model, "
                   f"boundary {len(semm.boundary_outputs)} x {len(semm.boundary_inputs)} of "
                   f"{len(semm.measured_outputs)} x {len(semm.measured_inputs)} measured; "
                   + quality)
    return out


def _number(x: float) -> float | None:
    return float(x) if np.isfinite(x) else None


def testlab_json(result: Any) -> dict[str, Any]:
    """``virtual_points`` (the smallest indicators of each transformed part), ``tpa`` and
    ``semm`` of ``result`` as JSON-safe data (keys only for what it holds)."""
    out: dict[str, Any] = {}
    vps = getattr(result, "virtual_points", {}) or {}
    if vps:
        out["virtual_points"] = {
            part: {key: _number(min((float(np.min(v)) for v in getattr(ind, key).values()),
                                    default=float("nan")))
                   for key in ("overall_u", "overall_f", "specific_u", "specific_f")}
            for part, ind in vps.items()}
    tpa = getattr(result, "tpa", None)
    if tpa is not None:
        out["tpa"] = {"method": tpa.method, "interface": list(tpa.interface),
                      "indicators": list(tpa.indicators), "targets": list(tpa.targets),
                      "error_median": _number(np.median(tpa.error)),
                      "error_max": _number(np.max(tpa.error))}
    semm = getattr(result, "semm", None)
    if semm is not None:
        ind = semm.indicator[np.isfinite(semm.indicator)]
        out["semm"] = {"boundary_outputs": list(semm.boundary_outputs),
                       "boundary_inputs": list(semm.boundary_inputs),
                       "indicator_min": _number(ind.min()) if ind.size else None,
                       "indicator_median": _number(np.median(ind)) if ind.size else None}
    return out
