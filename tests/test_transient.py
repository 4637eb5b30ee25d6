"""Constrained transient response (eqs 5, 10) against independent references: closed forms of
SDOF and 2-DOF systems with the integrators' measured order, the receptance at the forcing
frequency, the direct forms against modal superposition, the energy and constraint drift over
1e5 steps, the constraint force of a rigid tie."""

from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp

from substruct.analysis.formulations.coupling import receptance
from substruct.analysis.errors import CheckError
from substruct.analysis.transient.integrators import scheme
from substruct.analysis.transient import (
    InitialConditions,
    LoadHistory,
    TransientOptions,
    TransientOutputs,
    transient,
)
from substruct.case.loader import load_case
from substruct.run.runner import build_model

CASES = Path(__file__).resolve().parents[1] / "cases"


def _rate(hs, errs):
    return float(np.polyfit(np.log(hs), np.log(errs), 1)[0])


def _sdof(h, t_end, integrator, load=0.0, d0=1.0, c=0.0):
    m, k = 2.0, 800.0
    n = int(round(t_end / h))
    f = np.full((n + 1, 1), load)
    return transient(np.array([[m]]), None if c == 0 else np.array([[c]]), np.array([[k]]),
                     None, None, LoadHistory(np.ones((1, 1)), f, h, n),
                     TransientOutputs(np.eye(1)),
                     initial=InitialConditions(d0=np.array([d0])),
                     options=TransientOptions(integrator=integrator, rho_inf=0.7))


@pytest.mark.parametrize("integrator", ["newmark", "generalized-alpha"])
def test_sdof_free_vibration_is_second_order(integrator):
    w = np.sqrt(800.0 / 2.0)
    hs = [1e-3, 5e-4, 2.5e-4, 1.25e-4]
    errs = [float(np.abs(r.displacement[:, 0] - np.cos(w * r.t)).max())
            for r in (_sdof(h, 0.5, integrator) for h in hs)]
    assert 1.95 < _rate(hs, errs) < 2.05
    assert errs[-1] < 5e-6


def test_sdof_damped_step_response_is_second_order():
    m, k, c, F = 2.0, 800.0, 4.0, 3.0
    w = np.sqrt(k / m)
    z = c / (2 * m * w)
    wd = w * np.sqrt(1 - z * z)
    hs = [1e-3, 5e-4, 2.5e-4]
    errs = []
    for h in hs:
        r = _sdof(h, 0.5, "newmark", load=F, d0=0.0, c=c)
        t = r.t
        exact = F / k * (1 - np.exp(-z * w * t) * (np.cos(wd * t) + z * w / wd * np.sin(wd * t)))
        errs.append(float(np.abs(r.displacement[:, 0] - exact).max()))
    assert 1.95 < _rate(hs, errs) < 2.05


def test_two_dof_free_vibration_against_its_modes():
    M = np.diag([1.0, 3.0])
    K = np.array([[500.0, -200.0], [-200.0, 300.0]])
    w2, V = sla.eigh(K, M)
    q0 = np.array([0.01, -0.02])
    hs = [4e-4, 2e-4, 1e-4]
    errs = []
    for h in hs:
        n = int(round(0.4 / h))
        r = transient(M, None, K, None, None,
                      LoadHistory(np.zeros((2, 1)), np.zeros((n + 1, 1)), h, n),
                      TransientOutputs(np.eye(2)), initial=InitialConditions(d0=q0),
                      options=TransientOptions(integrator="generalized-alpha", rho_inf=0.9))
        exact = (V * np.cos(np.sqrt(w2)[None, :] * r.t[:, None])[:, None, :]
                 * (V.T @ M @ q0)[None, None, :]).sum(axis=2)
        errs.append(float(np.abs(r.displacement - exact).max()))
    assert 1.95 < _rate(hs, errs) < 2.05


