"""A random response with one input that is 0 on the whole grid, another that is not.

Refused only when every input is 0 there (nothing to respond to: ``random_psd_zero_on_grid``
of the bad-case corpus); a zero input beside others adds nothing to the response PSDs, so the
RMS is that of the others alone.
"""

from __future__ import annotations

import numpy as np

from cli_helpers import DAMPED_THREE_MASS
from substruct.case.loader import parse_case
from substruct.run.runner import run_case

CASE = "name: two_forces\n" + DAMPED_THREE_MASS + """\
analysis:
  random:
    frequencies: {start: 0.1, stop: 2, num: 40}
    forces: FORCES
    outputs: [P@2, P@3]
    rms_tolerance: 1.0     # a coarse grid: the runs are compared with each other on it
output: {pictures: false}
"""
ONE = "[{at: P@2, psd: [[0.1, 1], [2, 1]]}]"
TWO = "[{at: P@1, psd: [[5, 1], [9, 1]]}, {at: P@2, psd: [[0.1, 1], [2, 1]]}]"


def rms(tmp_path, forces: str) -> np.ndarray:
    r = run_case(parse_case(CASE.replace("FORCES", forces), "r.yaml", tmp_path)).random
    assert r is not None
    return np.asarray(r.rms)


def test_a_zero_input_beside_another_adds_nothing(tmp_path):
    one, two = rms(tmp_path, ONE), rms(tmp_path, TWO)
    assert np.all(one > 0)
    assert np.allclose(two, one, rtol=1e-12, atol=0)
