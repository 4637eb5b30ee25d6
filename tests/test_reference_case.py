"""The shipped reference case is what it claims, and a mode count is checked against the built
model whatever the discretization (issue 14, docs/convergence.md "Modal truncation under
constraints")."""

from pathlib import Path

import numpy as np
import pytest

from substruct.case.loader import CaseError, load_case
from substruct.run.runner import build_model, run_case

CASES = Path(__file__).resolve().parent.parent / "cases"
FE = CASES / "tapered_rod_fe.yaml"
#: The limit of docs/convergence.md: P2 with 512 elements, Richardson-extrapolated with 256.
LIMIT = np.array([31.5586551115, 55.3940016177, 62.4125587544, 83.9098193219, 128.6749611531,
                  153.4977754055])
LIMIT_FREE = np.array([22.5655497729, 53.0160197043, 60.8216110695, 83.695299765,
                       97.2989935423, 135.696553158])


def test_reference_case_agrees_with_the_refined_mesh_limit():
    result = run_case(load_case(FE))
    err = np.abs(result.modes.omega / LIMIT - 1)
    free = np.abs(result.variants["without_eq52"].omega / LIMIT_FREE - 1)
    assert err.max() < 1.1e-6 and free.max() < 7e-7, (err, free)  # the figures the docs state
    assert err[:4].max() < 3e-8


def test_modal_truncation_under_the_constraint_converges_as_one_over_g():
    errs = []
    for g in (20, 40):
        result = run_case(load_case(FE, [f"substructures.rod.reduce.modes={g}",
                                         "analysis.modes.variants=[]"]))
        errs.append(abs(result.modes.omega[0] / LIMIT[0] - 1))
    assert errs[0] == pytest.approx(1.31e-2, rel=0.02)    # 31.9736 rad/s, as the issue found
    assert 1.8 < errs[0] / errs[1] < 2.3                   # first order in g


def test_count_larger_than_the_built_model_is_an_error():
    case = load_case(FE, ["analysis.modes.count=500", "substructures.rod.discretization.elements=8"])
    with pytest.raises(CaseError, match=r"analysis.modes.count: more modes than the 22 "
                                        r"coordinates of the model, got 500"):
        build_model(case)
