"""Case files: schema, one-line errors naming field and value, --set overrides, building."""

import copy
from pathlib import Path

import numpy as np
import pytest
import scipy.io
import scipy.sparse as sp
import yaml

from substruct.case.loader import CaseError, apply_overrides, load_case, parse_case, parse_point
from substruct.run.runner import build_model

CASES = Path(__file__).resolve().parent.parent / "cases"
TABLE1 = yaml.safe_load((CASES / "tapered_rod_table1.yaml").read_text())
THREE = yaml.safe_load((CASES / "three_dof_frf.yaml").read_text())
FE = yaml.safe_load((CASES / "tapered_rod_fe.yaml").read_text())
#: The reference case with its rod reduced to 20 modes (the shipped case keeps every coordinate).
FE_REDUCED = copy.deepcopy(FE)
FE_REDUCED["substructures"][0]["reduce"] = {"modes": 20}


def error_of(data=None, text=None, overrides=(), base_dir=CASES, build=False) -> str:
    """The one-line message of the CaseError that a case raises."""
    text = yaml.safe_dump(data, sort_keys=False) if text is None else text
    with pytest.raises(CaseError) as info:
        case = parse_case(text, "cases/x.yaml", base_dir, overrides)
        if build:
            build_model(case)
    message = str(info.value)
    assert "\n" not in message and message.startswith("cases/x.yaml: ")
    return message


def changed(base, path, value=None, delete=False):
    data = copy.deepcopy(base)
    node = data
    for key in path[:-1]:
        node = node[key]
    if delete:
        del node[path[-1]]
    else:
        node[path[-1]] = value
    return data


@pytest.mark.parametrize("path", sorted(CASES.glob("*.yaml")), ids=lambda p: p.name)
def test_every_case_file_validates(path):
    case = load_case(path)
    assert case.name == path.stem
    assert case.text == path.read_text()
    assert case.source == str(path)


# ------------------------------------------------------------------- one error per class

