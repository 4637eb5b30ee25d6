"""The energy balance T + V - W + D of every transient route held as a check
(substruct/analysis/transient/record.py, integrators.py): constant to rounding for Newmark's
average acceleration when W counts the work of every load of the integrated equations (the
loads, the effective loads of a moving ground and of a nonhomogeneous constraint, the
reactions of moving supports), and a one-line CheckError when it is not."""

from pathlib import Path

import numpy as np
import pytest

from cli_helpers import run
from substruct.analysis.errors import CheckError
from substruct.analysis.transient import (
    InitialConditions,
    LoadHistory,
    TransientOptions,
    TransientOutputs,
    transient,
)
from substruct.analysis.transient.base import BaseMotion
from substruct.analysis.transient.record import Recorder, energy_change

CASES = Path(__file__).resolve().parents[1] / "cases"
FORMS = ["generalized-inverse", "null-space", "modal"]
N, DT = 800, 2e-3
#: rounding of N steps, each exact to a few eps of the energies, times the spread of S
#: (omega_max h ~ 1 here): N * 1e3 * eps ~ 2e-10
ROUND = N * 1e3 * np.finfo(float).eps


def _chain(n: int = 5):
    """A damped spring chain of ``n`` masses, coordinate 0 the massless ground point; a tie
    row makes the constraints coupled (q_3 = q_4 + b_1)."""
    M = np.diag([0.0] + [1.0 + 0.3 * i for i in range(1, n)])
    K = np.zeros((n, n))
    for i in range(n - 1):
        k = 400.0 * (1 + 0.5 * i)
        K[i:i + 2, i:i + 2] += k * np.array([[1.0, -1.0], [-1.0, 1.0]])
    C = 1e-3 * K + 0.05 * M
    A = np.zeros((2, n))
    A[0, 0] = 1.0
    A[1, 3], A[1, 4] = 1.0, -1.0
    return M, C, K, A


def _run(form: str, *, base: bool, b=None, static: bool = False, damped: bool = True,
         integrator: str = "newmark"):
    M, C, K, A = _chain()
    t = DT * np.arange(N + 1)
    f = np.where(t >= 0.3, 50.0, 0.0)[:, None]  # a step force at the tip: a jump in a step
    if static:
        f = f + 20.0
    B = np.zeros((5, 1))
    B[-1, 0] = 1.0
    ground = None
    if base:
        g = np.where(t <= 0.1, 9.81 * np.sin(np.pi * t / 0.1), 0.0)
        ground = BaseMotion(np.array([1.0, 0.0]), "acceleration", g)
    return transient(M, C if damped else None, K, A, b, LoadHistory(B, f, DT, N, base=ground),
                     TransientOutputs(np.eye(5)), initial=InitialConditions(static=static),
                     options=TransientOptions(method=form, integrator=integrator))


@pytest.mark.parametrize("form", FORMS)
def test_base_excited_chain_closes_its_balance(form):
    tr = _run(form, base=True)
    change = energy_change(tr.energy)[0]
    assert change < ROUND, change
    # the ground's work is the bulk of the energy: without it the balance would not close
    scale = np.abs(tr.energy).max()
    assert np.abs(tr.energy[:, 2]).max() > 0.5 * scale


@pytest.mark.parametrize("form", FORMS)
def test_force_driven_chain_with_nonhomogeneous_constraint_and_static_start(form):
    tr = _run(form, base=False, b=np.array([0.0, 0.01]), static=True)
    assert energy_change(tr.energy)[0] < ROUND
    assert abs(tr.energy[-1, 2]) > 0.1 * np.abs(tr.energy).max()


def test_undamped_base_motion_by_generalized_alpha_at_rho_one_is_exact_too():
    tr = _run("generalized-inverse", base=True, damped=False, integrator="generalized-alpha")
    assert energy_change(tr.energy)[0] < ROUND


def test_an_inconsistent_work_is_a_one_line_check_error(monkeypatch):
    def half(self, step, work):  # the work counted at half its value
        self.energy[-1][2], self.energy[-1][3] = 0.5 * work.external, work.dissipated

    monkeypatch.setattr(Recorder, "on_work", half)
    with pytest.raises(CheckError, match=r"^transient: energy balance T \+ V - W \+ D of "
                                         r"generalized-inverse changes by \d\.\de[+-]\d\d of "
                                         r"the largest energy \(tolerance 1e-06\)$"):
        _run("generalized-inverse", base=True)


def test_superelement_case_inconsistent_work_exits_1_with_one_line(tmp_path, capsys,
                                                                     monkeypatch):
    monkeypatch.setattr(Recorder, "on_work", lambda self, step, work: None)  # W, D left 0
    out = tmp_path / "out"
    code, text, err = run(capsys, "run", CASES / "two_superelements.yaml", "--out", out,
                          "--no-pictures")
    assert code == 1 and "Traceback" not in err, err
    errors = [line for line in err.splitlines() if line.startswith("substruct: error: ")]
    assert len(errors) == 1 and err.endswith(errors[0] + "\n"), err  # progress lines before it
    assert errors[0].startswith("substruct: error: transient: energy balance T + V - W + D of "
                                "generalized-inverse changes by 1.0e+00 of the largest energy "
                                "(tolerance 1e-06)"), err
    assert not out.exists() or not any(out.glob("*.h5"))


@pytest.mark.parametrize("name", ["tapered_rod_impact", "box_beam_step", "two_superelements",
                                  "tapered_rod_shock"])
def test_shipped_transient_cases_close_their_balance(tmp_path, capsys, name):
    import json
    code, text, err = run(capsys, "run", CASES / f"{name}.yaml", "--out", tmp_path, "--json",
                          "--no-pictures")
    assert code == 0, err
    assert json.loads(text)["transient"]["energy_balance_change"] < 1e-9


def test_generalized_alpha_below_one_is_reported_not_held():
    import io

    from substruct.cli.transient_summary import print_transient
    # a stiff mode (omega h = 1e3) released with rho_inf = 0: the nodal balance rises by the
    # largest energy before the scheme damps it; no bound of the scheme applies, no error
    tr = transient(np.eye(1), None, np.diag([1e12]), None, None,
                   LoadHistory(np.zeros((1, 1)), np.zeros((6, 1)), 1e-3, 5),
                   TransientOutputs(np.eye(1)), initial=InitialConditions(d0=np.ones(1)),
                   options=TransientOptions(integrator="generalized-alpha", rho_inf=0.0))
    change = energy_change(tr.energy)[0]
    assert change > 0.5
    out = io.StringIO()
    print_transient(tr, out)
    assert (f"changes by {change:.1e} of the largest energy (not held: the scheme's numerical "
            "dissipation)") in out.getvalue()
