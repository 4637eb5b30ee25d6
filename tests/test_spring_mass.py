"""``type: spring`` and ``type: mass`` in case files: closed-form frequencies, equivalence with
the same model written as ``type: matrices``, one-line errors, the free-end warning, drawings
and the shipped case ``two_rods_spring.yaml``."""

from pathlib import Path

import numpy as np
import pytest
import yaml
from scipy.optimize import brentq

from substruct import cli
from substruct.case.loader import CaseError, load_case, parse_case
from substruct.run.runner import build_model, run_case

CASES = Path(__file__).resolve().parent.parent / "cases"
CASE = CASES / "two_rods_spring.yaml"
FAST = ["analysis.frf.omega={start: 1000, stop: 60000, num: 40, spacing: log}"]
NO_CHECKS = FAST + ["analysis.modes.check=[]", "analysis.frf.check=[]"]


def case_of(data: dict, overrides=()):
    return parse_case(yaml.safe_dump(data, sort_keys=False), "cases/x.yaml", CASES, overrides)


def error_of(data: dict, overrides=(), build=False) -> str:
    with pytest.raises(CaseError) as info:
        case = case_of(data, overrides)
        if build:
            build_model(case)
    message = str(info.value)
    assert "\n" not in message and message.startswith("cases/x.yaml: ")
    return message


def roots(f, hi: float, count: int, n: int = 20000) -> np.ndarray:
    """The first ``count`` sign changes of ``f`` on (0, hi], refined by brentq."""
    x = np.linspace(hi / n, hi, n)
    y = np.array([f(v) for v in x])
    out = [brentq(f, x[k], x[k + 1], xtol=1e-14, rtol=1e-15)
           for k in np.flatnonzero(np.sign(y[:-1]) * np.sign(y[1:]) < 0)]
    # tan-type functions change sign at their poles too: keep true zeros only
    out = [r for r in out if abs(f(r)) < 1e-6]
    assert len(out) >= count
    return np.array(out[:count])


# ---------------------------------------------------------------- closed-form systems

TWO_MASSES = {
    "name": "two_masses",
    "substructures": [
        {"name": "m1", "type": "mass", "mass": 2.0},
        {"name": "m2", "type": "mass", "mass": 2.0},
        {"name": "k1", "type": "spring", "stiffness": 100.0, "ground": True},
        {"name": "k2", "type": "spring", "stiffness": 100.0},
    ],
    "connections": [["m1", "k1"], ["m1", "k2@i"], ["k2@j", "m2"]],
    "analysis": {"modes": {"count": 2, "check": ["null-space", "kkt"]},
                 "frf": {"omega": [1.0, 3.0, 7.5, 20.0], "inputs": ["m1", "m2"],
                         "outputs": ["m1", "m2"], "check": ["null-space", "kkt"]}},
}


def test_two_masses_from_pieces_match_closed_form():
    """ground -k- m -k- m: omega^2 = k/m (3 -+ sqrt 5)/2; H = (K - omega^2 M)^-1."""
    m, k = 2.0, 100.0
    result = run_case(case_of(TWO_MASSES))
    expected = np.sqrt(k / m * (3 - np.array([1, -1]) * np.sqrt(5)) / 2)
    np.testing.assert_allclose(result.modes.omega, expected, rtol=1e-13)
    assert np.allclose(result.modes.damping_ratio, 0.0, atol=1e-12)
    K = np.array([[2 * k, -k], [-k, k]])
    for w, H in zip(result.frf.omega, result.frf.H):
        np.testing.assert_allclose(H, np.linalg.inv(K - w ** 2 * m * np.eye(2)), rtol=1e-12,
                                   atol=1e-15)
    assert all(v < 1e-12 for v in result.frf.agreement.values())
    assert all(v < 1e-12 for v in result.modes.agreement.values())


def test_damped_grounded_spring_on_a_mass_is_a_damped_oscillator():
    """m on k and c to ground: lambda = -zeta w0 +- i w0 sqrt(1 - zeta^2)."""
    data = {"name": "sdof",
            "substructures": [{"name": "m", "type": "mass", "mass": 3.0},
                              {"name": "g", "type": "spring", "stiffness": 1200.0,
                               "damping": 6.0, "ground": True}],
            "connections": [["m", "g"]],
            "analysis": {"modes": {"count": 1}}}
    result = run_case(case_of(data))
    w0 = np.sqrt(1200.0 / 3.0)
    np.testing.assert_allclose(result.modes.omega, [w0], rtol=1e-12)
    np.testing.assert_allclose(result.modes.damping_ratio, [6.0 / (2 * np.sqrt(1200 * 3))],
                               rtol=1e-10)