ROD = ("substructures", 0)
BAD = [
    # (base, path, value, expected "path: problem", expected value)
    ("unknown key", TABLE1, ("substructures", 0, "lenght"), 200,
     "substructures.rod.lenght: unknown key; did you mean 'length'? (allowed: name, type, "
     "length", "got 200"),
    ("unknown top key", TABLE1, ("outputs",), {}, "outputs: unknown key", "got {}"),
    ("negative length", TABLE1, (*ROD, "length"), -200,
     "substructures.rod.length: must be > 0", "got -200"),
    ("wrong type", TABLE1, (*ROD, "length"), "long", "substructures.rod.length: must be a number",
     "got 'long'"),
    ("nan", TABLE1, (*ROD, "length"), float("nan"), "substructures.rod.length: must be a finite "
     "number", "got nan"),
    ("inf", TABLE1, ("substructures", 1, "mass"), float("inf"), "substructures.a.mass: must be a "
     "finite number", "got inf"),
    ("zero mass", TABLE1, ("substructures", 1, "mass"), 0, "substructures.a.mass: must be > 0",
     "got 0"),
    ("zero stiffness", TABLE1, ("substructures", 3, "stiffness"), 0.0,
     "substructures.c.stiffness: must be > 0", "got 0.0"),
    ("negative damping", TABLE1, ("substructures", 3, "damping"), -1,
     "substructures.c.damping: must be >= 0", "got -1"),
    ("bad name", TABLE1, ("name",), "my case", "name: must be a name of letters", "got 'my case'"),
    ("unknown substructure type", TABLE1, ("substructures", 1, "type"), "beam",
     "substructures.a.type: unknown type (expected one of rod, fixed-free", "got 'beam'"),
    ("unknown discretization", TABLE1, (*ROD, "discretization", "method"), "ritz",
     "substructures.rod.discretization.method: unknown method", "got 'ritz'"),
    ("unknown support", TABLE1, (*ROD, "support"), "pinned",
     "substructures.rod.support: must be one of 'fixed-free'", "got 'pinned'"),
    ("unknown modes method", TABLE1, ("analysis", "modes", "method"), "svd",
     "analysis.modes.method: must be one of 'generalized-inverse'", "got 'svd'"),
    ("unknown check method", TABLE1, ("analysis", "modes", "check", 1), "lu",
     "analysis.modes.check[1]: must be one of", "got 'lu'"),
    ("bad expression", TABLE1, (*ROD, "EA"), "__import__('os').system('true')",
     "substructures.rod.EA: call of", "got \"__import__('os')"),
    ("unknown name", TABLE1, (*ROD, "m"), "6/5*m1*(1 - x/L)",
     "substructures.rod.m: unknown name 'm1'", "got '6/5*m1*(1 - x/L)'"),
    ("EA not positive", TABLE1, (*ROD, "EA"), "EA0*(1 - x/L)",
     "substructures.rod.EA: must be > 0 and finite on [0, L]: EA(200) = 0", "got 'EA0*(1 - x/L)'"),
    ("EA wrong type", TABLE1, (*ROD, "EA"), [1, 2],
     "substructures.rod.EA: must be a number, an expression", "got [1, 2]"),
    ("duplicate substructure", TABLE1, ("substructures", 2, "name"), "a",
     "substructures[2].name: duplicate substructure name", "got 'a'"),
    ("empty constraint", TABLE1, ("constraints", 0, "terms"), {},
     "constraints.eq52.terms: a constraint needs at least one term", "got {}"),
    ("bad point syntax", TABLE1, ("connections", 1), ["rod@", "b"],
     "connections[1][0]: a point is written 'substructure@where'", "got 'rod@'"),
    ("short connection", TABLE1, ("connections", 1), ["rod@100"],
     "connections[1]: must have at least 2 item(s)", 'got ["rod@100"]'),
    ("too many assumed modes", TABLE1, (*ROD, "discretization", "n"), 50000,
     "substructures.rod.discretization.n: 50000 assumed modes would need about", "got 50000"),
    ("too many elements", FE, (*ROD, "discretization", "elements"), 3_000_000,
     "substructures.rod.discretization.elements: 3000000 elements would need about 12 GB",
     "got 3000000"),
    ("fractional count", TABLE1, (*ROD, "discretization", "n"), 8.5,
     "substructures.rod.discretization.n: must be an integer", "got 8.5"),
    ("more reduced modes than DOFs", TABLE1, (*ROD, "reduce", "modes"), 9,
     "substructures.rod.reduce.modes: more modes than the rod's 8 assumed modes", "got 9"),
    ("more modes than DOFs", TABLE1, ("analysis", "modes", "count"), 11,
     "analysis.modes.count: more modes than the 10 coordinates of the model", "got 11"),
    ("unknown variant constraint", TABLE1, ("analysis", "modes", "variants", 0, "drop"),
     ["eq53"], "analysis.modes.variants.without_eq52.drop[0]: no active constraint of that name",
     "got 'eq53'"),
    ("negative damping ratio", TABLE1, (*ROD, "reduce", "damping"), {"ratio": -0.1},
     "substructures.rod.reduce.damping.ratio: a damping ratio must be finite and >= 0",
     "got -0.1"),
    ("nothing to compute", TABLE1, ("analysis",), {}, "analysis: nothing to compute", "got {}"),
    ("non-square matrix", THREE, ("substructures", 0, "M"), [[1, 0], [0, 2], [0, 0]],
     "substructures.P.M: must be square, is 3 x 2", "got [[1, 0], [0, 2], [0, 0]]"),
    ("ragged matrix", THREE, ("substructures", 0, "M"), [[1, 0, 0], [0, 2], [0, 0, 4]],
     "substructures.P.M: must be a list of rows of numbers, all of equal length", "got [[1, 0"),
    ("non-symmetric matrix", THREE, ("substructures", 0, "K"),
     [[20, -10, 0], [-10, 30, -20], [0, -21, 20]],
     "substructures.P.K: must be symmetric: max |K - K^T| = 1", "got [[20, -10, 0]"),
    ("wrongly sized matrix", THREE, ("substructures", 0, "C"), [[1, 0], [0, 1]],
     "substructures.P.C: must be 3 x 3 like M, is 2 x 2", "got [[1, 0], [0, 1]]"),
    ("indefinite mass", THREE, ("substructures", 0, "M"), [[1, 2, 0], [2, 1, 0], [0, 0, 4]],
     "substructures.P.M: must be positive semidefinite: smallest eigenvalue -1", "got [[1, 2"),
    ("labels", THREE, ("substructures", 0, "labels"), ["a", "b"],
     "substructures.P.labels: 2 labels for 3 coordinates", 'got ["a", "b"]'),
    ("grid backwards", THREE, ("analysis", "frf", "omega"), {"start": 10, "stop": 1, "num": 5},
     "analysis.frf.omega.stop: must be > start (10)", "got 1.0"),
    ("log grid from zero", THREE, ("analysis", "frf", "omega"),
     {"start": 0, "stop": 10, "num": 5, "spacing": "log"},
     "analysis.frf.omega.start: must be > 0 for a log grid", "got 0.0"),
    ("grid too fine", THREE, ("analysis", "frf", "omega"), {"start": 1, "stop": 2, "num": 10**7},
     "analysis.frf.omega.num: at most 100000 frequencies", "got 10000000"),
    ("omega zero", THREE, ("analysis", "frf", "omega"), [0.0, 1.0],
     "analysis.frf.omega: the generalized-inverse receptance (eq 15) is singular", "got 0.0"),
    ("negative omega", THREE, ("analysis", "frf", "omega"), [1.0, -2.0],
     "analysis.frf.omega[1]: must be >= 0", "got -2.0"),
    ("no inputs", THREE, ("analysis", "frf", "inputs"), [],
     "analysis.frf.inputs: must have at least 1 item(s)", "got []"),
    ("bad parameter name", THREE, ("parameters", "pi"), 3.0,
     "parameters.pi: a parameter name must be an identifier", "got 'pi'"),
]


