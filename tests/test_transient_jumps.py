"""Loads that jump at any instant keep the integrators' second order: a step load that starts
between two instants, or on one, against the closed form of a damped oscillator and against
the matrix exponential of a constrained 3-DOF chain; measured rates on halving, in all three
forms and both integrators, through the API and through a case file."""

from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla

from substruct.analysis.transient.integrators import scheme
from substruct.analysis.transient import LoadHistory, TransientOptions, TransientOutputs, transient
from substruct.analysis.transient.loads import for_scheme, merge_pairs, step_pairs
from substruct.case.loader import parse_case
from substruct.case.transient_signals import Step, TableShape, waveform
from substruct.run.runner import build_model
from substruct.run.transient_run import transient_result

M1, K1, C1, F = 2.0, 800.0, 4.0, 3.0
HS = [1e-3, 5e-4, 2.5e-4, 1.25e-4]


def _rate(hs, errs):
    return float(np.polyfit(np.log(hs), np.log(errs), 1)[0])


def _sdof_step(t, t0):
    """The damped oscillator's response to the step F from t0, at rest before."""
    w = np.sqrt(K1 / M1)
    z = C1 / (2 * M1 * w)
    wd = w * np.sqrt(1 - z * z)
    s = np.clip(t - t0, 0.0, None)
    return np.where(t >= t0, F / K1 * (1 - np.exp(-z * w * s) * (np.cos(wd * s)
                                                                + z * w / wd * np.sin(wd * s))),
                    0.0)


def _run_sdof(h, sig, integrator, method, jumps=True, t_end=0.5):
    n = int(round(t_end / h))
    wave = waveform(sig, Path("."), {})
    f = wave.values(h * np.arange(n + 1))[:, None]
    pairs = merge_pairs([step_pairs(wave.values, wave.breaks, h, n)], f) if jumps else None
    return transient(np.array([[M1]]), np.array([[C1]]), np.array([[K1]]), None, None,
                     LoadHistory(np.ones((1, 1)), f, h, n, pairs=pairs),
                     TransientOutputs(np.eye(1)),
                     options=TransientOptions(method=method, integrator=integrator, rho_inf=0.7))


@pytest.mark.parametrize("integrator", ["newmark", "generalized-alpha"])
@pytest.mark.parametrize("method", ["generalized-inverse", "null-space", "modal"])
@pytest.mark.parametrize("t0", [0.1, 0.10037])
def test_step_at_any_start_is_second_order(integrator, method, t0):
    errs, ref = [], []
    for h in HS:
        r = _run_sdof(h, Step(amplitude=F, start=t0), integrator, method)
        errs.append(float(np.abs(r.displacement[:, 0] - _sdof_step(r.t, t0)).max()))
        r0 = _run_sdof(h, Step(amplitude=F, start=0.0), integrator, method)
        ref.append(float(np.abs(r0.displacement[:, 0] - _sdof_step(r0.t, 0.0)).max()))
    assert 1.95 < _rate(HS, errs) < 2.05, errs
    # the same error constant as the step at t = 0 (not only the same order)
    assert max(e / e0 for e, e0 in zip(errs, ref)) < 1.1, (errs, ref)


@pytest.mark.parametrize("integrator", ["newmark", "generalized-alpha"])
def test_step_at_a_fixed_fraction_of_the_step_is_second_order(integrator):
    """The start at the same fraction of every step size (0.2 .. 0.8): the rate is not the
    luck of where the jump falls."""
    for frac in (0.2, 0.5, 0.8):
        errs = []
        for h in HS:
            t0 = 0.1 + frac * h
            r = _run_sdof(h, Step(amplitude=F, start=t0), integrator, "generalized-inverse")
            errs.append(float(np.abs(r.displacement[:, 0] - _sdof_step(r.t, t0)).max()))
        assert 1.95 < _rate(HS, errs) < 2.05, (frac, errs)


def test_nodal_values_alone_are_first_order():
    """Without the step pairs the same step is first order (what the pairs correct)."""
    errs = []
    for h in HS:
        r = _run_sdof(h, Step(amplitude=F, start=0.1), "newmark", "generalized-inverse",
                      jumps=False)
        errs.append(float(np.abs(r.displacement[:, 0] - _sdof_step(r.t, 0.1)).max()))
    assert 0.9 < _rate(HS, errs) < 1.1


def test_table_jumps_at_its_ends(tmp_path):
    """A table that starts at a nonzero value (0 before it): a step from its first time."""
    t0 = 0.05037
    np.savetxt(tmp_path / "f.csv", [[t0, 1.0], [5.0, 1.0]], delimiter=",")
    errs = []
    for h in HS[:3]:
        n = int(round(0.5 / h))
        wave = waveform(TableShape(shape="table", table="f.csv", amplitude=F), tmp_path, {})
        f = wave.values(h * np.arange(n + 1))[:, None]
        pairs = merge_pairs([step_pairs(wave.values, wave.breaks, h, n)], f)
        r = transient(np.array([[M1]]), np.array([[C1]]), np.array([[K1]]), None, None,
                      LoadHistory(np.ones((1, 1)), f, h, n, pairs=pairs),
                      TransientOutputs(np.eye(1)))
        errs.append(float(np.abs(r.displacement[:, 0] - _sdof_step(r.t, t0)).max()))
    assert 1.95 < _rate(HS[:3], errs) < 2.05, errs


