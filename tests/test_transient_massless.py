"""Transient response of models whose effective matrix is singular: a massless motion (the common
motion of a spring's two massless ends) held only by the constraints that connect it.

The references know nothing of the massless coordinates: the same physical system assembled by
hand with the spring joining the masses directly, against the modal closed form (tolerance: the
period error of Newmark's average acceleration) and integrated by a plain Newmark loop written
here (tolerance: the round-off of the steps); and ``cases/two_rods_spring.yaml`` (two rods
joined by a two-ended spring) against the same rods with the spring between their nodes."""

import json
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp

from cli_helpers import run
from substruct.analysis.transient import response
from substruct.analysis.transient import (
    LoadHistory,
    TransientOptions,
    TransientOutputs,
    transient,
)
from substruct.case.loader import load_case
from substruct.run.runner import build_model

CASES = Path(__file__).resolve().parents[1] / "cases"
EPS = np.finfo(float).eps
M1, M2, K1, K2, KS, CS = 1.0, 2.0, 100.0, 300.0, 50.0, 0.4


def _tied(damping: float = 0.0):
    """Masses x1, x2 (grounded by K1, K2) and a spring KS (damper ``damping``) with massless
    ends i, j, connected by x1 = i, x2 = j: coordinates (x1, x2, i, j)."""
    M = np.diag([M1, M2, 0.0, 0.0])
    K = np.zeros((4, 4))
    K[0, 0], K[1, 1] = K1, K2
    K[2:, 2:] = KS * np.array([[1.0, -1.0], [-1.0, 1.0]])
    C = np.zeros((4, 4))
    C[2:, 2:] = damping * np.array([[1.0, -1.0], [-1.0, 1.0]])
    A = np.array([[1.0, 0.0, -1.0, 0.0], [0.0, 1.0, 0.0, -1.0]])
    return M, (C if damping else None), K, A


def _direct(damping: float = 0.0):
    """The same system without the spring's ends: KS (and the damper) between x1 and x2."""
    M = np.diag([M1, M2])
    K = np.array([[K1 + KS, -KS], [-KS, K2 + KS]])
    C = damping * np.array([[1.0, -1.0], [-1.0, 1.0]])
    return M, C, K


def _newmark(M, C, K, F, h):
    """A plain loop of Newmark's average acceleration from rest, ``F`` the loads at the
    instants (``(n_steps + 1) x n``): the displacements at the instants."""
    S = M + 0.5 * h * C + 0.25 * h * h * K
    d, v = np.zeros(M.shape[0]), np.zeros(M.shape[0])
    a = np.linalg.solve(M, F[0])
    out = [d]
    for f in F[1:]:
        ds, vs = d + h * v + 0.25 * h * h * a, v + 0.5 * h * a
        a = np.linalg.solve(S, f - C @ vs - K @ ds)
        d, v = ds + 0.25 * h * h * a, vs + 0.5 * h * a
        out.append(d)
    return np.array(out)


def _run(M, C, K, A, B, f, h, method, checks=(), integrator="newmark"):
    n_steps = f.shape[0] - 1
    return transient(M, C, K, A, None, LoadHistory(B, f, h, n_steps),
                     TransientOutputs(np.eye(M.shape[0])[:2]),
                     options=TransientOptions(method=method, checks=checks,
                                              integrator=integrator, rho_inf=0.7))


@pytest.mark.parametrize("dense", [True, False])
@pytest.mark.parametrize("method", ["generalized-inverse", "null-space", "modal"])
def test_step_response_against_closed_form(method, dense, monkeypatch):
    """A unit step on x1 from rest, undamped: q(t) = sum_k phi_k s_k (1 - cos w_k t),
    s_k = phi_k^T F / w_k^2.  Newmark's discrete solution is the same with the frequencies
    w~_k = (2/h) atan(w_k h / 2), so the error is at most sum_k |phi_k s_k| (w_k - w~_k) t."""
    if not dense:  # the sparse factorization of the effective matrix (augmented)
        monkeypatch.setattr(response, "DENSE_STEP", 0)
    M, C, K, A = _tied()
    h, n_steps = 1e-3, 2000
    B = np.array([[1.0], [0.0], [0.0], [0.0]])
    r = _run(M, C, K, A, B, np.ones((n_steps + 1, 1)), h, method)
    w2, phi = sla.eigh(_direct()[2], _direct()[0])
    w = np.sqrt(w2)
    amp = phi * (phi[0] / w2)  # column k: phi_k s_k, F = e_1
    exact = (1 - np.cos(np.outer(r.t, w))) @ amp.T
    bound = np.abs(amp).sum(axis=1) * (w - 2 / h * np.arctan(w * h / 2)).max() * r.t[-1]
    err = np.abs(r.displacement - exact).max(axis=0)
    assert np.all(err <= 1.01 * bound + 1e3 * EPS * np.abs(exact).max()), (err, bound)
    assert err.max() > 0.1 * bound.max()  # the error is the method's, the bound not vacuous
    assert r.drift < 1e-14


