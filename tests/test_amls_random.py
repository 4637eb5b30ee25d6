"""The random response on the AMLS basis (``analysis.random.method: modal`` with
``modal.solver: amls``) against the direct random response of the same case.

The model: two solid boxes ``2 x 0.5 x 0.5`` tied at x = 2, Rayleigh damping ``[5, 2e-5]``;
the face x = 0 of the left one held in x and y, and in z by nine constraint rows (one a node),
which ``base`` moves.  Two inputs: two uncorrelated force PSDs (1 and 2 -> 0.5 N^2/Hz), or a
flat base acceleration PSD; outputs the tip's z and a point's x; 120 frequencies 5 to 600 Hz;
the modal sum keeps the roots below 3 x 600 Hz with the second-order residual.
The error is ``max |S_y - S_y,direct| / max |S_y,direct|`` over the grid and the outputs.
What is asserted:

* every block's modes kept: the PSDs of the Lanczos modal sum of as many roots, to the
  eigensolvers' accuracy over the damping ratio at the peaks (measured 4.4e-8); what is left against the direct response is the modal sum's own truncation,
  which falls as its cut-off grows (3 -> 6 x the highest frequency: 1.0e-4 -> 3.8e-5 with
  forces, 3.4e-7 -> 1.7e-8 with the base);
* truncated (AMLS cut-off 2, 3, 5 x the wanted frequency): the error falls (measured 1.1e-2,
  1.1e-2, 1.1e-3 with forces; 8.3e-3, 5.1e-3, 1.7e-4 with the base), the RMS values with it (largest
  relative error 1.4e-2, 8.1e-3, 3.2e-3 with forces; 3.3e-1, 1.6e-2, 7.2e-3 with the base,
  whose second output moves little), and the run's own direct check of
  each receptance sum (kkt at 3 frequencies) sees the error of the same order.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from substruct.case.loader import parse_case
from substruct.run.runner import run_case

ROOT = Path(__file__).resolve().parent.parent
FACE = [(y, z) for y in (0, 0.25, 0.5) for z in (0, 0.25, 0.5)]
INPUTS = {
    "forces": "    forces:\n"
              "      - {at: \"right@4,0.5,0.5:z\", psd: [[5, 1.0], [600, 1.0]]}\n"
              "      - {at: \"right@3,0.5,0.5:y\", psd: [[5, 2.0], [600, 0.5]]}\n",
    "base": "    base: {at: [" + ", ".join(f'"left@0,{y},{z}:z"' for y, z in FACE) +
            "], psd: [[5, 0.04], [600, 0.04]]}\n",
}


def case_text(inputs: str, method: str) -> str:
    """The case of the module docstring with the random inputs and the method lines."""
    box = "{lengths: [2.0, 0.5, 0.5], divisions: [8, 2, 2]"
    damping = "    damping: {rayleigh: [5.0, 2.0e-5]}\n"
    rows = "".join(f"  - {{name: base{i}, terms: {{\"left@0,{y},{z}:z\": 1}}}}\n"
                   for i, (y, z) in enumerate(FACE))
    return ("name: boxes\nsubstructures:\n"
            f"  - name: left\n    type: solid\n    box: {box}}}\n"
            "    E: 2.1e11\n    nu: 0.3\n    rho: 7850\n"
            "    fixed: [{set: xmin, components: [x, y]}]\n" + damping +
            f"  - name: right\n    type: solid\n    box: {box}, origin: [2, 0, 0]}}\n"
            "    E: 2.1e11\n    nu: 0.3\n    rho: 7850\n" + damping +
            "interfaces:\n"
            "  - {name: a, between: [left, right], nodes: {box: [[2, 0, 0], [2, 0.5, 0.5]]}}\n"
            "constraints:\n" + rows +
            "analysis:\n  random:\n    frequencies: {start: 5, stop: 600, num: 120}\n"
            "    rms_tolerance: 1.0\n"     # a coarse grid: the PSDs are compared on it
            "    outputs: [\"right@4,0.5,0.5:z\", \"right@2.5,0.25,0.5:x\"]\n" + inputs +
            method + "    tolerance: 1.0\noutput: {pictures: false}\n")


def random(inputs: str, modal: str | None = None):
    method = "" if modal is None else f"    method: modal\n    modal: {modal}\n"
    return run_case(parse_case(case_text(INPUTS[inputs], method), "boxes.yaml", ROOT)).random


def error(r, ref) -> float:
    return float(np.abs(r.psd - ref.psd).max() / np.abs(ref.psd).max())


@pytest.fixture(scope="module", params=["forces", "base"])
def direct(request):
    return request.param, random(request.param)


def test_every_block_mode_kept_is_the_lanczos_modal_sum(direct):
    inputs, ref = direct
    exact = {c: random(inputs, f"{{solver: amls, cutoff: {c}, amls: {{cutoff: 1e6, "
                               f"leaf_size: 60}}}}") for c in (3, 6)}
    count = int(re.search(r"modal: (\d+) root", exact[3].method).group(1))
    assert count >= 15 and "(AMLS basis)" in exact[3].method
    lanczos = random(inputs, f"{{solver: sparse, count: {count}}}")
    # the same roots, to the eigensolvers' accuracy (about 1e-10 relative) divided by the
    # damping ratio at the peaks (about 1e-2): measured 4.4e-8
    assert error(exact[3], lanczos) < 1e-6, error(exact[3], lanczos)
    # the rest is the modal sum's truncation: it falls with the modal cut-off
    e3, e6 = error(exact[3], ref), error(exact[6], ref)
    assert e6 < e3 / 2 and e3 < 1e-3, (e3, e6)
    np.testing.assert_allclose(exact[3].rms, ref.rms, rtol=1e-3)


def test_truncated_amls_converges_and_its_error_is_the_receptances(direct):
    inputs, ref = direct
    runs = [random(inputs, f"{{solver: amls, cutoff: 3, amls: {{cutoff: {r}, "
                           f"leaf_size: 60}}}}") for r in (2, 3, 5)]
    errs = [error(r, ref) for r in runs]
    assert errs[0] > errs[1] > errs[2] and errs[2] < errs[0] / 5, errs
    for r in runs:   # each sum checked against the direct receptance by the run itself
        (name, e), = r.agreement.items()
        assert name == "kkt (3 frequencies)" and e < errs[0]
    rms = [float(np.abs(r.rms / ref.rms - 1).max()) for r in runs]
    assert rms[2] < rms[0] / 2, rms
