"""The shipped transient cases through the command line: the box beam with its tuned absorbers
under a step load (direct vs the null-space form and modal superposition, the drift figure,
Newmark's energy balance, the static equilibrium the step response oscillates about)."""

import json
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from cli_helpers import run
from substruct.case.loader import load_case
from substruct.io import hdf5 as results
from substruct.run.runner import build_model

CASES = Path(__file__).resolve().parents[1] / "cases"


def test_box_beam_step_direct_and_checks_agree(tmp_path, capsys):
    out = tmp_path / "out"
    code, text, err = run(capsys, "run", CASES / "box_beam_step.yaml", "--out", out, "--json")
    assert code == 0, err
    data = json.loads(text)["transient"]
    assert data["steps"] == 500 and data["method"] == "generalized-inverse"
    assert data["agreement"]["null-space"] < 1e-10 and data["agreement"]["modal"] < 1e-6
    assert data["drift"] < 1e-13
    assert data["energy_balance_change"] < 1e-10
    tr = results.load(out / "box_beam_step.h5").transient
    assert tr.constraint_forces.shape == (501, 99)
    # the undamped beam rings about its static deflection under the step: the time average of
    # the tip over whole periods of the slow absorber is near K^-1 F on A q = 0
    case = load_case(CASES / "box_beam_step.yaml")
    model = build_model(case)
    asm = model.assembly
    tip = asm.rows([model.points["right@1,0.05,0.1:z"]])
    n, m = asm.n_dof, asm.A.shape[0]
    kkt = sp.block_array([[asm.K, asm.A.T], [asm.A, None]], format="csc")
    rhs = np.concatenate([-1000.0 * np.asarray(tip.todense()).ravel(), np.zeros(m)])
    static = float((tip @ sp.linalg.spsolve(kkt, rhs)[:n])[0])
    mean = float(tr.displacement[:, 0].mean())
    assert abs(mean - static) < 0.02 * abs(static), (mean, static)
