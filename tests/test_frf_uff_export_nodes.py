"""UFF export: the nodes of the 58 functions are the nodes the same file's dataset 15 defines
(the model's coordinates 1..n, then the other points), with consistent directions; a
one-frequency result exports; every file is read back by ``pyuff`` and by the plain reader of
``tests/uff_plain.py`` (the spec's columns, read by hand) with the same codes and values."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from substruct.io.uff import export_uff, frf_nodes, read_uff
from substruct.case.loader import load_case
from substruct.run.runner import build_model, run_case
from uff_plain import read_plain

CASES = Path(__file__).resolve().parents[1] / "cases"


def _run(name):
    case = load_case(CASES / name, ["output.pictures=false"])
    return run_case(case, model=build_model(case))


def _check_both_readers(path, result, expect_nodes):
    """pyuff and the plain reader agree on every 58 function: the nodes (all defined by the
    file's 15), the directions, the codes and the values (bit for bit: binary doubles)."""
    frf = result.frf
    sets = read_uff(path)
    plain = read_plain(path.read_bytes())
    n15 = [s for s in sets if s["type"] == 15]
    assert len(n15) == 1
    defined = set(int(k) for k in n15[0]["node_nums"])
    assert defined == set(plain["nodes"]) == set(range(1, max(defined) + 1))
    f58 = [s for s in sets if s["type"] == 58]
    assert len(f58) == len(plain["functions"]) == len(frf.outputs) * len(frf.inputs)
    seen = {}
    k = 0
    for i, out in enumerate(frf.outputs):
        for j, inp in enumerate(frf.inputs):
            a, b = f58[k], plain["functions"][k]
            k += 1
            for key in ("rsp_node", "rsp_dir", "ref_node", "ref_dir", "func_type"):
                assert a[key] == b[key], key
            assert b["func_type"] == 4 and b["abscissa"] == 18 and b["denominator"] == 13
            assert b["numerator"] == 8  # receptance: displacement over force
            assert (b["rsp_node"], b["rsp_dir"]) == expect_nodes[out]
            assert (b["ref_node"], b["ref_dir"]) == expect_nodes[inp]
            assert b["rsp_node"] in defined and b["ref_node"] in defined
            assert b["id4"] == f"response {out}" and b["id5"] == f"reference {inp}"
            for name, nd in ((out, expect_nodes[out]), (inp, expect_nodes[inp])):
                assert seen.setdefault(nd, name) == name  # one name per node and direction
            np.testing.assert_array_equal(a["data"], frf.H[:, i, j])
            np.testing.assert_array_equal(np.array(b["y"]), frf.H[:, i, j])
            np.testing.assert_array_equal(np.array(b["x"]), frf.omega / (2 * np.pi))
            np.testing.assert_array_equal(a["x"], frf.omega / (2 * np.pi))


def test_one_frequency_result_exports_with_coordinate_nodes(tmp_path):
    """cases/three_dof_frf.yaml: one frequency (2 rad/s), points P@q1..q3 that are the
    coordinates P.q1..q3, i.e. the nodes 1..3 of dataset 15 (and of the 55 mode shapes)."""
    result = _run("three_dof_frf.yaml")
    assert result.frf.omega.size == 1
    assert result.model.dof_labels == ["P.q1", "P.q2", "P.q3"]
    path = export_uff(result, tmp_path)
    _check_both_readers(path, result, {"P@q1": (1, 1), "P@q2": (2, 1), "P@q3": (3, 1)})
    # the paper's eq (40), as the case file prints it: H[1, 1] = 0.3361 - 0.0033i
    h = read_plain(path.read_bytes())["functions"][4]["y"][0]
    assert abs(h - (0.3361 - 0.0033j)) < 5e-5


def test_points_off_the_coordinates_get_their_own_nodes(tmp_path):
    """The tapered rod: rod@50 and rod@200 are positions on the rod (no coordinate of their
    own), so they are nodes 11 and 12 after the 10 coordinates; c@mass is coordinate c.mass,
    node 7.  (The export used to number them 1, 2, 3 by their place in the lists, and give the
    driving point rod@200 node 1, which is rod@50's.)"""
    result = _run("tapered_rod.yaml")
    labels = result.model.dof_labels
    assert len(labels) == 10 and labels.index("c.mass") == 6
    assert result.frf.outputs == ["rod@50", "rod@200", "c@mass"]
    path = export_uff(result, tmp_path)
    _check_both_readers(path, result, {"rod@50": (11, 1), "rod@200": (12, 1),
                                       "c@mass": (7, 1)})


def test_node_rules_for_frf_parts_and_file_labels():
    """Coordinates of FRF parts (``A@2:z``): one node per part and node number, the direction
    kept; bare file labels (``5:y``) as given; new nodes after both."""
    nodes, n = frf_nodes(["A@2:x", "A@2:z", "B@2:x", "P@q1", "rod@7", "5:y"], ["P.q1", "P.q2"])
    assert nodes == {"P@q1": (1, 1), "5:y": (5, 2), "A@2:x": (6, 1), "A@2:z": (6, 3),
                     "B@2:x": (7, 1), "rod@7": (8, 1)}
    assert n == 8
    assert len(set(nodes.values())) == len(nodes)