def _tied():
    """Two masses and an absorber (massless boundary tied to mass 2), a tie between the masses."""
    M = sp.diags_array([1.0, 2.0, 0.0, 0.5]).tocsr()
    K = sp.csr_array(np.array([[900.0, -100, 0, 0], [-100, 400, 0, 0],
                               [0, 0, 300, -300], [0, 0, -300, 300]]))
    A = sp.csr_array(np.array([[1.0, -1.0, 0, 0], [0, 1.0, -1.0, 0]]))
    return M, K, A


def test_harmonic_steady_state_is_the_receptance():
    M, K, A = _tied()
    C = 0.002 * K + 0.5 * M
    w = 17.0
    e = np.zeros((4, 1))
    e[3] = 1.0
    H = receptance(K, M, C, A, np.array([w]), method="kkt", inputs=sp.csc_array(e),
                   outputs=sp.identity(4, format="csr"))[0][:, 0]
    h = 5e-5
    n = int(round(2 * np.pi / w / h))
    t = h * np.arange(n + 1)
    r = transient(M, C, K, A, None, LoadHistory(e, np.cos(w * t)[:, None], h, n),
                  TransientOutputs(sp.identity(4)),
                  initial=InitialConditions(d0=H.real, v0=(1j * w * H).real),
                  options=TransientOptions(method="generalized-inverse",
                                           checks=["null-space", "modal"]))
    exact = (H[None, :] * np.exp(1j * w * r.t)[:, None]).real
    assert np.abs(r.displacement - exact).max() / np.abs(H).max() < 1e-6
    assert max(r.agreement.values()) < 1e-10


def test_constraint_force_of_a_rigid_tie():
    m1, m2, F = 1.0, 3.0, 2.0
    M, K = np.diag([m1, m2]), np.diag([1e-9, 1e-9])
    r = transient(M, None, K, np.array([[1.0, -1.0]]), None,
                  LoadHistory(np.array([[1.0], [0.0]]), np.full((11, 1), F), 1e-3, 10),
                  TransientOutputs(np.eye(2)), constraint_labels=["tie"])
    # Q^c = A^T lambda; mass 2 is pulled by -lambda = m2 F / (m1 + m2)
    assert np.allclose(r.constraint_forces[:, 0], -m2 * F / (m1 + m2), rtol=1e-9)
    assert np.allclose(r.acceleration, F / (m1 + m2), rtol=1e-9)


def test_energy_and_constraints_hold_over_1e5_steps():
    M, K, A = _tied()
    d0 = np.array([0.01, 0.01, 0.01, 0.03])
    n = 100_000
    r = transient(M, None, K, A, None,
                  LoadHistory(np.zeros((4, 1)), np.zeros((n + 1, 1)), 1e-3, n),
                  TransientOutputs(sp.identity(4)), initial=InitialConditions(d0=d0),
                  options=TransientOptions(every=10, forces=False))
    E = r.energy_balance()
    assert np.abs(E - E[0]).max() / E[0] < 1e-10
    assert r.drift <= 1e-12
    assert r.constraint_residual.size == n // 10 + 1


def test_generalized_alpha_damps_the_highest_frequency():
    s = scheme("generalized-alpha", 0.0)
    assert s.alpha_m == -1.0 and s.alpha_f == 0.0
    # a stiff mode at omega h = 1e3 loses its amplitude within a few steps for rho_inf = 0
    M, K = np.diag([1.0]), np.diag([1e12])
    r = transient(M, None, K, None, None,
                  LoadHistory(np.zeros((1, 1)), np.zeros((6, 1)), 1e-3, 5),
                  TransientOutputs(np.eye(1)), initial=InitialConditions(d0=np.array([1.0])),
                  options=TransientOptions(integrator="generalized-alpha", rho_inf=0.0))
    assert abs(r.displacement[-1, 0]) < 1e-3
    newmark = transient(M, None, K, None, None,
                        LoadHistory(np.zeros((1, 1)), np.zeros((6, 1)), 1e-3, 5),
                        TransientOutputs(np.eye(1)), initial=InitialConditions(d0=np.array([1.0])))
    assert abs(abs(newmark.displacement[-1, 0]) - 1.0) < 1e-3


