"""The modal transient of a free body whose kept modes are its rigid-body modes alone, against
the direct integration (the generalized-inverse form, Newmark's average acceleration, same
step).

A free steel bar (8 x 3 x 3 Q1 hexahedra, 432 coordinates, first flexible mode 3,782 rad/s)
under a step force at a corner, 50 steps of 1 ms: the Nyquist frequency (3,142 rad/s) is
below the first flexible mode, so the modes kept are the six rigid-body modes, and the
elastic response is the static correction's (inertia relief).  The modes' eigenvalues are
round-off; the rigid-body decision was made against the largest of the modes kept (round-off
itself), so they were read as elastic and the static correction divided by them: errors of
0.72 (dense), 1.36 (sparse), 10.0 (AMLS with a count) and 2.7e-2 (AMLS below 0.5 x pi / dt)
where the bare modal sum is within 2.8e-4.  What is asserted: with the static correction the
four bases give the same response, within 1e-3 of the direct integration (measured
1.5e-4) and closer to it than the bare modal sum.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from substruct.case.loader import parse_case
from substruct.run.runner import run_case

ROOT = Path(__file__).resolve().parent.parent

CASE = """\
name: free_bar
substructures:
  - name: b
    type: solid
    box: {lengths: [2.0, 0.5, 0.5], divisions: [8, 3, 3]}
    E: 2.1e11
    nu: 0.3
    rho: 7850
analysis:
  transient:
    t_end: 0.05
    dt: 1.0e-3
    integrator: newmark
    method: METHOD
    loads:
      - {point: "b@2,0.5,0.5:z", amplitude: -1000, shape: step}
    outputs: ["b@2,0.5,0.5:z", "b@0,0,0:z"]
"""


def response(method: str, modal: str = "") -> np.ndarray:
    block = "".join(f"    {line}\n" for line in modal.splitlines())
    text = CASE.replace("METHOD", method) + block + "output: {pictures: false}\n"
    return run_case(parse_case(text, "free_bar.yaml", ROOT)).transient.displacement


@pytest.fixture(scope="module")
def direct():
    return response("generalized-inverse")


@pytest.fixture(scope="module")
def bare():
    return response("modal", "modal_count: 6\nmodal: {solver: dense, residual: none}")


def error(y: np.ndarray, ref: np.ndarray) -> float:
    return float(np.abs(y - ref).max() / np.abs(ref).max())


@pytest.mark.parametrize("modal", [
    "modal_count: 6\nmodal: {solver: dense}",
    "modal_count: 6\nmodal: {solver: sparse}",
    "modal_count: 6\nmodal: {solver: amls}",
    "modal: {solver: amls, cutoff: 0.5, amls: {leaf_size: 50}}",
])
def test_rigid_modes_alone_with_the_static_correction(direct, bare, modal):
    y = response("modal", modal)
    assert error(y, direct) < 1e-3
    assert error(y, direct) < error(bare, direct)
