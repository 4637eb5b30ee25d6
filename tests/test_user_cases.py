"""Cases an engineer writes from docs/case-files.md alone, checked against closed forms:
the printed receptance table of a stiff structure in SI units, connections that join
nothing, and the message of a malformed polynomial distribution."""

import re
from pathlib import Path

import numpy as np
import pytest
import yaml

from substruct import cli
from substruct.cli.summary import complex_text, needs_scientific
from substruct.case.loader import CaseError, parse_case
from substruct.run.runner import build_model, run_case

CASES = Path(__file__).resolve().parent.parent / "cases"


def case_of(data: dict):
    return parse_case(yaml.safe_dump(data, sort_keys=False), "cases/x.yaml", CASES, ())


def error_of(data: dict) -> str:
    with pytest.raises(CaseError) as info:
        build_model(case_of(data))
    message = str(info.value)
    assert "\n" not in message and message.startswith("cases/x.yaml: ")
    return message


# ------------------------------------------------- the printed table of small receptances

#: a fixed-free uniform steel rod (SI units) with a grounded spring at its tip
L, EA, MU, KS = 1.0, 2.1e7, 0.785, 1.0e9
STIFF_ROD = {
    "name": "stiff_rod",
    "units": "N, m, kg, s",
    "substructures": [
        {"name": "rod", "type": "rod", "length": L, "EA": EA, "m": MU,
         "support": "fixed-free", "discretization": {"method": "fe", "elements": 40, "order": 2}},
        {"name": "g", "type": "spring", "stiffness": KS, "ground": True},
    ],
    "connections": [["rod@L", "g"]],
    "analysis": {"frf": {"omega": [500.0, 3000.0], "inputs": ["rod@L"],
                         "outputs": ["rod@L", "rod@0.3"]}},
    "output": {"pictures": False},
}


def rod_tip_receptance(omega: float, x: float) -> float:
    r"""``u(x) / F(L)`` of the uniform fixed-free rod with a grounded spring ``k_s`` at
    ``x = L``: the tip dynamic stiffness is ``EA k cot(k L) + k_s`` (``k = omega
    sqrt(m/EA)``) and the shape ``sin(k x) / sin(k L)``."""
    k = omega * np.sqrt(MU / EA)
    tip = 1.0 / (EA * k / np.tan(k * L) + KS)
    return tip * np.sin(k * x) / np.sin(k * L)


def test_small_receptances_are_printed_with_their_digits(tmp_path, capsys):
    """|H| ~ 1e-9 m/N: fixed decimals printed 0.0000+0.0000i for every entry; the table now
    switches to scientific notation and shows 4 significant figures of the closed form."""
    path = tmp_path / "stiff_rod.yaml"
    path.write_text(yaml.safe_dump(STIFF_ROD, sort_keys=False))
    assert cli.main(["run", str(path), "--out", str(tmp_path / "out")]) == 0
    text = capsys.readouterr().out
    for omega in (500.0, 3000.0):
        block = text.split(f"H at omega = {omega:g} rad/s")[1]
        for out_x, label in ((L, "rod@L"), (0.3, "rod@0.3")):
            row = re.search(rf"^\s+{re.escape(label)}\s+(\S+)i$", block, re.M).group(1)
            value = complex(row + "j")
            expected = rod_tip_receptance(omega, out_x)
            assert abs(expected) < 1e-8
            assert value.real == pytest.approx(expected, rel=1e-3)
            assert value.imag == 0.0


def test_order_one_receptances_keep_fixed_decimals():
    assert complex_text(0.0246 - 0.0295j) == "0.0246-0.0295i"
    assert not needs_scientific(np.array([[0.3361 - 0.0033j, 0.0082]]))
    assert needs_scientific(np.array([[1.0e-9, 3.5e-10]]))
    assert complex_text(1.0e-9 - 3.512e-10j, scientific=True) == "1.000e-09-3.512e-10i"


# ----------------------------------------------------------- connections that join nothing