def test_tapered_rod_direct_and_modal_agree():
    case = load_case(CASES / "tapered_rod.yaml")
    asm = build_model(case).assembly
    model = build_model(case)
    tip = asm.rows([model.points["rod@200"]])
    n = 4000
    h = 2e-5
    t = h * np.arange(n + 1)
    pulse = np.where(t < 2e-3, np.sin(np.pi * t / 2e-3), 0.0) * 100.0
    r = transient(asm.M, asm.C, asm.K, asm.A, asm.b,
                  LoadHistory(sp.csc_array(tip.T), pulse[:, None], h, n), TransientOutputs(tip),
                  options=TransientOptions(method="generalized-inverse",
                                           checks=["null-space", "modal"]))
    assert r.agreement["modal"] < 1e-6 and r.agreement["null-space"] < 1e-10
    assert r.drift < 1e-13
    assert np.abs(r.displacement).max() > 0


def test_a_check_beyond_the_tolerance_fails():
    M, K, A = _tied()
    d0 = np.array([0.01, 0.01, 0.01, 0.03])
    with pytest.raises(CheckError, match="modal disagrees"):
        transient(M, None, K, A, None,
                  LoadHistory(np.zeros((4, 1)), np.zeros((101, 1)), 1e-3, 100),
                  TransientOutputs(sp.identity(4)), initial=InitialConditions(d0=d0),
                  options=TransientOptions(checks=["modal"], tolerance=1e-6, modal_count=1,
                                           modal_solver="dense"))


def test_inconsistent_initial_displacement_is_refused():
    M, K, A = _tied()
    with pytest.raises(ValueError, match="initial displacement violates"):
        transient(M, None, K, A, None,
                  LoadHistory(np.zeros((4, 1)), np.zeros((11, 1)), 1e-3, 10),
                  TransientOutputs(sp.identity(4)),
                  initial=InitialConditions(d0=np.array([0.01, 0.0, 0.0, 0.0])))


def test_shipped_impact_case_writes_the_transient_group(tmp_path):
    import h5py

    from substruct import cli
    out = tmp_path / "out"
    assert cli.main(["run", str(CASES / "tapered_rod_impact.yaml"), "--out", str(out)]) == 0
    with h5py.File(out / "tapered_rod_impact.h5") as f:
        g = f["transient"]
        assert g.attrs["agreement_modal"] < 1e-6 and g.attrs["drift"] < 1e-13
        assert g["displacement"].shape == (5001, 4) and g["displacement"].attrs["units"] == "length"
        e = g["energy"][:]
        balance = e[:, 0] + e[:, 1] - e[:, 2] + e[:, 3]
        assert np.abs(balance - balance[0]).max() < 1e-9 * np.abs(e[:, 2]).max()


@pytest.mark.parametrize("change, fragment", [
    ({"dt": 0}, "analysis.transient.dt"),
    ({"dt": 1.0, "t_end": 0.5}, "must be at most t_end"),
    ({"every": 1, "t_end": 1e3, "dt": 1e-4, "outputs": ["rod@200"] * 3000}, "more than the 4 GB allowed"),
])
def test_bad_transient_input_is_one_line(change, fragment):
    import yaml

    from substruct.case.loader import CaseError
    data = yaml.safe_load((CASES / "tapered_rod_impact.yaml").read_text())
    data["analysis"]["transient"].update(change)
    with pytest.raises(CaseError, match=fragment):
        load_case(data)


@pytest.mark.parametrize("rows, fragment", [
    ("0,0\n0.1,nan\n", "not finite"), ("0,0\n0.2,1\n0.1,2\n", "not strictly increasing")])
def test_bad_load_table_is_refused(tmp_path, rows, fragment):
    from substruct.case.transient import read_table
    p = tmp_path / "load.csv"
    p.write_text(rows)
    with pytest.raises(ValueError, match=fragment):
        read_table(p)