@pytest.mark.parametrize("label, base, path, value, where_what, got", BAD, ids=[b[0] for b in BAD])
def test_each_bad_input_class_is_one_line_naming_field_and_value(label, base, path, value,
                                                                  where_what, got):
    message = error_of(changed(base, path, value))
    assert f"cases/x.yaml: {where_what}" in message
    assert message.endswith(got) or f", {got}" in message


def test_missing_fields():
    assert error_of(changed(TABLE1, ("name",), delete=True)) == \
        "cases/x.yaml: name: required field is missing"
    assert error_of(changed(TABLE1, (*ROD, "length"), delete=True)) == \
        "cases/x.yaml: substructures.rod.length: required field is missing"
    assert ("substructures.a.type: needs type: one of rod, fixed-free, free-free, spring, "
            "mass, matrices") in error_of(changed(TABLE1, ("substructures", 1, "type"),
                                                  delete=True))


def test_yaml_errors_name_the_line():
    text = "name: x\nsubstructures:\n  - name: a\n    mass: [1, 2\n"
    assert error_of(text=text).startswith("cases/x.yaml: line 5, column 1: invalid YAML")
    assert error_of(text="name: x\nname: y\n") == \
        "cases/x.yaml: line 2, column 1: invalid YAML: duplicate key 'name'"
    assert "a case file is a mapping" in error_of(text="- 1\n- 2\n")
    assert "got empty file" in error_of(text="")


def test_file_errors(tmp_path):
    with pytest.raises(CaseError, match="no such case file"):
        load_case(tmp_path / "nope.yaml")
    with pytest.raises(CaseError, match="is a directory"):
        load_case(tmp_path)


# ---------------------------------------------------------------------------- overrides


def test_overrides_by_name_index_and_brackets():
    data = copy.deepcopy(TABLE1)
    paths = apply_overrides(data, ["substructures.c.stiffness=8000", "substructures[1].mass=2",
                                   "substructures.2.damping=0.5", "connections.0=[rod@25, a]",
                                   "analysis.modes.check=[kkt]", "output.pictures=false",
                                   "constraints[1]={name: tie, terms: {rod@100: 1}}"])
    assert data["substructures"][3]["stiffness"] == 8000
    assert data["substructures"][1]["mass"] == 2 and data["substructures"][2]["damping"] == 0.5
    assert data["connections"][0] == ["rod@25", "a"]
    assert data["analysis"]["modes"]["check"] == ["kkt"] and data["output"]["pictures"] is False
    assert data["constraints"][1]["name"] == "tie"
    assert paths[:3] == ["substructures.c.stiffness", "substructures.a.mass",
                         "substructures.b.damping"]


def test_override_changes_the_validated_case_and_its_text():
    case = load_case(CASES / "three_dof_frf.yaml", ["parameters.k3=40"])
    np.testing.assert_array_equal(case.substructures[0].matrix("K"),
                                  [[20, -10, 0], [-10, 50, -40], [0, -40, 40]])
    assert case.overrides == ("parameters.k3=40",)
    assert "# --set parameters.k3=40" in case.text and "k3: 40" in case.text


