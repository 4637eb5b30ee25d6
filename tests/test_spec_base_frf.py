"""The case door of the base-driven frequency response (``analysis.base_frf``,
substruct/run/base_frf_route.py), run through ``substruct run``: a single-DOF oscillator on a
moving base against the closed-form transmissibility, a three-mass model on two tables against
a dense KKT solve per frequency written here, the same model's ``analysis.random`` response
PSD against ``|T|^2 S_in``, and bad input refused in one line."""

import copy

import h5py
import numpy as np
import pytest
import yaml

from base_drive_reference import dense_transmissibility
from cli_helpers import assert_one_line_error, run
from substruct.case.loader import load_case
from substruct.io.result_reader import load

K1, M1 = 1.0e5, 1.0
C1 = 31.6227766
ZETA = C1 / (2 * float(np.sqrt(K1 * M1)))
WN = float(np.sqrt(K1 / M1))

SDOF = {
    "name": "sdof",
    "units": "N, m, kg, s",
    "substructures": [{"name": "s", "type": "free-free", "mass": M1, "stiffness": K1,
                       "damping": C1}],
    "constraints": [{"name": "table", "terms": {"s@boundary": 1}}],
    "analysis": {"base_frf": {
        "omega": {"start": 0.05 * WN, "stop": 5 * WN, "num": 400, "spacing": "log"},
        "base": {"at": ["s@boundary"]},
        "outputs": ["s@mass", "s@boundary"],
        "check": ["kkt"]}},
    "output": {"pictures": False},
}

TABLES = {
    "name": "two_tables",
    "units": "N, m, kg, s",
    "substructures": [
        {"name": "a", "type": "free-free", "mass": 1.0, "stiffness": 1.0e4, "damping": 6.0},
        {"name": "b", "type": "free-free", "mass": 2.0, "stiffness": 3.0e4, "damping": 9.0},
        {"name": "c", "type": "free-free", "mass": 0.5, "stiffness": 5.0e3, "damping": 2.0},
    ],
    "connections": [["a@mass", "c@boundary"], ["c@mass", "b@mass"]],
    "constraints": [{"name": "ta", "terms": {"a@boundary": 1}},
                    {"name": "tb", "terms": {"b@boundary": 2}}],
    "analysis": {"base_frf": {
        "omega": {"start": 2, "stop": 60, "num": 300, "spacing": "log"},
        "units": "Hz",
        "bases": [{"name": "left", "at": ["a@boundary"]},
                  {"name": "right", "at": ["b@boundary"]}],
        "outputs": ["a@mass", "b@mass", "c@mass"],
        "check": ["null-space"]}},
    "output": {"pictures": False},
}


def _run(capsys, tmp_path, case):
    path = tmp_path / f"{case['name']}.yaml"
    path.write_text(yaml.safe_dump(case))
    code, out, err = run(capsys, "run", path, "--out", tmp_path / "out", "--force")
    return path, code, out, err, tmp_path / "out" / f"{case['name']}.h5"


def _read(h5path):
    with h5py.File(h5path) as f:
        g = f["base_frf"]
        return ({k: g[k][()] for k in ("omega", "f", "transmissibility")},
                [s.decode() for s in g["outputs"][()]], [s.decode() for s in g["inputs"][()]],
                dict(g.attrs), dict(g["agreement"].attrs))


@pytest.mark.parametrize("quantity,power", [("acceleration", 2), ("velocity", 1),
                                            ("displacement", 0)])
def test_sdof_transmissibility_closed_form(capsys, tmp_path, quantity, power):
    """|T| = |1 + 2 i zeta r| / |1 - r^2 + 2 i zeta r| (acceleration per base acceleration), the
    complex value too, and (i w)^(p - 2) times it for velocity and displacement; the base
    itself moves with the table (T = 1 there). The rounding of the 2 x 2 solves bounds the
    error by ~1e-14 of max |T| = Q."""
    case = copy.deepcopy(SDOF)
    case["analysis"]["base_frf"]["quantity"] = quantity
    _, code, out, err, h5path = _run(capsys, tmp_path, case)
    assert code == 0, err
    data, outputs, inputs, attrs, agreement = _read(h5path)
    assert outputs == ["s@mass", "s@boundary"] and inputs == ["base"]
    assert attrs["quantity"] == quantity and attrs["per"] == "acceleration"
    assert agreement["kkt"] < 1e-12 and agreement["relative-coordinates"] < 1e-12
    w = data["omega"]
    np.testing.assert_allclose(data["f"], w / (2 * np.pi), rtol=1e-15)
    r = w / WN
    exact = (1 + 2j * ZETA * r) / (1 - r ** 2 + 2j * ZETA * r) * (1j * w) ** (power - 2)
    T = data["transmissibility"]
    assert T.shape == (400, 2, 1)
    scale = np.abs(exact).max()
    assert np.abs(T[:, 0, 0] - exact).max() <= 1e-10 * scale
    assert np.abs(np.abs(T[:, 0, 0]) - np.abs(exact)).max() <= 1e-10 * scale
    np.testing.assert_allclose(T[:, 1, 0], (1j * w) ** (power - 2), rtol=1e-10)
    if quantity == "acceleration":
        k = int(np.argmax(np.abs(exact)))
        row = next(line.split() for line in out.splitlines() if line.startswith("  s@mass"))
        assert row == ["s@mass", "base", f"{np.abs(exact[k]):.4e}", f"{w[k] / (2 * np.pi):.4g}"]