@pytest.mark.parametrize("integrator", ["newmark", "generalized-alpha"])
def test_damped_pulse_against_the_direct_model(integrator):
    """A damped joint under a smooth pulse on both masses: the three forms (each the main
    one, the other two its checks) against the direct model integrated by the same scheme,
    to the round-off of the steps (n_steps x 1e3 eps of the peak)."""
    M, C, K, A = _tied(CS)
    h, n_steps = 1e-3, 1000
    t = h * np.arange(n_steps + 1)
    pulse = np.where(t < 0.05, 0.5 * (1 - np.cos(2 * np.pi * t / 0.05)), 0.0)[:, None]
    B = np.array([[1.0], [-2.0], [0.0], [0.0]])
    Md, Cd, Kd = _direct(CS)
    if integrator == "newmark":
        ref = _newmark(Md, Cd, Kd, pulse @ B[:2].T, h)
    else:  # the same generalized-alpha scheme on the direct model, no constraint
        ref = transient(Md, Cd, Kd, None, None, LoadHistory(B[:2], pulse, h, n_steps),
                        TransientOutputs(np.eye(2)),
                        options=TransientOptions(integrator=integrator, rho_inf=0.7)
                        ).displacement
    peak = np.abs(ref).max()
    for method in ("generalized-inverse", "null-space", "modal"):
        others = tuple(m for m in ("generalized-inverse", "null-space", "modal") if m != method)
        r = _run(M, C, K, A, B, pulse, h, method, others, integrator)
        assert np.abs(r.displacement - ref).max() <= n_steps * 1e3 * EPS * peak, method
        assert max(r.agreement.values()) <= n_steps * 1e3 * EPS, (method, r.agreement)


def _rods_direct(asm, points):
    """``cases/two_rods_spring.yaml`` without the spring's ends and the point mass's coordinate:
    the spring and its damper between the rods' end nodes, the 0.5 kg on the steel rod's
    middle node (the connection is a rigid tie), the other coordinates kept."""
    i, j = (int(asm.rows([points[p]]).indices[0]) for p in ("s@i", "s@j"))
    ends = [int(asm.rows([points[p]]).indices[0]) for p in ("steel@1.0", "alu@0")]
    mid, m1 = (int(asm.rows([points[p]]).indices[0]) for p in ("steel@L/2", "m1"))
    keep = np.setdiff1d(np.arange(asm.n_dof), [i, j, m1])
    pick = {c: int(np.flatnonzero(keep == c)[0]) for c in (*ends, mid)}
    M, C, K = (np.asarray(sp.csr_array(X)[keep][:, keep].toarray()) for X in
               (asm.M, asm.C, asm.K))
    M[pick[mid], pick[mid]] += asm.M[m1, m1]
    e = np.zeros(keep.size)
    e[pick[ends[0]]], e[pick[ends[1]]] = 1.0, -1.0
    K += asm.K[i, i] * np.outer(e, e)
    C += asm.C[i, i] * np.outer(e, e)
    return M, C, K, keep, [pick[ends[0]], pick[ends[1]], pick[mid]]


def test_two_rods_spring_against_the_rods_joined_directly():
    """The shipped two rods joined by a two-ended spring (3 connections, the spring's common
    motion held only by them), a smooth 1 ms pulse at the joint, 600 steps of 10 us: each form
    against the rods joined directly by the spring and integrated by the plain Newmark loop."""
    model = build_model(load_case(CASES / "two_rods_spring.yaml"))
    asm = model.assembly
    Md, Cd, Kd, keep, sel = _rods_direct(asm, model.points)
    h, n_steps = 1e-5, 600
    t = h * np.arange(n_steps + 1)
    pulse = np.where(t < 1e-3, 0.5 * (1 - np.cos(2 * np.pi * t / 1e-3)), 0.0)[:, None]
    B = asm.rows([model.points["steel@1.0"]]).toarray().T
    ref = _newmark(Md, Cd, Kd, pulse @ B[keep].T, h)
    outputs = asm.rows([model.points[p] for p in ("steel@1.0", "alu@0", "m1")])
    forms = ("generalized-inverse", "null-space", "modal")
    for method in forms:
        r = transient(asm.M, asm.C, asm.K, asm.A, None, LoadHistory(B, pulse, h, n_steps),
                      TransientOutputs(outputs),
                      options=TransientOptions(method=method,
                                               checks=tuple(m for m in forms if m != method)))
        peak = np.abs(ref[:, sel]).max()
        assert np.abs(r.displacement - ref[:, sel]).max() <= n_steps * 1e3 * EPS * peak, method
        assert r.drift < 1e-14