@pytest.mark.parametrize("override, message", [
    ("substructures.zz.mass=1", "--set substructures.zz.mass: no item named 'zz' in substructures "
                                "(names: rod, a, b, c, d)"),
    ("substructures.c.stiffness", "--set substructures.c.stiffness: expected key.path=value"),
    ("connections.9=[rod@50, a]", "--set connections.9: no item 9 in connections"),
    ("name.first=x", "--set name.first: name is a value, not a mapping or list"),
    ("analysis.modes.count=[1", "--set analysis.modes.count: value is not valid YAML"),
    ("substructures.c.stiffness=-5", "substructures.c.stiffness: must be > 0 (set on the command "
                                     "line), got -5"),
    ("substructures.c.springs=5", "substructures.c.springs: unknown key"),
])
def test_bad_overrides(override, message):
    assert message in error_of(TABLE1, overrides=[override])


# ------------------------------------------------------------------------ matrix files


def test_matrices_from_npz_npy_and_mtx(tmp_path):
    M = np.diag([1.0, 2.0, 4.0])
    K = np.array([[20.0, -10, 0], [-10, 30, -20], [0, -20, 20]])
    C = np.zeros((3, 3))
    C[0, 0] = 10.0
    np.savez(tmp_path / "sys.npz", M=M, stiffness=K)
    np.save(tmp_path / "M.npy", M)
    scipy.io.mmwrite(str(tmp_path / "C.mtx"), sp.coo_matrix(C))
    data = copy.deepcopy(THREE)
    data.pop("parameters")
    data["substructures"][0].update(M={"file": "sys.npz"},
                                    K={"file": "sys.npz", "key": "stiffness"},
                                    C={"file": "C.mtx"})
    (tmp_path / "c.yaml").write_text(yaml.safe_dump(data))
    P = load_case(tmp_path / "c.yaml").substructures[0]
    np.testing.assert_array_equal(P.matrix("M"), M)
    np.testing.assert_array_equal(P.matrix("K"), K)
    np.testing.assert_array_equal(P.matrix("C").toarray(), C)
    data["substructures"][0]["M"] = {"file": "M.npy"}
    assert parse_case(yaml.safe_dump(data), base_dir=tmp_path).substructures[0].n_dof() == 3

    def bad(field, value):
        return error_of(changed(data, ("substructures", 0, field), value), base_dir=tmp_path)
    assert "substructures.P.K.key: no array 'K' in sys.npz (it has M, stiffness), got 'K'" in \
        bad("K", {"file": "sys.npz", "key": "K"})
    assert "substructures.P.K.file: no such file" in bad("K", {"file": "nope.npz"})
    assert "substructures.P.K.file: matrix files are .npz, .npy or .mtx" in \
        bad("K", {"file": "k.txt"})
    (tmp_path / "junk.npz").write_text("not a zip")
    assert "substructures.P.K.file: cannot read matrix" in bad("K", {"file": "junk.npz"})


# -------------------------------------------------------------- points, found on building


def test_parse_point():
    assert parse_point("rod@50") == ("rod", "50")
    assert parse_point(" a ") == ("a", None)
    assert parse_point("P@q1") == ("P", "q1")


@pytest.mark.parametrize("base, override, message", [
    (TABLE1, "connections[2]=[rod@250, c]",
     "connections[2][0]: point is not on rod 'rod' [0, 200], got 'rod@250'"),
    (TABLE1, "connections[2]=[rodd@150, c]",
     "connections[2][0]: unknown substructure 'rodd' (known: rod, a, b, c, d), got 'rodd@150'"),
    (TABLE1, "connections[2]=[rod, c]",
     "connections[2][0]: a point on rod 'rod' needs a position"),
    (TABLE1, "connections[2]=[rod@150, c@spring]",
     "connections[2][1]: c: no point 'spring'"),
    (TABLE1, "connections[2]=[rod@60, c]",
     "connections[2][0]: rod: the paper-literal mapping (reproducing Table 1, not physical) only "
     "knows the stations"),
    (TABLE1, "constraints.eq52.terms={rod@50: 1, rod@50.0: -1}",
     "constraints.eq52.terms: eq52: its terms cancel"),
    (THREE, "analysis.frf.inputs=[P@q4]", "analysis.frf.inputs[0]: 'P' has no coordinate 'q4'"),
    (THREE, "analysis.frf.outputs=[P@0]", "analysis.frf.outputs[0]: 'P' has no coordinate '0'"),
    (FE_REDUCED, "substructures.rod.discretization.elements=2",
     "substructures.rod.reduce.modes: rod: n_keep = 20 modes requested, but the substructure has"),
])
def test_points_are_resolved_when_building(base, override, message):
    assert message in error_of(base, overrides=[override], build=True)


