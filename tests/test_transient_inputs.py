"""The transient block's input: every key of a load used or refused (the shapes as a union
discriminated by shape, walked key by key), the rho_inf a run really used in the file and the
summary, and the general initial states (by point, from an NPZ file, the constrained static
state with a nonzero constraint right-hand side) against closed forms."""

import json

import h5py
import numpy as np
import pytest
import scipy.sparse as sp

from cli_helpers import assert_one_line_error, run
from substruct.case.errors import CaseError
from substruct.case.loader import parse_case
from substruct.case.transient_files import npz_vector
from substruct.case.transient_signals import SHAPE_KEYS, SHAPES
from substruct.run.runner import build_model
from substruct.run.transient_run import transient_result

M1, K1 = 2.0, 800.0
W = np.sqrt(K1 / M1)
#: a value of each shape's own keys
_VALUES = {"start": 0.1, "duration": 0.2, "omega": 3.0, "phase": 0.5, "expression": "sin(t)",
           "table": "f.csv"}


def _case(block, extra=""):
    return f"""
name: inputs
substructures:
  - {{name: s, type: fixed-free, mass: {M1}, stiffness: {K1}}}
{extra}
analysis:
  transient:
{block}
"""


def _load_case(load):
    return _case(f"    t_end: 0.1\n    dt: 0.01\n    outputs: [s@mass]\n"
                 f"    loads: [{json.dumps(load)}]")


def _base_case(sig):
    return _case(f"    t_end: 0.1\n    dt: 0.01\n    outputs: [s@mass]\n"
                 f"    base: {{at: [s@mass], acceleration: {json.dumps(sig)}}}")


@pytest.mark.parametrize("shape", SHAPES)
def test_every_key_of_another_shape_is_refused(shape):
    """Walk the shapes: each takes its own keys, and each key of another shape is refused at
    that key with the shape it belongs to, for loads and for the ground's motion."""
    own = {k: _VALUES[k] for k in SHAPE_KEYS[shape]}
    parse_case(_load_case({"point": "s@mass", "shape": shape, **own}))  # accepted
    for key in sorted({k for keys in SHAPE_KEYS.values() for k in keys} - set(SHAPE_KEYS[shape])):
        for text in (_load_case({"point": "s@mass", "shape": shape, **own, key: _VALUES[key]}),
                     _base_case({"shape": shape, **own, key: _VALUES[key]})):
            with pytest.raises(CaseError) as err:
                parse_case(text, "c.yaml")
            msg = str(err.value)
            assert f".{key}: not a key of shape: {shape} ({key} belongs to shape:" in msg, msg
        with pytest.raises(CaseError, match=r"loads\[0\]\.colour: unknown key"):
            parse_case(_load_case({"point": "s@mass", "shape": shape, **own, "colour": 1}))


@pytest.mark.parametrize("key, shape", [("expression", "expression"), ("table", "table"),
                                        ("omega", "harmonic"), ("duration", "ramp or half-sine")])
def test_a_load_without_a_shape_is_never_a_silent_step(key, shape):
    with pytest.raises(CaseError) as err:
        parse_case(_load_case({"point": "s@mass", key: _VALUES[key]}), "c.yaml")
    assert f"loads[0].{key}: a signal without a shape is a step, which has no {key}: add " \
           f"shape: {shape}" in str(err.value)


def test_an_unknown_shape_is_refused_at_its_key():
    with pytest.raises(CaseError, match=r"loads\[0\]\.shape: must be one of step, ramp"):
        parse_case(_load_case({"point": "s@mass", "shape": "sine", "omega": 1}))


@pytest.mark.parametrize("integrator, rho, stored", [("newmark", None, 1.0),
                                                     ("generalized-alpha", None, 0.9),
                                                     ("generalized-alpha", 0.6, 0.6)])
def test_the_file_and_the_summary_hold_the_rho_inf_used(tmp_path, capsys, integrator, rho,
                                                        stored):
    line = f"    rho_inf: {rho}\n" if rho is not None else ""
    (tmp_path / "c.yaml").write_text(_case(
        f"    t_end: 0.1\n    dt: 0.01\n    integrator: {integrator}\n{line}"
        f"    outputs: [s@mass]\n    loads: [{{point: s@mass}}]"))
    code, out, err = run(capsys, "run", tmp_path / "c.yaml", "--out", tmp_path / "o", "--json",
                         "--no-pictures")
    assert code == 0, err
    assert json.loads(out)["transient"]["rho_inf"] == stored
    with h5py.File(tmp_path / "o" / "inputs.h5") as f:
        assert f["transient"].attrs["rho_inf"] == stored


def _history(text, tmp_path=None):
    case = parse_case(text, base_dir=tmp_path or ".")
    return transient_result(case, build_model(case))


def test_initial_displacement_and_velocity_by_point():
    """x(0) = 0.01, x'(0) = 0.3: x = 0.01 cos wt + 0.3/w sin wt, second order in dt."""
    errs, hs = [], [1e-3, 5e-4]
    for dt in hs:
        r = _history(_case(f"    t_end: 0.2\n    dt: {dt}\n    outputs: [s@mass]\n"
                           f"    initial: {{displacement: {{s@mass: 0.01}}, "
                           f"velocity: {{s@mass: 0.3}}}}"))
        exact = 0.01 * np.cos(W * r.t) + 0.3 / W * np.sin(W * r.t)
        errs.append(float(np.abs(r.displacement[:, 0] - exact).max()))
    # Newmark's phase error, w^3 h^2 t / 12 of the amplitude at t
    amp = np.hypot(0.01, 0.3 / W)
    assert errs[1] < 1.2 * amp * W ** 3 * hs[1] ** 2 * 0.2 / 12, errs
    assert 3.9 < errs[0] / errs[1] < 4.1, errs


