"""Transient response of a model whose constraints hold every coordinate (rank A = n): the motion
is prescribed by the constraints alone, q = A^-1 (b + e g(t)), and every form gives it, the zero
response exactly, with the figures (drift, agreement, energy balance) 0 instead of round-off
over round-off."""

import numpy as np
import pytest
import scipy.sparse as sp

from cli_helpers import DAMPED_THREE_MASS, run
from substruct.analysis.transient.base import BaseMotion
from substruct.analysis.transient import (
    InitialConditions,
    LoadHistory,
    TransientOptions,
    TransientOutputs,
    transient,
)

FORMS = ("generalized-inverse", "null-space", "modal")
M = np.array([[2.0, 0.5, 0.0], [0.5, 2.0, 0.3], [0.0, 0.3, 4.0]])
K = np.array([[20.0, -10.0, 0.0], [-10.0, 30.0, -20.0], [0.0, -20.0, 20.0]])
C = np.diag([10.0, 0.0, 0.0])
A = np.array([[1.0, 0.3, 0.0], [0.0, 1.0, 0.0], [0.2, 0.0, 1.0]])
B = np.array([[1.0], [-3.0], [0.5]])


@pytest.mark.parametrize("integrator", ["newmark", "generalized-alpha"])
@pytest.mark.parametrize("method", FORMS)
def test_every_coordinate_held_is_exactly_at_rest(method, integrator):
    """A step load (a kink at 0.3 s, so the acceleration is restarted) on a model the three
    rows hold: q, q', q'' are 0, the loads are carried by the constraint forces,
    A^T lambda = -B f (the reactions)."""
    n_steps, h = 100, 0.01
    t = h * np.arange(n_steps + 1)
    f = np.minimum(t / 0.3, 1.0)[:, None]
    r = transient(M, C, K, A, None, LoadHistory(B, f, h, n_steps), TransientOutputs(np.eye(3)),
                  constraint_labels=["a", "b", "c"],
                  options=TransientOptions(method=method, integrator=integrator,
                                           checks=tuple(m for m in FORMS if m != method)))
    for history in (r.displacement, r.velocity, r.acceleration, r.energy):
        assert not np.any(history)
    assert r.drift == 0.0 and all(v == 0.0 for v in r.agreement.values())
    if method != "modal":
        reaction = -np.linalg.solve(A.T, B @ f.T).T
        assert np.abs(r.constraint_forces - reaction).max() <= 1e3 * np.finfo(float).eps


def test_every_coordinate_held_follows_the_constraints():
    """A settled support (b) and a ground acceleration step at the first row: the motion is
    A^-1 (b + e g(t)), g = g0'' t^2 / 2 (integrated exactly by the scheme), in every form."""
    n_steps, h, g2 = 50, 0.01, 3.0
    b = np.array([0.0, 1e-3, 0.0])
    base = BaseMotion(np.array([1.0, 0.0, 0.0]), "acceleration", np.full(n_steps + 1, g2))
    t = h * np.arange(n_steps + 1)
    exact = np.linalg.solve(A, b[:, None] + np.outer([1.0, 0.0, 0.0], g2 * t * t / 2)).T
    for method in FORMS:
        r = transient(M, C, K, A, b, LoadHistory(B, np.ones((n_steps + 1, 1)), h, n_steps,
                                                 base=base),
                      TransientOutputs(np.eye(3)), initial=InitialConditions(static=True),
                      options=TransientOptions(method=method,
                                               checks=tuple(m for m in FORMS if m != method)))
        scale = np.abs(exact).max()
        assert np.abs(r.displacement - exact).max() <= 1e3 * np.finfo(float).eps * scale
        assert max(r.agreement.values()) <= 1e3 * np.finfo(float).eps, r.agreement


def test_every_coordinate_held_through_the_command_line(tmp_path, capsys):
    """The case of the receptance's exact zero (``frf_all_held``) with a transient: exit 0."""
    case = tmp_path / "held.yaml"
    case.write_text("name: held\n" + DAMPED_THREE_MASS + """\
constraints:
  - {name: a, terms: {P@1: 1}}
  - {name: b, terms: {P@2: 1}}
  - {name: c, terms: {P@3: 1}}
analysis:
  transient:
    t_end: 1
    dt: 0.01
    check: [null-space, modal]
    loads: [{point: P@1}]
    outputs: [P@1]
output: {pictures: false}
""")
    code, text, err = run(capsys, "run", case, "--out", tmp_path / "out", "--json")
    assert code == 0, err


def test_a_load_on_a_held_coordinate_leaves_the_rest_at_rest_within_rounding():
    """One row holds the first coordinate, the only one loaded: the exact response is 0 and the
    forms compute rounding (about 1e-25 of the load's static displacement), whose energy
    balance is rounding over rounding; it is reported, not refused, below the floor
    (:func:`~substruct.analysis.transient.record.roundoff_energy`), and held above it."""
    from substruct.analysis.errors import CheckError
    from substruct.analysis.transient.integrators import scheme
    from substruct.analysis.transient.record import require_energy_balance, roundoff_energy

    n_steps, h = 200, 1e-3
    f = np.full((n_steps + 1, 1), 100.0)
    A1 = np.array([[1.0, 0.0, 0.0]])
    B1 = np.array([[1.0], [0.0], [0.0]])
    for method in FORMS:
        r = transient(M, C, K, A1, None, LoadHistory(B1, f, h, n_steps),
                      TransientOutputs(np.eye(3)),
                      options=TransientOptions(method=method))
        static = 100.0 / 20.0
        assert np.abs(r.displacement).max() <= 1e3 * np.finfo(float).eps * static
    floor = roundoff_energy(sp.csr_array(K), sp.csr_array(M), sp.csr_array(B1), f, h)
    assert 0 < floor < 1e-20 * 100.0 ** 2 / 50.0
    noise = np.array([[0.0, 0.0, 0.0, 0.0], [0.5 * floor, 0.0, 0.0, 0.0]])
    assert require_energy_balance("t", "f", noise, scheme("newmark"), 1e-6, floor) == 1.0
    with pytest.raises(CheckError, match="energy balance"):
        require_energy_balance("t", "f", noise * 4.0, scheme("newmark"), 1e-6, floor)