def test_build_model_rows_and_drawings():
    case = load_case(CASES / "tapered_rod_table1.yaml")
    model = build_model(case)
    asm, active = model.assembly, model.constraints
    assert active == ["eq52"]
    assert asm.constraint_labels == ["rod@50 = a", "rod@100 = b", "rod@150 = c", "rod@200 = d",
                                     "eq52"]
    assert asm.n_dof == 10 and asm.A.shape == (5, 10)
    # absorbers are drawn at their attachment points
    where = {d.name: d.points[0] for d in model.drawings}
    for name, x in zip("abcd", (50.0, 100.0, 150.0, 200.0)):
        assert where[name][0] == x
    assert all(d.interp.shape[1] == 10 for d in model.drawings)
    # points may be written as expressions of L and the parameters
    same = build_model(load_case(CASES / "tapered_rod_table1.yaml",
                                 ["connections[0]=[rod@L/4, a]"]))
    assert (same.assembly.A != asm.A).nnz == 0


def test_inactive_constraints_are_left_out():
    case = load_case(CASES / "tapered_rod_table1.yaml",
                     ["constraints.eq52.active=false", "analysis.modes.variants=[]"])
    assert build_model(case).assembly.A.shape == (4, 10)


def test_numbers_with_exponents_are_numbers():
    text = (CASES / "tapered_rod_table1.yaml").read_text().replace(
        "reduce: {modes: 4}", "reduce: {modes: 4, damping: {ratio: 2e-3}}").replace(
        "EA0: 6.0e6", "EA0: 6e6")
    case = parse_case(text)
    assert case.parameters["EA0"] == 6e6
    assert case.substructures[0].reduce.damping.as_argument() == 0.002
    assert yaml.safe_load("x: 6e6")["x"] == "6e6"  # PyYAML itself is left alone


NONHOMOGENEOUS = CASES / "three_dof_frf_nonhomogeneous.yaml"


def test_inconsistent_constraints_are_refused_before_computing():
    # eq41 reads q1 + 2 q3 = F1 + F2 + 3 F3; twice its left side with another right side.
    # The misfit is measured on the equilibrated rows (both left sides become [.5, 0, 1]):
    # R of eq41 becomes [.5, .5, 1.5], that of 'again' [.25, 0, 0]; 1.5 apart, relative to 1.5
    case = load_case(NONHOMOGENEOUS, [
        "constraints[1]={name: again, terms: {P@q1: 2, P@q3: 4}, rhs_force: {P@q1: 1}}"])
    with pytest.raises(CaseError, match=r"constraints.again.rhs_force: inconsistent constraints: "
                                        r"the left-hand side of 'again' is 2 x \(eq41\), but its "
                                        r"rhs_force is not the same combination \(differs by 1, "
                                        r"relative\), got \{\"P@q1\": 1.0\}"):
        build_model(case)
    # constant right-hand sides too
    case = load_case(NONHOMOGENEOUS, [
        "constraints.eq41.rhs=1",
        "constraints[1]={name: again, terms: {P@q1: 2, P@q3: 4}, rhs: 1, "
        "rhs_force: {P@q1: 2, P@q2: 2, P@q3: 6}}"])
    with pytest.raises(CaseError, match=r"constraints.again.rhs: inconsistent constraints: .*"
                                        r"its rhs is not the same combination.*, got 1.0$"):
        build_model(case)


def test_redundant_but_consistent_constraints_are_accepted():
    case = load_case(NONHOMOGENEOUS, [
        "constraints[1]={name: again, terms: {P@q1: 2, P@q3: 4}, "
        "rhs_force: {P@q1: 2, P@q2: 2, P@q3: 6}}"])
    assert build_model(case).assembly.A.shape == (2, 3)


def test_dense_eigenproblem_is_refused_up_front():
    from substruct.run import analyses as run
    case = load_case(CASES / "tapered_rod_fe.yaml", [
        "substructures.rod.reduce=null", "substructures.rod.discretization.elements=1500",
        "analysis.modes.solver=dense"])  # auto would solve this undamped model sparse
    # 1500 P2 elements: at least 2999 free nodes, plus 6 coordinates of the attachments
    with pytest.raises(CaseError, match=r"analysis.modes: the coupled eigenproblem is dense and "
                                        r"the model has at least 3005 coordinates \(about 2.31 GB"):
        build_model(case)  # before anything is built
    with pytest.raises(CaseError, match=r"the model has 3006 coordinates \(about 2.31 GB"):
        run.check_dense_sizes(case, 3006, at_least=False)  # the exact count, once built