def rod_case(elements: int, attach: dict, connection: list) -> dict:
    return {"name": "rod_tip",
            "substructures": [{"name": "rod", "type": "rod", "length": 1.0, "EA": 1.0, "m": 1.0,
                               "support": "fixed-free",
                               "discretization": {"method": "fe", "elements": elements,
                                                  "order": 2}}, attach],
            "connections": [connection],
            "analysis": {"modes": {"count": 3, "check": []}}}


def test_rod_with_tip_point_mass_converges_to_transcendental_equation():
    """Fixed-free rod (EA = m = L = 1) with a point mass M at the tip: beta L tan(beta L) =
    m L / M, omega = beta sqrt(EA/m).  P2 elements converge like h^4 on the eigenvalues."""
    M = 0.5
    exact = roots(lambda b: b * np.sin(b) - (1.0 / M) * np.cos(b), 10.0, 3)
    np.testing.assert_allclose(exact[0], 1.0768739863118038, rtol=1e-12)  # b tan b = 2
    errors = []
    for n in (2, 4, 8, 16):
        case = case_of(rod_case(n, {"name": "tip", "type": "mass", "mass": M},
                                ["rod@1", "tip"]))
        errors.append(abs(run_case(case).modes.omega - exact) / exact)
    errors = np.array(errors)
    assert np.all(np.diff(errors, axis=0) < 0)          # every mode improves at every level
    assert np.all(errors[-2] / errors[-1] > 12)          # ~ 2^4 per halving of h
    assert errors[-1].max() < 5e-5 and errors[-1][0] < 1e-7


def test_rod_with_grounded_spring_at_tip_matches_transcendental_equation():
    """Fixed-free rod with a spring k to ground at its tip: EA beta cos(beta L) = -k sin(beta L)."""
    k = 3.0
    exact = roots(lambda b: b * np.cos(b) + k * np.sin(b), 10.0, 3)
    errors = []
    for n in (16, 32):
        case = case_of(rod_case(n, {"name": "g", "type": "spring", "stiffness": k,
                                    "ground": True}, ["rod@1", "g"]))
        errors.append(abs(run_case(case).modes.omega - exact) / exact)
    assert np.all(errors[0] / errors[1] > 12) and errors[1].max() < 5e-6


def test_spring_between_two_rods_matches_transcendental_equation():
    """Rod 1 fixed at 0, rod 2 fixed at its far end, their free ends joined by k:
    det [[EA1 b1 c1 + k s1, -k s2], [k s1, -EA2 b2 c2 - k s2]] = 0 with b_r = w sqrt(m_r/EA_r),
    s_r = sin(b_r L_r), c_r = cos(b_r L_r)."""
    EA1, m1, L1, EA2, m2, L2, k = 2.0, 1.0, 1.0, 1.0, 0.5, 0.6, 1.5

    def det(w):
        b1, b2 = w * np.sqrt(m1 / EA1), w * np.sqrt(m2 / EA2)
        s1, c1, s2, c2 = np.sin(b1 * L1), np.cos(b1 * L1), np.sin(b2 * L2), np.cos(b2 * L2)
        return (EA1 * b1 * c1 + k * s1) * (-EA2 * b2 * c2 - k * s2) + k * s2 * k * s1

    exact = roots(det, 12.0, 4)
    rod = {"type": "rod", "discretization": {"method": "fe", "elements": 32, "order": 2}}
    data = {"name": "two_rods",
            "substructures": [rod | {"name": "r1", "length": L1, "EA": EA1, "m": m1,
                                     "support": "fixed-free"},
                              rod | {"name": "r2", "length": L2, "EA": EA2, "m": m2,
                                     "support": "free-fixed"},
                              {"name": "s", "type": "spring", "stiffness": k}],
            "connections": [["r1@1", "s@i"], ["s@j", "r2@0"]],
            "analysis": {"modes": {"count": 4, "check": ["null-space", "kkt"]}}}
    result = run_case(case_of(data))
    np.testing.assert_allclose(result.modes.omega, exact, rtol=5e-6)
    assert abs(result.modes.omega[0] / exact[0] - 1) < 1e-8


# ------------------------------------------------------- the same model as matrices

AS_MATRICES = {
    "s": "substructures.s={name: s, type: matrices, M: [[0, 0], [0, 0]], "
         "K: [[5.0e6, -5.0e6], [-5.0e6, 5.0e6]], C: [[20, -20], [-20, 20]], labels: [i, j]}",
    "m1": "substructures.m1={name: m1, type: matrices, M: [[0.5]], K: [[0]], labels: [mass]}",
}