def two_rods(support_b: str, chain: list[str]) -> dict:
    rod = {"type": "rod", "length": 1.0, "EA": 1.0, "m": 1.0,
           "discretization": {"method": "fe", "elements": 20, "order": 2}}
    return {"name": "two_rods",
            "substructures": [{"name": "a", **rod, "support": "fixed-free"},
                              {"name": "b", **rod, "support": support_b}],
            "connections": [chain],
            "analysis": {"modes": {"count": 4, "check": ["null-space", "kkt"]}},
            "output": {"pictures": False}}


def test_rods_joined_end_to_end_are_one_rod_of_double_length():
    """A fixed-free rod and a free-free rod joined at a@L = b@0: the fixed-free rod of length
    2L, ``omega_i = (2i - 1) pi c / 4L`` (c = 1)."""
    result = run_case(case_of(two_rods("free-free", ["a@L", "b@0"])))
    expected = [(2 * i - 1) * np.pi / 4 for i in range(1, 5)]
    np.testing.assert_allclose(result.modes.omega, expected, rtol=2e-5)  # P2, h = 1/20


@pytest.mark.parametrize("chain, fragment", [
    (["a@1", "a@L"], "connections[0][1]: connects nothing: a@1 and a@L are the same coordinate"),
    (["b@0", "a@L", "a@1.0"],
     "connections[0][2]: connects nothing: a@L and a@1.0 are the same coordinate"),
    (["a@0", "b@L"], "connections[0][1]: connects nothing: a@0 and b@L are supported"),
])
def test_a_connection_that_joins_nothing_is_refused(chain, fragment):
    """Its row of A would be empty (as a constraint whose terms cancel, which is refused)."""
    message = error_of(two_rods("free-fixed", chain))
    assert fragment in message and "empty row of A" in message


def test_a_connection_to_a_supported_point_is_a_support():
    """One side supported is a real constraint: b (free-free) pinned to a's clamp at b@0 is the
    fixed-free rod b, omega = (2i - 1) pi / 2, plus the fixed-free rod a itself."""
    result = run_case(case_of(two_rods("free-free", ["a@0", "b@0"])))
    expected = sorted([(2 * i - 1) * np.pi / 2 for i in range(1, 3)] * 2)
    np.testing.assert_allclose(result.modes.omega, expected, rtol=2e-5)  # P2, h = 1/20


# ---------------------------------------------------------------- malformed distributions

@pytest.mark.parametrize("EA, fragment", [
    ({"poly": []}, 'poly needs a non-empty list of coefficients, got {"poly": []}'),
    ({"poly": [1.0], "c": 2}, "{poly: [c0, c1, ...]} (unknown keys: c), got {"),
])
def test_a_bad_polynomial_shows_its_value_once(EA, fragment):
    data = two_rods("free-free", ["a@L", "b@0"])
    data["substructures"][0]["EA"] = EA
    with pytest.raises(CaseError) as info:
        case_of(data)
    message = str(info.value)
    assert fragment in message and message.count(", got ") == 1


# ------------------------------------------------------ stiffness matrices that are not PSD

def two_masses(K: list) -> dict:
    return {"name": "two_masses",
            "substructures": [{"name": "P", "type": "matrices", "M": [[1.0, 0.0], [0.0, 2.0]],
                               "K": K}],
            "analysis": {"modes": {"count": 2, "check": ["null-space", "kkt"]}},
            "output": {"pictures": False}}


def test_free_two_mass_matrices_have_a_rigid_mode_and_the_spring_mode():
    """Masses 1 and 2 on a spring k = 1/3: omega = 0 and sqrt(k (m1 + m2) / (m1 m2))."""
    k = 1.0 / 3.0
    result = run_case(case_of(two_masses([[k, -k], [-k, k]])))
    np.testing.assert_allclose(result.modes.omega, [0.0, np.sqrt(k * 1.5)], atol=1e-12)
    np.testing.assert_allclose(result.modes.damping_ratio, [0.0, 0.0], atol=1e-12)


