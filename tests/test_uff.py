"""Universal File Format: receptances (58) written by substruct and read back by pyuff and by
the FRF substructure reader; modes (55) and nodes (15) to the format's own precision."""

from __future__ import annotations

import numpy as np
import pytest

from substruct.analysis.results import Modes
from substruct.case.frf_files import read_frf_file
from substruct.io.uff import read_uff, uff15_set, uff55_sets, uff58_sets, write_uff


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
    np.testing.assert_array_equal(H2, H)


def test_point_names_become_numbered_nodes(tmp_path):
    w, H = _frf(1)
    sets = read_uff(write_uff(tmp_path / "h.uff",
                              uff58_sets(w, H[:, :2, :1], ["rod@50", "c@mass"], ["rod@200"])))
    assert [(s["rsp_node"], s["ref_node"]) for s in sets] == [(1, 1), (2, 1)]
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