# ---------------------------------------------------------------- hostile YAML and files


def test_anchors_and_merge_keys_still_work():
    text = (CASES / "tapered_rod_table1.yaml").read_text().replace(
        "  - {name: a, type: fixed-free, mass: 1, stiffness: 3000}",
        "  - &spring {name: a, type: fixed-free, mass: 1, stiffness: 3000}").replace(
        "  - {name: b, type: fixed-free, mass: 1, stiffness: 9000}",
        "  - {<<: *spring, name: b, stiffness: 9000}")
    case = parse_case(text)
    assert case.substructures[2].stiffness == 9000 and case.substructures[2].mass == 1


def test_alias_bombs_and_deep_nesting_are_refused_quickly():
    import time
    bomb = "a0: &a0 [x, x, x, x, x, x, x, x, x, x]\n" + "".join(
        f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 10)}]\n" for i in range(1, 9))
    start = time.perf_counter()
    assert "invalid YAML: aliases expand to more than 1000000 values" in error_of(text=bomb)
    assert "invalid YAML: a structure that contains itself" in \
        error_of(text="name: &x [*x]\n")
    assert error_of(text="name: " + "[" * 5000 + "]" * 5000) == \
        "cases/x.yaml: line 1, column 27: invalid YAML: nested more than 20 levels deep"
    assert "nested more than 20 levels deep" in error_of(
        text="".join(" " * i + "- \n" for i in range(300)))
    assert time.perf_counter() - start < 5


def test_matrix_file_headers_are_read_before_the_data(tmp_path):
    data = copy.deepcopy(THREE)
    data.pop("parameters")
    data["substructures"][0].update(M=[[1, 0, 0], [0, 2, 0], [0, 0, 4]],
                                    K=[[20, -10, 0], [-10, 30, -20], [0, -20, 20]], C=None)

    def bad(name):
        return error_of(changed(data, ("substructures", 0, "K"), {"file": name}),
                        base_dir=tmp_path)
    # an .npy header that promises 10^5 x 10^5 doubles (80 GB) over 8 bytes of data
    header = np.lib.format.header_data_from_array_1_0(np.zeros((1, 1)))
    header["shape"] = (100_000, 100_000)
    with open(tmp_path / "huge.npy", "wb") as f:
        np.lib.format.write_array_header_1_0(f, header)
        f.write(np.zeros(1).tobytes())
    assert "substructures.P.K.file: a 100000 x 100000 matrix with 10000000000 stored entries " \
           "would need about 160 GB of memory, more than the 4 GB allowed, got 'huge.npy'" in \
        bad("huge.npy")
    # the same inside an .npz
    import zipfile
    with zipfile.ZipFile(tmp_path / "huge.npz", "w") as z:
        z.write(tmp_path / "huge.npy", "K.npy")
    assert "a 100000 x 100000 matrix with 10000000000 stored entries" in bad("huge.npz")
    scipy.io.mmwrite(str(tmp_path / "c.mtx"), sp.coo_matrix(np.eye(3) * 1j))
    assert "substructures.P.K.file: must be a real matrix, the file holds a complex one" in \
        bad("c.mtx")
    np.save(tmp_path / "s.npy", np.array([["a", "b"], ["c", "d"]]))
    assert "substructures.P.K.file: must hold a real matrix, holds <U1 entries" in bad("s.npy")
    np.save(tmp_path / "empty.npy", np.zeros((0, 0)))
    data["substructures"][0]["M"] = {"file": "empty.npy"}
    assert "substructures.P.M: must have at least one row" in bad("empty.npy")


def test_receptances_too_large_for_memory_are_refused():
    message = error_of(changed(THREE, ("analysis", "frf"), {
        "omega": {"start": 1, "stop": 2, "num": 100000}, "inputs": ["P@q1"] * 300,
        "outputs": ["P@q2"] * 300, "check": ["kkt"]}))
    assert "analysis.frf: the receptances would need about 288 GB of memory (100000 frequencies " \
           "x 300 outputs x 300 inputs, complex, 2 array(s) at a time), more than this machine " \
           "has available, got {\"frequencies\": 100000, \"outputs\": 300, \"inputs\": 300}" \
           in message
