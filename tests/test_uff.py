"""Universal File Format: receptances (58) written by substruct and read back by pyuff and by
the FRF substructure reader; modes (55) and nodes (15) to the format's own precision, and the
modes exactly through the double-precision analysis dataset 2414 (nodes through 2411)."""

from __future__ import annotations

import numpy as np
import pytest

from substruct.analysis.results import Modes
from substruct.case.frf_files import read_frf_file
from pathlib import Path

from substruct.case.loader import load_case
from substruct.io.uff import (
    export_uff,
    modes_from_2414,
    read_uff,
    uff15_set,
    uff55_sets,
    uff58_sets,
    uff2411_set,
    uff2414_text,
    write_uff,
)
from substruct.run.runner import build_model, run_case


def _frf(seed=0):
    rng = np.random.default_rng(seed)
    w = np.geomspace(1.0, 3000.0, 37) * np.pi  # not round in Hz: the binary form keeps them
    H = (rng.standard_normal((37, 3, 3)) + 1j * rng.standard_normal((37, 3, 3))) * \
        10.0 ** rng.uniform(-9, 3, (37, 3, 3))
    return w, H


def test_uff58_round_trip_is_exact(tmp_path):
    w, H = _frf()
    labels = ["1:x", "2:y", "17:rz"]
    path = write_uff(tmp_path / "h.uff", uff58_sets(w, H, labels, labels, "mobility"))
    sets = read_uff(path)
    assert [s["type"] for s in sets] == [58] * 9
    first = sets[0]
    assert (first["rsp_node"], first["rsp_dir"], first["ref_node"], first["ref_dir"]) == \
        (1, 1, 1, 1)
    assert first["ordinate_spec_data_type"] == 11 and first["orddenom_spec_data_type"] == 13
    assert sets[5]["rsp_node"] == 2 and sets[5]["ref_dir"] == 6
    np.testing.assert_array_equal(first["x"], w / (2 * np.pi))
    np.testing.assert_array_equal(sets[5]["data"], H[:, 1, 2])
    omega, lab, H2 = read_frf_file(path)
    assert lab == labels
    np.testing.assert_allclose(omega, w, rtol=1e-15)
    # a mobility (velocity / force, 11 over 13) is read as the receptance V / (i omega): one
    # complex division, and omega = 2 pi (w / 2 pi) off w by an ulp at most
    np.testing.assert_allclose(H2, H / (1j * w)[:, None, None], rtol=4e-16 * 8, atol=0)


def test_point_names_become_numbered_nodes(tmp_path):
    w, H = _frf(1)
    sets = read_uff(write_uff(tmp_path / "h.uff",
                              uff58_sets(w, H[:, :2, :1], ["rod@50", "c@mass"], ["rod@200"])))
    # each point its own node: rod@200 is not rod@50's node 1
    assert [(s["rsp_node"], s["ref_node"]) for s in sets] == [(1, 3), (2, 3)]
    assert sets[1]["id4"].strip() == "response c@mass"
    assert sets[1]["id5"].strip() == "reference rod@200"


def test_reader_refuses_an_incomplete_matrix(tmp_path):
    w, H = _frf(2)
    sets = uff58_sets(w, H, ["1:x", "2:x", "3:x"], ["1:x", "2:x", "3:x"])
    write_uff(tmp_path / "h.uff", sets[:-1])
    with pytest.raises(ValueError, match="lacks the function of response 3:x to reference 3:x"):
        read_frf_file(tmp_path / "h.uff")


def test_modes_and_nodes(tmp_path):
    rng = np.random.default_rng(3)
    shapes = rng.standard_normal((5, 2)) + 1j * rng.standard_normal((5, 2))
    lam = np.array([-0.2 + 30j, -1.0 + 70j])
    modes = Modes(method="kkt", eigenvalues=lam, omega=np.abs(lam),
                  damping_ratio=-lam.real / np.abs(lam), shapes=shapes, residual=np.zeros(2))
    sets = read_uff(write_uff(tmp_path / "m.uff", [uff15_set(5), *uff55_sets(modes, "x")]))
    assert [s["type"] for s in sets] == [15, 55, 55]
    np.testing.assert_array_equal(sets[0]["node_nums"], np.arange(1, 6))
    np.testing.assert_array_equal(sets[0]["x"], np.arange(1, 6))
    for k in range(2):
        assert sets[1 + k]["mode_n"] == k + 1
        np.testing.assert_allclose(sets[1 + k]["eig"], lam[k], rtol=5e-6)
        # UFF 55 holds values as E13.5: six significant digits
        np.testing.assert_allclose(sets[1 + k]["r1"], shapes[:, k], rtol=1e-5)


