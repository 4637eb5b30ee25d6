"""Base excitation of grounded supports (substruct/analysis/transient/base.py): a prescribed
ground motion as the nonhomogeneous constraint A q = b + e g(t), checked against closed forms
of a single oscillator on a moving base and against the relative-motion form (effective load
-M r g'') of a coupled model."""

from pathlib import Path

import numpy as np
import pytest

from cli_helpers import run
from substruct.analysis.transient.integrators import scheme
from substruct.analysis.transient import LoadHistory, TransientOptions, TransientOutputs, transient
from substruct.analysis.transient.base import BaseMotion, ground_history
from substruct.io import hdf5 as results

M1, K1, ZETA = 2.0, 800.0, 0.05
W1 = np.sqrt(K1 / M1)


def _oscillator(zeta: float = ZETA):
    """A mass on a spring and a damper whose other end is the ground coordinate q_0, held by
    the constraint q_0 = 0 (massless: eq 10)."""
    c = 2 * zeta * W1 * M1
    pattern = np.array([[1.0, -1.0], [-1.0, 1.0]])
    return np.diag([0.0, M1]), c * pattern, K1 * pattern, np.array([[1.0, 0.0]])


def _step_error(method: str, dt: float, integrator: str = "newmark", a0: float = 3.0,
                t_end: float = 1.0) -> float:
    M, C, K, A = _oscillator()
    n = int(round(t_end / dt))
    t = dt * np.arange(n + 1)
    tr = transient(M, C, K, A, None,
                   LoadHistory(np.zeros((2, 0)), np.zeros((n + 1, 0)), dt, n,
                               base=BaseMotion(np.array([1.0]), "acceleration",
                                               np.full(n + 1, a0))),
                   TransientOutputs(np.eye(2)),
                   options=TransientOptions(method=method, integrator=integrator, rho_inf=0.8))
    # z'' + 2 zeta w z' + w^2 z = -a0 from rest
    wd = W1 * np.sqrt(1 - ZETA ** 2)
    z = -(a0 / W1 ** 2) * (1 - np.exp(-ZETA * W1 * t) * (np.cos(wd * t) + ZETA
                                                        / np.sqrt(1 - ZETA ** 2) * np.sin(wd * t)))
    assert tr.drift < 1e-15
    np.testing.assert_allclose(tr.displacement[:, 0], 0.5 * a0 * t ** 2, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(tr.base_influence, [1.0, 1.0], rtol=1e-12)
    return float(np.abs(tr.relative("displacement")[:, 1] - z).max() / np.abs(z).max())


@pytest.mark.parametrize("integrator", ["newmark", "generalized-alpha"])
@pytest.mark.parametrize("method", ["generalized-inverse", "null-space", "modal"])
def test_step_base_acceleration_matches_closed_form_at_second_order(method, integrator):
    coarse = _step_error(method, 2e-3, integrator)
    fine = _step_error(method, 1e-3, integrator)
    assert fine < 1e-3
    assert 3.6 < coarse / fine < 4.4, (coarse, fine)  # Newmark: second order


def _harmonic_error(method: str, dt: float, kind: str, a0: float = 3.0, w: float = 13.0,
                    t_end: float = 1.0) -> float:
    """Generalized-alpha (rho_inf 0.6) under the ground acceleration a0 cos(w t) from rest (or
    the displacement that has it): the error of the relative displacement against the closed
    form of z'' + 2 zeta W z' + W^2 z = -a0 cos(w t), z(0) = z'(0) = 0."""
    M, C, K, A = _oscillator()
    n = int(round(t_end / dt))
    t = dt * np.arange(n + 1)
    if kind == "acceleration":
        base = BaseMotion(np.array([1.0]), kind, a0 * np.cos(w * t))
    else:
        base = BaseMotion(np.array([1.0]), kind, a0 * (1 - np.cos(w * t)) / w ** 2,
                          rate0=0.0, accel0=a0)
    tr = transient(M, C, K, A, None,
                   LoadHistory(np.zeros((2, 0)), np.zeros((n + 1, 0)), dt, n, base=base),
                   TransientOutputs(np.eye(2)),
                   options=TransientOptions(method=method, integrator="generalized-alpha",
                                            rho_inf=0.6))
    H = -a0 / (W1 ** 2 - w ** 2 + 2j * ZETA * W1 * w)  # z_p = Re(H e^{i w t})
    wd = W1 * np.sqrt(1 - ZETA ** 2)
    c1 = -H.real
    c2 = (H.imag * w + ZETA * W1 * c1) / wd  # z_h'(0) = -z_p'(0) = Im(H) w
    z = (np.real(H * np.exp(1j * w * t))
         + np.exp(-ZETA * W1 * t) * (c1 * np.cos(wd * t) + c2 * np.sin(wd * t)))
    return float(np.abs(tr.relative("displacement")[:, 1] - z).max() / np.abs(z).max())


@pytest.mark.parametrize("kind", ["acceleration", "displacement"])
@pytest.mark.parametrize("method", ["generalized-inverse", "null-space", "modal"])
def test_harmonic_base_motion_by_generalized_alpha_is_second_order_in_every_form(method, kind):
    """The relative forms take the ground's acceleration as a load at generalized-alpha's
    shifted instant: with the scheme's acceleration variable as that load (O(h) away from the
    physical one) they were first order (ratio 2.2 between dt and dt/2) and disagreed with the
    generalized-inverse form by 2e-4 at dt = 1e-3."""
    coarse = _harmonic_error(method, 2e-3, kind)
    fine = _harmonic_error(method, 1e-3, kind)
    main = _harmonic_error("generalized-inverse", 1e-3, kind)
    assert 3.6 < coarse / fine < 4.4, (coarse, fine)
    assert abs(fine - main) < 1e-3 * main, (fine, main)


@pytest.mark.parametrize("name", ["newmark", "generalized-alpha"])
def test_ground_history_is_the_schemes_own_integral(name):
    """From an accelerogram cos(7 t): the displacement and velocity the scheme integrates
    converge at second order to the exact integrals from rest; read back from the displacement
    it gives the same history (to the rounding of solving the updates for the acceleration)."""
    s = scheme(name, 0.8)
    errors = []
    for h in (2e-3, 1e-3):
        t = h * np.arange(int(round(2.0 / h)) + 1)
        g = ground_history("acceleration", np.cos(7 * t), s, h)
        errors.append(max(np.abs(g[:, 0] - (1 - np.cos(7 * t)) / 49).max() * 49 / 2,
                          np.abs(g[:, 1] - np.sin(7 * t) / 7).max() * 7))
        d = ground_history("displacement", g[:, 0], s, h, g[0, 1], g[0, 2])
        np.testing.assert_allclose(d[:, 0], g[:, 0], rtol=0, atol=1e-17)
        # solving the updates for g'' amplifies rounding by 1 / (beta h^2)
        np.testing.assert_allclose(d[:, 1:], g[:, 1:], rtol=0, atol=1e-6)
    assert errors[1] < 1e-4 and 3.6 < errors[0] / errors[1] < 4.4, errors


def _case(tmp_path: Path, base: str, outputs: str = "[o@mass, o@boundary]") -> Path:
    text = f"""name: sdof_base
units: "N, m, kg, s"
substructures:
  - {{name: o, type: free-free, mass: {M1}, stiffness: {K1}, damping: 8.0}}
constraints:
  - {{name: ground, terms: {{o@boundary: 1}}}}
analysis:
  transient:
    t_end: 4.0
    dt: 5.0e-4
    check: [null-space, modal]
    base: {base}
    outputs: {outputs}
output: {{pictures: false}}
"""
    path = tmp_path / "sdof_base.yaml"
    path.write_text(text)
    return path


def test_harmonic_base_acceleration_steady_state_is_the_transmissibility(tmp_path, capsys):
    w = 15.0
    case = _case(tmp_path, f"{{at: [o@boundary], acceleration: {{shape: harmonic, amplitude: 2, "
                           f"omega: {w}}}}}")
    code, _, err = run(capsys, "run", case, "--out", tmp_path / "out")
    assert code == 0, err
    tr = results.load(tmp_path / "out" / "sdof_base.h5").transient
    zeta = 8.0 / (2 * M1 * W1)
    r = w / W1
    T = np.sqrt(1 + (2 * zeta * r) ** 2) / np.sqrt((1 - r ** 2) ** 2 + (2 * zeta * r) ** 2)
    late = tr.t > 3.0  # e^{-zeta w_n t} < 2e-3 of the start-up left
    a = tr.acceleration[late, 0]
    amp = 0.5 * (a.max() - a.min())
    assert abs(amp / 2.0 - T) < 5e-3 * T, (amp / 2.0, T)
    # relative motion z = x - g: amplitude r^2 / sqrt(...) times the ground's |g''| / w^2
    z = tr.relative("displacement")[late, 0]
    zr = 0.5 * (z.max() - z.min()) / (2.0 / w ** 2)
    assert abs(zr - r ** 2 / np.sqrt((1 - r ** 2) ** 2 + (2 * zeta * r) ** 2)) < 5e-3 * zr
    # the ground point follows the prescribed motion exactly; its relative motion is nil
    np.testing.assert_allclose(tr.acceleration[:, 1], 2 * np.cos(w * tr.t), atol=1e-12)
    assert np.abs(tr.relative("displacement")[:, 1]).max() < 1e-15
    assert tr.agreement["null-space"] < 1e-12 and tr.agreement["modal"] < 1e-12


def test_base_displacement_expression_drives_the_same_motion(tmp_path, capsys):
    """g = (1 - cos w t) 2 / w^2 given as a displacement is the harmonic acceleration above."""
    case = _case(tmp_path, "{at: [o@boundary], displacement: {shape: expression, "
                           "expression: '2 * (1 - cos(15 * t)) / 225'}}")
    code, _, err = run(capsys, "run", case, "--out", tmp_path / "out")
    assert code == 0, err
    tr = results.load(tmp_path / "out" / "sdof_base.h5").transient
    np.testing.assert_allclose(tr.displacement[:, 1], 2 * (1 - np.cos(15 * tr.t)) / 225,
                               atol=1e-15)
    exact = 2 * np.cos(15 * tr.t)
    assert np.abs(tr.acceleration[:, 1] - exact).max() < 1e-3 * 2


def test_coupled_model_base_motion_equals_relative_form_with_effective_load():
    """Two chains (3 masses and 2 masses) tied at one point, grounded at the first coordinate:
    the ground motion as a constraint gives the relative response of the fixed-base model under
    the effective load -M r g'', r the rigid translation."""
    rng = np.random.default_rng(3)
    def chain(n):
        k = rng.uniform(500, 1500, n)
        K = np.diag(np.r_[k[1:], 0.0] + k) - np.diag(k[1:], 1) - np.diag(k[1:], -1)
        K[0, 0] = k[1]  # free at the first coordinate: its spring to ground left out
        return np.diag(rng.uniform(1, 2, n)), K
    Ma, Ka = chain(3)
    Mb, Kb = chain(2)
    Ma[0, 0] = 0.0  # a massless base coordinate
    M = np.block([[Ma, np.zeros((3, 2))], [np.zeros((2, 3)), Mb]])
    K = np.block([[Ka, np.zeros((3, 2))], [np.zeros((2, 3)), Kb]])
    C = 2e-4 * K
    A = np.zeros((2, 5))
    A[0, 0] = 2.0                 # the support: 2 q_0 = 0
    A[1, 2], A[1, 3] = 1.0, -1.0  # the tie of the two chains
    dt, n = 1e-3, 1500
    t = dt * np.arange(n + 1)
    ag = 5.0 * np.sin(30 * t) * np.exp(-t)
    O = np.eye(5)[[1, 2, 4]]
    moving = transient(M, C, K, A, None,
                       LoadHistory(np.zeros((5, 0)), np.zeros((n + 1, 0)), dt, n,
                                   base=BaseMotion(np.array([2.0, 0.0]), "acceleration", ag)),
                       TransientOutputs(O),
                       options=TransientOptions(checks=["null-space", "modal"], tolerance=1e-9))
    r = np.ones(5)
    fixed = transient(M, C, K, A, None,
                      LoadHistory((-M @ r)[:, None], moving.base_motion[:, 2:3], dt, n),
                      TransientOutputs(O), options=TransientOptions(method="null-space"))
    peak = np.abs(fixed.displacement).max()
    for name in ("displacement", "velocity", "acceleration"):
        ref = getattr(fixed, name)
        assert np.abs(moving.relative(name) - ref).max() < 1e-9 * np.abs(ref).max(), name
    assert peak > 1e-3 and moving.drift < 1e-14


def test_initial_acceleration_by_sparse_kkt_when_the_dense_gain_is_refused(monkeypatch):
    """A model whose n x m gain may not be copied dense starts from the same eq-10
    acceleration (one sparse KKT factorization), so the whole history is the same."""
    import substruct.analysis.transient.response as transient_module
    M, C, K, A = _oscillator()
    n = 200
    g = np.cos(20 * 1e-3 * np.arange(n + 1))
    base = BaseMotion(np.array([1.0]), "acceleration", g)
    args = (M, C, K, A, None,
            LoadHistory(np.zeros((2, 0)), np.zeros((n + 1, 0)), 1e-3, n, base=base),
            TransientOutputs(np.eye(2)))
    ref = transient(*args)
    def refuse(*args):
        raise MemoryError("refusing a dense copy")

    monkeypatch.setattr(transient_module, "constrained_acceleration", refuse)
    low = transient(*args)
    np.testing.assert_allclose(low.acceleration, ref.acceleration, rtol=0,
                               atol=1e-12 * np.abs(ref.acceleration).max())
    # at rest with g''(0) = 1: the ground accelerates, the mass (its spring relaxed) does not
    np.testing.assert_allclose(low.acceleration[0], [1.0, 0.0], atol=1e-14)


def test_initial_state_with_a_moving_ground_is_relative_to_it(tmp_path, capsys):
    """The ground at g(0) = 0.01: a point's initial displacement is measured from the
    pseudo-static position (the mass starts at 0.01 + 0.02); the absolute state (which the
    constraint check then sees shifted by r g(0)) is refused with that said."""
    from cli_helpers import assert_one_line_error
    base = "{at: [o@boundary], displacement: {shape: harmonic, amplitude: 0.01, omega: 13}}"
    text = _case(tmp_path, base).read_text().replace(
        "    check: [null-space, modal]\n",
        "    check: [null-space, modal]\n    initial: {displacement: {o@mass: 0.02}}\n")
    case = tmp_path / "initial.yaml"
    case.write_text(text)
    code, _, err = run(capsys, "run", case, "--out", tmp_path / "out")
    assert code == 0, err
    tr = results.load(tmp_path / "out" / "sdof_base.h5").transient
    np.testing.assert_allclose(tr.displacement[0], [0.03, 0.01], rtol=1e-14)
    np.testing.assert_allclose(tr.relative("displacement")[0], [0.02, 0.0], atol=1e-15)
    case.write_text(text.replace("{o@mass: 0.02}", "{o@mass: 0.02, o@boundary: 0.01}"))
    code, out, err = run(capsys, "run", case, "--out", tmp_path / "out2")
    assert_one_line_error(code, out, err, "the initial displacement violates the constraints",
                          "with a moving ground the initial state is measured from the "
                          "pseudo-static position r g(0)")