@pytest.mark.parametrize("K, fragment", [
    # the same spring written with 8 digits: the rigid-body pair became +-8.2e-5 (real), and
    # was reported as two modes of damping ratio +1 and -1 in place of omega = 0.7071
    ([[0.33333333, -0.33333334], [-0.33333334, 0.33333333]],
     "smallest eigenvalue -1e-08 (1.5e-08 of the largest: a rigid-body motion needs K u = 0"),
    # a sign slip, statically unstable: eigenvalues 15 -+ sqrt(425)
    ([[10.0, -20.0], [-20.0, 20.0]],
     f"smallest eigenvalue {(30 - np.sqrt(30**2 - 4 * (200 - 400))) / 2:.6g}, got"),
])
def test_an_indefinite_stiffness_matrix_is_refused(K, fragment):
    with pytest.raises(CaseError) as info:
        case_of(two_masses(K))
    message = str(info.value)
    assert "substructures.P.K: must be positive semidefinite" in message
    assert fragment in message


# -------------------------------------- solver: auto on a larger undamped model (sparse path)


def test_auto_takes_the_sparse_path_for_a_large_undamped_rod_and_keeps_its_rigid_mode():
    """A free-free uniform rod of 601 coordinates (P2, 300 elements), ``c = 2``, ``L = 2``:
    ``omega_i = i pi c / L = i pi``; ``auto`` solves it sparse (the dense pencil takes about a
    minute), reports the rigid-body mode as exactly 0 like the dense path, and the three
    sparse formulations agree."""
    data = {"name": "free_rod",
            "substructures": [{"name": "r", "type": "rod", "length": 2.0, "EA": 4.0, "m": 1.0,
                               "support": "free-free",
                               "discretization": {"method": "fe", "elements": 300, "order": 2}}],
            "analysis": {"modes": {"count": 5, "check": ["null-space", "kkt"]}},
            "output": {"pictures": False}}
    result = run_case(case_of(data))
    modes = result.modes
    assert modes.method == "null-space/sparse"
    assert modes.omega[0] == 0.0
    np.testing.assert_allclose(modes.omega[1:], np.pi * np.arange(1, 5), rtol=1e-8)  # P2: 2e-9
    assert max(modes.agreement.values()) < 1e-9
    data["substructures"][0]["discretization"]["elements"] = 150  # 301 coordinates: dense
    small = run_case(case_of(data)).modes
    assert small.method == "generalized-inverse" and small.omega[0] == 0.0


# ---------------------------------------- an absorber on a solid is drawn along its component


@pytest.mark.parametrize("component, axis", [("z", 2), ("y", 1), ("x", 0)])
def test_an_absorber_on_a_solid_is_drawn_moving_along_its_component(component, axis):
    """``[beam@1,0.05,0.1:z, tmd]``: the absorber's mass moves (and hangs) along z in the
    picture, as it does in the model; before, every discrete system was drawn moving along x."""
    data = {"name": "beam_tmd",
            "substructures": [
                {"name": "beam", "type": "solid",
                 "box": {"lengths": [1.0, 0.1, 0.1], "divisions": [4, 1, 1]},
                 "E": 2.1e11, "nu": 0.3, "rho": 7850, "fixed": ["xmin"]},
                {"name": "tmd", "type": "free-free", "mass": 0.5, "stiffness": 2.0e5}],
            "connections": [[f"beam@1,0.05,0.1:{component}", "tmd"]],
            "analysis": {"modes": {"count": 2}}}
    model = build_model(case_of(data))
    tmd = next(d for d in model.drawings if d.name == "tmd")
    j = model.assembly.offsets[1]  # the absorber's coordinates: mass, boundary
    u = np.zeros(model.assembly.n_dof)
    u[j] = 1.0
    moves = np.asarray(tmd.interp @ u).reshape(-1, 3)[tmd.glyphs["mass"]]
    np.testing.assert_array_equal(moves, np.eye(3)[axis])
    hang = tmd.points[tmd.glyphs["mass"]] - tmd.points[tmd.glyphs["boundary"]]
    assert hang[axis] < 0 and np.count_nonzero(hang) == 1