@pytest.mark.parametrize("which", [["s"], ["m1"], ["s", "m1"]])
def test_spring_and_mass_equal_the_same_model_as_matrices(which):
    """two_rods_spring.yaml with its spring and/or point mass written as type: matrices."""
    base = run_case(load_case(CASE, NO_CHECKS))
    other = load_case(CASE, NO_CHECKS + [AS_MATRICES[w] for w in which]
                      + ["connections[2]=[steel@L/2, m1@mass]",
                         "analysis.frf.outputs=[steel@1.0, alu@0, m1@mass]"])
    assert {s.name: s.type for s in other.substructures}["s"] == \
        ("matrices" if "s" in which else "spring")
    alt = run_case(other)
    np.testing.assert_allclose(alt.modes.omega, base.modes.omega, rtol=1e-12)
    np.testing.assert_allclose(alt.modes.damping_ratio, base.modes.damping_ratio, rtol=1e-8)
    np.testing.assert_allclose(alt.frf.H, base.frf.H, rtol=1e-10,
                               atol=1e-10 * np.abs(base.frf.H).max())


def test_grounded_spring_equals_matrices():
    spring = {"name": "g", "type": "spring", "stiffness": 3.0, "damping": 0.1, "ground": True}
    matrices = {"name": "g", "type": "matrices", "M": [[0]], "K": [[3.0]], "C": [[0.1]],
                "labels": ["i"]}
    a = run_case(case_of(rod_case(8, spring, ["rod@1", "g"])))
    b = run_case(case_of(rod_case(8, matrices, ["rod@1", "g@i"])))
    np.testing.assert_allclose(a.modes.omega, b.modes.omega, rtol=1e-12)
    np.testing.assert_allclose(a.modes.damping_ratio, b.modes.damping_ratio, rtol=1e-8)
    assert a.modes.damping_ratio.min() > 0


# ------------------------------------------------------------------ the shipped case


def test_shipped_case_runs_with_pictures(tmp_path, capsys):
    code = cli.main(["run", str(CASE), "--out", str(tmp_path), "--quiet", "--set", FAST[0]])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert err == ""  # both spring ends are connected: no warning
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == ["two_rods_spring.h5", "two_rods_spring_frf.png",
                     "two_rods_spring_modes.png"]
    import matplotlib.image
    for png in tmp_path.glob("*.png"):
        assert matplotlib.image.imread(png)[..., :3].std() > 0.01


def test_shipped_case_numbers():
    """Modes of two_rods_spring.yaml: converged (twice the elements move them < 3e-6),
    checked by both other formulations; the FRF at the lowest frequency is quasi-static."""
    result = run_case(load_case(CASE, FAST))
    finer = run_case(load_case(CASE, NO_CHECKS + [
        "substructures.steel.discretization.elements=80",
        "substructures.alu.discretization.elements=48", "analysis.frf=null"]))
    np.testing.assert_allclose(result.modes.omega, finer.modes.omega, rtol=3e-6)
    np.testing.assert_allclose(result.modes.omega[:3], [6599.1939, 14313.7254, 20340.6464],
                               rtol=1e-8)
    assert max(result.modes.agreement.values()) < 1e-10
    assert result.modes.residual.max() < 1e-12
    assert result.frf.constraint_residual < 1e-12
    assert max(result.frf.agreement.values()) < 1e-8
    # at 1000 rad/s (0.15 of the first mode) H is close to the static flexibility: a force
    # F at the steel tip sees k_steel = EA/L in parallel with (k in series with k_alu)
    k_steel, k_alu, k = 2.1e7 / 1.0, 1.4e7 / 0.6, 5.0e6
    k_joint = k * k_alu / (k + k_alu)
    static = np.array([1 / (k_steel + k_joint), k_joint / k_alu / (k_steel + k_joint),
                       0.5 / (k_steel + k_joint)])     # mid-span of the steel rod: half
    H0 = result.frf.H[0, :, 0]
    np.testing.assert_allclose(abs(H0), static, rtol=0.03)
    assert np.all(H0.real > 0)


def test_shipped_case_drawings_lay_the_rods_end_to_end():
    model = build_model(load_case(CASE))
    d = {x.name: x for x in model.drawings}
    steel, alu, s, m1 = (np.asarray(d[n].points) for n in ("steel", "alu", "s", "m1"))
    assert np.isclose(steel[:, 0].min(), 0.0) and np.isclose(steel[:, 0].max(), 1.0)
    # a spring a tenth of the longest rod long, then the aluminium rod from its end
    np.testing.assert_allclose(s, [[1.0, 0, 0], [1.1, 0, 0]], atol=1e-12)
    assert np.isclose(alu[:, 0].min(), 1.1) and np.isclose(alu[:, 0].max(), 1.7)
    np.testing.assert_allclose(m1, [[0.5, 0, 0]], atol=1e-12)
    assert d["s"].kind == "spring" and d["m1"].kind == "mass"


# ------------------------------------------------------------------ errors, warnings


def spring_case(**spring) -> dict:
    data = yaml.safe_load(CASE.read_text())
    data["substructures"][2] = {"name": "s", "type": "spring", "stiffness": 5.0e6} | spring
    return data