def test_two_rods_spring_transient_through_the_command_line(tmp_path, capsys):
    """The example with a transient added: exit 0, the checks agree, the balance holds."""
    setting = ("analysis.transient={t_end: 0.002, dt: 1e-5, check: [null-space, modal], "
               "loads: [{point: steel@1.0, amplitude: 1, shape: half-sine, duration: 0.001}], "
               "outputs: [steel@1.0, alu@0]}")
    code, text, err = run(capsys, "run", CASES / "two_rods_spring.yaml", "--out",
                          tmp_path / "out", "--no-pictures", "--json", "--set", setting)
    assert code == 0, err
    data = json.loads(text)["transient"]
    assert max(data["agreement"].values()) < 1e-9
    assert data["energy_balance_change"] < 1e-10


def test_a_massless_motion_held_by_nothing_is_refused():
    """A coordinate with neither mass, damping nor stiffness, and no constraint on it: the
    effective matrix stays singular once augmented, refused as input, not an internal error."""
    from substruct.analysis.errors import AnalysisInputError
    from substruct.analysis.transient.effective import constraint_correction, effective_solver

    A = sp.csr_array(np.array([[1.0, 0.0, -1.0]]))
    S = np.diag([1.0, 0.0, 0.0])
    with pytest.raises(AnalysisInputError, match="no constraint holds"):
        effective_solver(S, A, "superlu")
    # a unit mass tied to a coordinate with nothing: the tie holds it, the pair moves as one
    A = sp.csr_array(np.array([[1.0, -1.0]]))
    eff = effective_solver(np.diag([1.0, 0.0]), A, "auto")
    corr = constraint_correction(eff.S, eff.solve, A, np.zeros(1))
    a = corr.apply(eff.solve(np.array([1.0, 0.0])), np.zeros(1))
    assert eff.augmented and np.abs(a - 1.0).max() < 10 * EPS


def test_velocity_given_at_the_masses_only_is_followed_by_the_massless_coordinate():
    """A unit mass on a spring chain 2, -1 / -1, 1 with a massless end (no constraint) released
    with q1' = 1: condensed, a unit oscillator of stiffness 2 - 1 = 1, q1 = sin t, and the end
    follows its static equation, q2 = q1, q2' = cos t, q2'' = -sin t (before this, q2' started
    at 0 and its velocity and acceleration rang at the Nyquist frequency, 2 and 4e4).  Newmark's
    error: at most the period error, |1 - (2/h) atan(h/2)| t."""
    from substruct.analysis.transient import InitialConditions
    from substruct.analysis.transient.initial import InitialStateError

    h, n_steps = 0.01, 100
    M, K = np.diag([1.0, 0.0]), np.array([[2.0, -1.0], [-1.0, 1.0]])
    load = LoadHistory(np.zeros((2, 0)), np.zeros((n_steps + 1, 0)), h, n_steps)
    r = transient(M, None, K, None, None, load, TransientOutputs(np.eye(2)),
                  initial=InitialConditions(v0=np.array([1.0, 0.0])))
    bound = abs(1 - 2 / h * np.arctan(h / 2)) * r.t[-1] * 1.01 + 1e3 * EPS
    assert np.abs(r.displacement - np.sin(r.t)[:, None]).max() <= bound
    assert np.abs(r.velocity - np.cos(r.t)[:, None]).max() <= bound
    assert np.abs(r.acceleration + np.sin(r.t)[:, None]).max() <= bound
    with pytest.raises(InitialStateError, match="got 0.5"):  # a velocity of its own there
        transient(M, None, K, None, None, load, TransientOutputs(np.eye(2)),
                  initial=InitialConditions(v0=np.array([1.0, 0.5])))
