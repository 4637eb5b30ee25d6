"""The modal form of a free-free body (substruct/analysis/transient/modal.py): its rigid-body
mode is rigid whatever else is kept, so the static correction is the inertia-relief
flexibility, and the centre of mass moves as F t^2 / 2 m."""

from __future__ import annotations

import numpy as np
import yaml

from substruct import load_case, run_case

MASSES = np.array([1.0, 2.0, 1.0])
K = 1e4 * np.array([[1.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]])
F, RAMP = 4.0, 0.5


def _run(method: str, count: int | None = None, residual: str = "static"):
    block = {"t_end": 1.0, "dt": 1e-3, "method": method,
             "loads": [{"point": "P@q1", "amplitude": F, "shape": "ramp", "duration": RAMP}],
             "outputs": ["P@q1", "P@q2", "P@q3"]}
    if count is not None:
        block.update(modal_count=count, modal={"residual": residual})
    case = {"name": "free_chain",
            "substructures": [{"name": "P", "type": "matrices",
                               "M": np.diag(MASSES).tolist(), "K": K.tolist()}],
            "analysis": {"transient": block}}
    tr = run_case(load_case(yaml.safe_dump(case))).transient
    assert tr is not None
    return tr


def test_rigid_mode_alone_with_the_static_correction():
    """Only the rigid mode kept: its root (0 from the eigen solver, the rounding of
    Phi^T K Phi after the Rayleigh-Ritz) was judged against itself and not found rigid, and
    the static correction failed ('the constrained stiffness is singular')."""
    full = _run("generalized-inverse")
    t = full.t
    # centre of mass under the ramp F min(t / T, 1): closed form of x'' = F(t) / m
    m = MASSES.sum()
    cm = np.where(t < RAMP, F * t ** 3 / (6 * RAMP * m),
                  F * RAMP ** 2 / (6 * m) + F * RAMP * (t - RAMP) / (2 * m)
                  + F * (t - RAMP) ** 2 / (2 * m))
    peak = np.abs(full.displacement).max()
    errors = {}
    for residual in ("static", "none"):
        tr = _run("modal", 1, residual)
        # Newmark's displacement update misses h^3 a' / 12 a step of a linear acceleration
        newmark = 2 * 1e-3 ** 2 * F / (RAMP * m) * t[-1] / 12
        np.testing.assert_allclose(tr.displacement @ MASSES / m, cm, rtol=0, atol=newmark)
        errors[residual] = np.abs(tr.displacement - full.displacement).max() / peak
    # the elastic part is quasi-static under the slow ramp (its mode at 100 rad/s): the
    # inertia-relief correction holds it, the rigid mode alone does not
    assert errors["static"] < 0.05 * errors["none"], errors
    assert errors["none"] > 1e-4, errors