def test_pairs_keep_the_load_impulse_for_generalized_alpha():
    """The shifted pair gives generalized-alpha's velocity impulse h[(1 - c) p + c q] the
    load's integral, and is the moment-matched pair itself for Newmark."""
    h, t0 = 0.01, 0.0337
    wave = waveform(Step(amplitude=1.0, start=t0), Path("."), {})
    (n, (p, q)), = step_pairs(wave.values, wave.breaks, h, 10).items()
    assert n == 3
    m0 = (4 * h - t0) * 1.0  # the step is 1 on [t0, 4h] of the step [3h, 4h]
    assert abs(h * (p + q) / 2 - m0) < 1e-15
    for rho in (0.0, 0.5, 0.9):
        s = scheme("generalized-alpha", rho)
        c = s.gamma * (1 - s.alpha_f) / (1 - s.alpha_m)
        (pp, qq), = for_scheme({n: (np.array([p]), np.array([q]))}, s).values()
        assert abs(h * ((1 - c) * pp[0] + c * qq[0]) - m0) < 1e-15
    (pp, qq), = for_scheme({n: (np.array([p]), np.array([q]))}, scheme("newmark")).values()
    assert pp[0] == p and qq[0] == q


def _chain():
    M = np.diag([1.0, 2.0, 1.5])
    K = np.array([[700.0, -300.0, 0.0], [-300.0, 800.0, -500.0], [0.0, -500.0, 900.0]])
    C = 0.002 * K + 0.5 * M
    A = np.array([[1.0, 0.0, 2.0]])
    return M, C, K, A


def _chain_exact(t, t0):
    """The constrained chain under a unit step at coordinate 2 from t0: the matrix exponential
    of the first-order system on the null space of A."""
    M, C, K, A = _chain()
    T = sla.null_space(A)
    Mr, Cr, Kr = T.T @ M @ T, T.T @ C @ T, T.T @ K @ T
    k = Mr.shape[0]
    Ainv = np.linalg.inv(Mr)
    S = np.block([[np.zeros((k, k)), np.eye(k)], [-Ainv @ Kr, -Ainv @ Cr]])
    g = np.concatenate([np.zeros(k), Ainv @ (T.T @ np.array([0.0, 1.0, 0.0]))])
    xs = np.linalg.solve(S, -g)  # the static state of the step
    out = []
    for tk in t:
        x = np.zeros(2 * k) if tk < t0 else xs - sla.expm(S * (tk - t0)) @ xs
        out.append(T @ x[:k])
    return np.array(out)


@pytest.mark.parametrize("integrator", ["newmark", "generalized-alpha"])
def test_constrained_chain_step_between_instants_is_second_order(integrator):
    """The start at the same fraction of each step (where it falls in the step changes the
    error's constant, 3.5 to 5.6 between halvings for a start fixed in time, not its order)."""
    M, C, K, A = _chain()
    errs = []
    for h in HS[:3]:
        t0 = 0.02 + 0.13 * h
        n = int(round(0.2 / h))
        wave = waveform(Step(start=t0), Path("."), {})
        f = wave.values(h * np.arange(n + 1))[:, None]
        pairs = merge_pairs([step_pairs(wave.values, wave.breaks, h, n)], f)
        r = transient(M, C, K, A, None,
                      LoadHistory(np.array([[0.0], [1.0], [0.0]]), f, h, n, pairs=pairs),
                      TransientOutputs(np.eye(3)),
                      options=TransientOptions(checks=["null-space", "modal"], tolerance=1e-9,
                                               integrator=integrator, rho_inf=0.6))
        errs.append(float(np.abs(r.displacement - _chain_exact(r.t, t0)).max()))
        assert r.drift < 1e-12
    assert 1.95 < _rate(HS[:3], errs) < 2.05, errs


def test_a_step_case_between_instants_is_second_order():
    """Through a case file: a fixed-free oscillator under a step that starts between two
    instants, dt halved three times."""
    errs, hs = [], [1e-3, 5e-4, 2.5e-4]
    for dt in hs:
        case = parse_case(f"""
name: step_late
substructures:
  - {{name: s, type: fixed-free, mass: {M1}, stiffness: {K1}, damping: {C1}}}
analysis:
  transient:
    t_end: 0.4
    dt: {dt}
    loads: [{{point: s@mass, amplitude: {F}, start: 0.10037}}]
    outputs: [s@mass]
""")
        r = transient_result(case, build_model(case))
        errs.append(float(np.abs(r.displacement[:, 0] - _sdof_step(r.t, 0.10037)).max()))
    assert 1.95 < _rate(hs, errs) < 2.05, errs
