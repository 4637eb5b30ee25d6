r"""Den Hartog's closed-form tuning of a damped vibration absorber, to compare with a study.

A primary mode of natural frequency :math:`\omega_p` and mass-normalized shape :math:`\phi`
(:math:`\phi^T M \phi = 1`) seen at the absorber's point :math:`x_a` is a single oscillator of
equivalent modal mass :math:`M_{eq} = 1 / \phi(x_a)^2`.  An absorber of mass :math:`m_a`,
:math:`\mu = m_a / M_{eq}`, minimizes the peak of the primary's receptance (equal fixed points,
Den Hartog) with

.. math::  f_{opt} = \frac{\omega_a}{\omega_p} = \frac{1}{1 + \mu}, \qquad
           \zeta_{opt} = \sqrt{\frac{3 \mu}{8 (1 + \mu)^3}},

that is :math:`k_{opt} = m_a (f_{opt} \omega_p)^2` and
:math:`c_{opt} = 2 \zeta_{opt} m_a \omega_p`: Den Hartog's damping ratio is
:math:`c / c_c` with :math:`c_c = 2 m_a \omega_p`, the primary's frequency (in the absorber's
own, :math:`c / (2 m_a f_{opt} \omega_p) = \sqrt{3\mu / (8 (1 + \mu))}`, the same ``c``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from substruct.case.loader import Case

__all__ = ["DenHartog", "den_hartog", "grid_optimum", "absorber_tuning"]


@dataclass(frozen=True)
class DenHartog:
    """The closed-form tuning: mass ratio, frequency ratio, damping ratio, stiffness, damping."""

    mu: float
    f_opt: float
    zeta_opt: float
    k_opt: float
    c_opt: float


def den_hartog(omega_p: float, modal_mass: float, absorber_mass: float) -> DenHartog:
    """Den Hartog's tuning of an absorber of ``absorber_mass`` on a mode of ``omega_p`` (rad/s)
    and equivalent ``modal_mass`` at the absorber's point."""
    mu = float(absorber_mass) / float(modal_mass)
    f = 1.0 / (1.0 + mu)
    zeta = math.sqrt(3.0 * mu / (8.0 * (1.0 + mu) ** 3))
    w = f * float(omega_p)
    m = float(absorber_mass)
    return DenHartog(mu=mu, f_opt=f, zeta_opt=zeta, k_opt=m * w * w,
                     c_opt=2.0 * zeta * m * float(omega_p))


def grid_optimum(peaks: Sequence[float]) -> tuple[int, float]:
    """The sample of the smallest finite peak: ``(index, peak)``."""
    best, value = -1, math.inf
    for k, p in enumerate(peaks):
        if math.isfinite(p) and p < value:
            best, value = k, float(p)
    return best, value


def _mentions(point: Any, name: str) -> bool:
    text = str(point)
    return text == name or text.startswith(name + "@")


def absorber_tuning(case: Case) -> tuple[str, DenHartog] | None:
    """Den Hartog's tuning of the absorber a two-parameter grid tunes, or ``None``.

    The absorber is the ``free-free`` spring-mass-damper whose ``stiffness`` and ``damping``
    are the grid's first and second parameters, by name, joined to the rest by one
    connection.  The primary is the case without it (and without its connection and the
    study): its modes are computed, the mode tuned is the one nearest the absorber's own
    frequency :math:`\\sqrt{k/m}` at the middle of the stiffness axis, and its equivalent mass
    at the attachment point is :math:`1/\\phi(x_a)^2` (mass-normalized shape).

    Returns:
        ``(absorber name, tuning)``; ``None`` when the study is not such a grid.
    """
    from substruct.case.loader import load_case
    from substruct.case.yaml_io import load_yaml
    from substruct.run.runner import build_model, run_case
    from substruct.studies.study_plan import axis_values

    spec = case.study
    if spec is None or spec.grid is None or len(spec.grid.parameters) != 2:
        return None
    k_name, c_name = spec.parameter_names()
    raw = load_yaml(case.text, case.source)
    entry = next((s for s in raw.get("substructures") or [] if isinstance(s, dict)
                  and s.get("type") == "free-free" and s.get("stiffness") == k_name
                  and s.get("damping") == c_name), None)
    if entry is None:
        return None
    name = str(entry["name"])
    chains = [c for c in raw.get("connections") or [] if any(_mentions(p, name) for p in c)]
    if len(chains) != 1 or len(chains[0]) != 2:
        return None
    where = next(str(p) for p in chains[0] if not _mentions(p, name))
    raw["substructures"] = [s for s in raw["substructures"] if s is not entry]
    raw["connections"] = [c for c in raw["connections"] if c is not chains[0]]
    raw.pop("study", None)
    raw["analysis"] = {"modes": raw.get("analysis", {}).get("modes") or {"count": 6}}
    raw["output"] = {"pictures": False}
    primary = load_case(raw)
    model = build_model(primary)
    modes = run_case(primary, model=model).modes
    absorber = case.substructure(name)
    if modes is None or absorber is None or where not in model.points:
        return None
    mass = float(getattr(absorber, "mass"))
    k_mid = float(np.median(axis_values(spec.grid.parameters[0])))
    i = int(np.argmin(np.abs(modes.omega - math.sqrt(k_mid / mass))))
    u = float((model.assembly.rows([model.points[where]]) @ modes.shapes[:, i]).real.item())
    return name, den_hartog(float(modes.omega[i]), 1.0 / u ** 2, mass)