def test_initial_state_from_a_file_is_the_same_state(tmp_path):
    text = _case("    t_end: 0.05\n    dt: 0.001\n    outputs: [s@mass]\n"
                 "    initial: {displacement: {s@mass: 0.01}, velocity: {s@mass: 0.3}}")
    by_point = _history(text)
    case = parse_case(text)
    n = build_model(case).assembly.n_dof
    q0 = np.zeros(n)
    q0[0] = 0.01
    v0 = np.zeros(n)
    v0[0] = 0.3
    np.savez(tmp_path / "state.npz", displacement=q0, velocity=v0)
    from_file = _history(_case("    t_end: 0.05\n    dt: 0.001\n    outputs: [s@mass]\n"
                               "    initial: {file: state.npz}"), tmp_path)
    assert np.array_equal(from_file.displacement, by_point.displacement)
    assert np.array_equal(from_file.velocity, by_point.velocity)


def test_a_state_vector_is_read_through_its_header(tmp_path):
    np.savez(tmp_path / "v.npz", displacement=np.arange(4.0), velocity=np.ones((2, 2)))
    assert np.array_equal(npz_vector(tmp_path / "v.npz", "displacement", 4, exact=4),
                          np.arange(4.0))
    assert npz_vector(tmp_path / "v.npz", "other", 4) is None
    with pytest.raises(ValueError, match="displacement has 4 entries, 3 expected"):
        npz_vector(tmp_path / "v.npz", "displacement", 4, exact=3)
    with pytest.raises(ValueError, match="velocity must be a 1-D array"):
        npz_vector(tmp_path / "v.npz", "velocity", 4)
    np.savez(tmp_path / "c.npz", displacement=np.ones(3, dtype=complex))
    with pytest.raises(ValueError, match="holds complex128 entries, not real numbers"):
        npz_vector(tmp_path / "c.npz", "displacement", 3)


_SETTLED = """
constraints:
  - {name: settle, terms: {a@mass: 1}, rhs: 0.002}
connections:
  - [a@boundary, b@mass]
"""


def _settled_case(initial, t_end=0.05):
    return f"""
name: settled
substructures:
  - {{name: a, type: free-free, mass: 1.0, stiffness: 400}}
  - {{name: b, type: fixed-free, mass: 2.0, stiffness: 900}}
{_SETTLED}
analysis:
  transient:
    t_end: {t_end}
    dt: 0.001
    check: [null-space, modal]
    tolerance: 1.0e-9
    loads: [{{point: b@mass, amplitude: 5.0}}]
    outputs: [a@mass, b@mass, a@boundary]
{initial}
"""


def test_static_start_with_a_nonzero_constraint_rhs_stays_at_rest(tmp_path, capsys):
    """A support moved by 0.002 (constant right-hand side) and a step load present from t = 0:
    the run starts from K q + A^T l = P, A q = b and stays there, in all three forms."""
    case = parse_case(_settled_case("    initial: static"))
    model = build_model(case)
    asm = model.assembly
    r = transient_result(case, model)
    n, m = asm.n_dof, asm.A.shape[0]
    P = np.asarray(asm.rows([model.points["b@mass"]]).T.toarray()).ravel() * 5.0
    kkt = sp.block_array([[asm.K, asm.A.T], [asm.A, None]], format="csc")
    q = sp.linalg.spsolve(kkt, np.concatenate([P, np.asarray(asm.b, float)]))[:n]
    O = asm.rows([model.points[p] for p in ("a@mass", "b@mass", "a@boundary")])
    static = O @ q
    assert abs(static[0] - 0.002) < 1e-15
    scale = float(np.abs(static).max())
    assert np.abs(r.displacement - static[None, :]).max() < 1e-12 * scale
    assert np.abs(r.velocity).max() < 1e-9 * scale
    assert max(r.agreement.values()) < 1e-9


def test_a_nonzero_constraint_rhs_needs_a_consistent_start(tmp_path, capsys):
    (tmp_path / "c.yaml").write_text(_settled_case(""))
    code, out, err = run(capsys, "run", tmp_path / "c.yaml", "--out", tmp_path / "o")
    assert_one_line_error(code, out, err, "analysis.transient.initial: the initial "
                          "displacement violates the constraints: residual", "initial: static")
    assert not (tmp_path / "o").exists() or not any((tmp_path / "o").iterdir())


def test_static_start_under_a_load_then_released_rings_about_zero():
    """Static under P(0) = F (a ramp from F down to 0 over one step from t = 0): the mass
    starts at F/k at rest, and after the release vibrates as x = F/k cos(w (t - h)) ..., to
    the scheme's order."""
    dt = 1e-4
    r = _history(_case(f"    t_end: 0.1\n    dt: {dt}\n    outputs: [s@mass]\n"
                       "    initial: static\n"
                       "    loads: [{point: s@mass, amplitude: 4.0},\n"
                       f"            {{point: s@mass, amplitude: -4.0, shape: ramp, "
                       f"duration: {dt}}}]"))
    assert r.displacement[0, 0] == pytest.approx(4.0 / K1, rel=1e-14)
    # the release over one step: the free vibration from F/k at rest, shifted by half a step
    exact = 4.0 / K1 * np.cos(W * (r.t - dt / 2))
    assert np.abs(r.displacement[1:, 0] - exact[1:]).max() < 1e-3 * 4.0 / K1
