"""The summary lines of the test-lab analyses (``analysis.tpa``, ``analysis.semm``), printed by
``substruct run`` and ``substruct info``."""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["testlab_lines"]


def testlab_lines(result: Any) -> list[str]:
    """One line for the transfer path analysis and one for the model mixing of ``result``
    (none for what it does not hold)."""
    out = []
    tpa = getattr(result, "tpa", None)
    if tpa is not None:
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
        out.append(f"  model mixing: {len(semm.outputs)} x {len(semm.inputs)} model, "
                   f"boundary {len(semm.boundary_outputs)} x {len(semm.boundary_inputs)} of "
                   f"{len(semm.measured_outputs)} x {len(semm.measured_inputs)} measured; "
                   + quality)
    return out