def _modes(n=6, seed=4):
    """Complex modes with values over 17 decades and eigenvalues not round in any base."""
    rng = np.random.default_rng(seed)
    shapes = (rng.standard_normal((n, 3)) + 1j * rng.standard_normal((n, 3))) * \
        10.0 ** rng.uniform(-12, 5, (n, 3))
    lam = np.array([-0.2 + 30j, -1.0 + 70j, -3e-5 + 1e5j]) * np.pi
    return Modes(method="kkt", eigenvalues=lam, omega=np.abs(lam),
                 damping_ratio=-lam.real / np.abs(lam), shapes=shapes, residual=np.zeros(3))


def test_modes_round_trip_exactly_through_2414(tmp_path):
    """The 2414 datasets read back by pyuff give the shapes and eigenvalues bit for bit
    (``%25.16e`` is 17 significant digits); the 55 datasets of the same modes hold 6."""
    modes = _modes()
    path = write_uff(tmp_path / "m.uff", [uff15_set(6), *uff55_sets(modes, "x")],
                     uff2414_text(modes, "x"))
    sets = read_uff(path)
    assert [s["type"] for s in sets] == [15] + [55] * 3 + [2414] * 3
    assert all(len(line) <= 80 for line in path.read_text().splitlines())
    first = sets[4]
    assert (first["analysis_type"], first["data_type"], first["dataset_location"]) == (3, 6, 1)
    lam, shapes = modes_from_2414(sets)
    np.testing.assert_array_equal(lam, modes.eigenvalues)
    np.testing.assert_array_equal(shapes, modes.shapes)
    np.testing.assert_allclose(first["record12_field2"], modes.omega[0] / (2 * np.pi),
                               rtol=5e-6)
    err55 = max(np.abs(sets[1 + k]["r1"] - modes.shapes[:, k]).max() /
                np.abs(modes.shapes[:, k]).max() for k in range(3))
    assert 1e-9 < err55 < 1e-5  # E13.5


def test_pyuff_reads_55_in_13_column_slices(tmp_path):
    """Why 55 cannot carry more digits: pyuff cuts each data line of a 55 dataset into
    13-character fields (the spec's 6E13.5), so the same file with its values written 25 wide
    (17 digits) is not read."""
    modes = _modes(2)
    path = write_uff(tmp_path / "m.uff", uff55_sets(modes, "x")[:1])
    lines = path.read_text().splitlines()
    first = next(i for i, line in enumerate(lines) if i > 9 and line.strip() == "1")
    u = modes.shapes[:, 0]
    for k in range(2):  # the value line after each node line
        assert lines[first + 2 * k].strip() == str(k + 1)
        lines[first + 2 * k + 1] = f"{u[k].real:25.16e}{u[k].imag:25.16e}" + \
            f"{0.0:25.16e}" * 4
    (tmp_path / "wide.uff").write_text("\n".join(lines) + "\n")
    assert read_uff(tmp_path / "m.uff")[0]["r1"].size == 2
    with pytest.raises(Exception, match="Error when reading"):
        read_uff(tmp_path / "wide.uff")


def test_nodes_exact_in_15_and_2411(tmp_path):
    """Nodes at ``x = k``: integers, exact in 15 up to 999,999; 2411 (3D25.16) holds any
    double (here positions that are not integers, read back bit for bit)."""
    last = uff15_set(3)
    last["node_nums"] = last["node_nums"] + 999_996
    last["x"] = last["node_nums"].astype(float)
    sets = read_uff(write_uff(tmp_path / "n.uff", [last]))
    np.testing.assert_array_equal(sets[0]["x"], [999_997.0, 999_998.0, 999_999.0])
    node = uff2411_set(4)
    node["x"] = node["x"] * np.pi
    back = read_uff(write_uff(tmp_path / "n2.uff", [node]))[0]
    assert back["type"] == 2411
    np.testing.assert_array_equal(back["x"], np.arange(1, 5) * np.pi)


def test_export_of_a_result_round_trips(tmp_path):
    """``substruct export --format uff`` of the tapered rod (modes and receptances): pyuff reads
    the modes from 2414 and the receptances from 58 exactly."""
    case = load_case(Path(__file__).resolve().parents[1] / "cases" / "tapered_rod.yaml",
                     ["output.pictures=false"])
    result = run_case(case, model=build_model(case))
    sets = read_uff(export_uff(result, tmp_path))
    lam, shapes = modes_from_2414(sets)
    np.testing.assert_array_equal(lam, result.modes.eigenvalues)
    np.testing.assert_array_equal(shapes, result.modes.shapes)
    frf = [s for s in sets if s["type"] == 58]
    assert len(frf) == result.frf.H.shape[1] * result.frf.H.shape[2]
    np.testing.assert_array_equal(frf[0]["data"], result.frf.H[:, 0, 0])