def direct(case, f):
    """``T`` ``(n_f, outputs, bases)`` of ``analysis.base_frf`` by a dense KKT solve per
    frequency (:func:`base_drive_reference.dense_transmissibility`)."""
    return dense_transmissibility(case, case.analysis.base_frf, f)


def test_two_tables_against_dense_kkt(capsys, tmp_path):
    """Two tables (one row with coefficient 2), three outputs: the run's T equals the dense KKT
    solve to 1e-9 of max |T| (both direct solves of a well-conditioned 5 x 5 system; the run's
    own checks agree to ~1e-15)."""
    path, code, out, err, h5path = _run(capsys, tmp_path, TABLES)
    assert code == 0, err
    data, outputs, inputs, _, agreement = _read(h5path)
    assert inputs == ["left", "right"] and outputs == ["a@mass", "b@mass", "c@mass"]
    assert max(agreement.values()) < 1e-10
    f = data["f"]
    np.testing.assert_allclose(f, np.geomspace(2, 60, 300), rtol=1e-14)
    T = direct(load_case(path), f)
    assert np.abs(data["transmissibility"] - T).max() <= 1e-9 * np.abs(T).max()
    assert "left" in out and "right" in out and "peak |T|" in out
    back = load(h5path).base_frf  # read back as written
    assert back is not None and back.inputs == ["left", "right"]
    np.testing.assert_array_equal(back.T, data["transmissibility"])
    assert back.agreement == agreement and back.quantity == "acceleration"


def test_random_psd_is_T_squared_times_input(capsys, tmp_path):
    """analysis.random on the same model and grid, one table moved by a PSD S_in (the other
    held): the response auto-PSD is |T|^2 S_in at every frequency (to 1e-9 of its largest)."""
    case = copy.deepcopy(TABLES)
    case["analysis"]["base_frf"]["bases"] = [{"name": "left", "at": ["a@boundary"]}]
    case["analysis"]["random"] = {
        "frequencies": {"start": 2, "stop": 60, "num": 300, "spacing": "log"},
        "bases": [{"name": "left", "at": ["a@boundary"], "psd": [[2, 1.5], [60, 0.25]]}],
        "outputs": ["a@mass", "b@mass", "c@mass"],
        "quantity": "acceleration"}
    _, code, out, err, h5path = _run(capsys, tmp_path, case)
    assert code == 0, err
    data = _read(h5path)[0]
    with h5py.File(h5path) as f:
        psd, s_in, fr = f["random/psd"][()], f["random/input_psd"][()], f["random/f"][()]
    np.testing.assert_allclose(fr, data["f"], rtol=1e-14)
    s = np.exp(np.interp(np.log(fr), np.log([2, 60]), np.log([1.5, 0.25])))
    np.testing.assert_allclose(s_in[:, 0], s, rtol=1e-12)
    T = data["transmissibility"][:, :, 0]
    auto = np.real(np.einsum("kii->ki", psd))
    expect = np.abs(T) ** 2 * s[:, None]
    assert np.abs(auto - expect).max() <= 1e-9 * expect.max()


@pytest.mark.parametrize("edit,fragments", [
    (lambda a: a["base_frf"].update(outputs=["s@mass"], base={"at": ["s@mass"]}),
     ["analysis.base_frf.base.at[0]", "not a grounded support", "s@mass"]),
    (lambda a: a["base_frf"].update(omega=[0.0, 10.0]),
     ["analysis.base_frf.omega", "must be > 0", "0.0"]),
    (lambda a: a["base_frf"].update(bases=[{"name": "x", "at": ["s@boundary"]}]),
     ["analysis.base_frf.bases", "one of the two"]),
    (lambda a: a["base_frf"].update(base={"at": ["s@nowhere"]}),
     ["analysis.base_frf.base.at[0]", "s@nowhere"]),
    (lambda a: a["base_frf"].update(loss_factor={"t": 0.1}),
     ["analysis.base_frf.loss_factor.t", "not a substructure"]),
])
def test_bad_input_one_line(capsys, tmp_path, edit, fragments):
    case = copy.deepcopy(SDOF)
    edit(case["analysis"])
    _, code, out, err, h5path = _run(capsys, tmp_path, case)
    assert_one_line_error(code, out, err, *fragments)
    assert not h5path.exists()


def test_two_inputs_sharing_a_support(capsys, tmp_path):
    case = copy.deepcopy(TABLES)
    case["analysis"]["base_frf"]["bases"][1]["at"] = ["b@boundary", "a@boundary"]
    _, code, out, err, h5path = _run(capsys, tmp_path, case)
    assert_one_line_error(code, out, err, "analysis.base_frf.bases.right.at",
                          "another base input already moves")
    assert not h5path.exists()