@pytest.mark.parametrize("field, value, fragment", [
    ("stiffness", 0, "substructures.s.stiffness: must be > 0, got 0"),
    ("stiffness", -5.0, "substructures.s.stiffness: must be > 0, got -5.0"),
    ("stiffness", ".inf", "substructures.s.stiffness: must be a finite number"),
    ("damping", -1, "substructures.s.damping: must be >= 0, got -1"),
    ("damping", True, "substructures.s.damping: must be a number, not true/false"),
    ("ground", "maybe", "substructures.s.ground: must be true or false, got 'maybe'"),
    ("stifness", 3, "substructures.s.stifness: unknown key; did you mean 'stiffness'?"),
])
def test_spring_errors_are_one_line(field, value, fragment):
    data = spring_case()
    text = yaml.safe_dump(data, sort_keys=False).replace(
        "type: spring\n", f"type: spring\n  {field}: {value}\n".replace("True", "true"))
    if field == "stiffness":
        text = text.replace("  stiffness: 5000000.0\n", "")
    with pytest.raises(CaseError) as info:
        parse_case(text, "cases/x.yaml", CASES)
    assert fragment in str(info.value) and "\n" not in str(info.value)


@pytest.mark.parametrize("value, fragment", [
    (0, "substructures.m1.mass: must be > 0, got 0"),
    (-0.5, "substructures.m1.mass: must be > 0, got -0.5"),
    (float("nan"), "substructures.m1.mass: must be a finite number"),
    ("heavy", "substructures.m1.mass: must be a number, got 'heavy'"),
])
def test_mass_errors_are_one_line(value, fragment):
    data = yaml.safe_load(CASE.read_text())
    data["substructures"][3]["mass"] = value
    assert fragment in error_of(data)


def test_mass_unknown_key_names_the_key():
    data = yaml.safe_load(CASE.read_text())
    data["substructures"][3]["stiffness"] = 3
    assert "substructures.m1.stiffness: unknown key" in error_of(data)


@pytest.mark.parametrize("connection, fragment", [
    (["s", "alu@0"], "connections[1][0]: spring 's' has two ends: write s@i or s@j, got 's'"),
    (["s@k", "alu@0"], "connections[1][0]: s: no point 'k'"),
    (["s@j", "m1@boundary"], "connections[1][1]: m1: no point 'boundary'"),
])
def test_bad_points_on_springs_and_masses(connection, fragment):
    data = yaml.safe_load(CASE.read_text())
    data["connections"][1] = connection
    assert fragment in error_of(data, build=True)


def test_grounded_spring_has_point_i_only():
    data = spring_case(ground=True)
    assert "connections[1][0]: s: no point 'j'" in error_of(data, build=True)
    data["connections"][1] = ["s", "alu@0"]  # a bare name is the grounded spring's point i
    data["connections"][0] = ["steel@1.0", "m1"]
    data["connections"][2] = ["steel@L/2", "alu@0.3"]
    build_model(case_of(data))


def test_spring_with_a_free_end_warns_on_one_line_and_carries_no_force(tmp_path, capsys):
    # s@j joined to nothing (a connection of a point to itself is refused: it joins nothing)
    drop = "connections=[[steel@1.0, s@i], [steel@L/2, m1]]"
    free = ["--set", drop, "--set", "output.pictures=false",
            "--set", "analysis.frf=null", "--quiet"]
    code = cli.main(["run", str(CASE), "--out", str(tmp_path), *free])
    out, err = capsys.readouterr()
    assert code == 0 and out == ""
    assert err.count("\n") == 1 and err.startswith("substruct: warning: ")
    assert "substructures.s: spring 's': s@j is in no connection or constraint" in err
    # the spring carries no force: its stiffness and damping change nothing
    loose = run_case(load_case(CASE, [drop, "analysis.frf=null"]))
    other = run_case(load_case(CASE, [drop, "analysis.frf=null",
                                      "substructures.s.stiffness=7e8",
                                      "substructures.s.damping=0"]))
    np.testing.assert_allclose(loose.modes.omega, other.modes.omega, rtol=1e-10)
    np.testing.assert_allclose(other.modes.damping_ratio, 0.0, atol=1e-12)
    reasons = " ".join(loose.modes.spurious_reason)
    assert "infinite root" in reasons


def test_convergence_study_rejects_springs_and_masses():
    from substruct.builder.rod_system_case import spec_from_case
    case = case_of(rod_case(8, {"name": "tip", "type": "mass", "mass": 0.5}, ["rod@1", "tip"]))
    with pytest.raises(CaseError) as info:
        spec_from_case(case)
    message = str(info.value)
    assert "substructures.tip.type" in message and "spring and mass" in message
    assert message.endswith("got 'mass'")
