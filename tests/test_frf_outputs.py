"""Outputs of the receptances: the quantity (receptance, mobility, accelerance), grids in Hz,
the UFF export through the command line read back by pyuff, and ``substruct compare``."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from substruct import cli
from substruct.analysis.frf.quantity import as_quantity, quantity_units
from substruct.case.loader import load_case
from substruct.io import hdf5
from substruct.io.uff import modes_from_2414, read_uff
from substruct.run.runner import build_model, run_case

CASE = Path(__file__).resolve().parents[1] / "cases" / "tapered_rod.yaml"


def _frf(*overrides):
    case = load_case(CASE, list(overrides))
    return run_case(case, model=build_model(case))


@pytest.fixture(scope="module")
def receptance():
    return _frf("analysis.frf.omega={start: 1, stop: 200, num: 40}").frf


def test_mobility_and_accelerance(receptance):
    w = receptance.omega
    for quantity, factor in (("mobility", 1j * w), ("accelerance", -w**2)):
        frf = _frf("analysis.frf.omega={start: 1, stop: 200, num: 40}",
                   f"analysis.frf.quantity={quantity}").frf
        assert frf.quantity == quantity
        np.testing.assert_allclose(frf.H, receptance.H * factor[:, None, None], rtol=1e-12)
    with pytest.raises(ValueError, match="already mobility"):
        as_quantity(as_quantity(receptance, "mobility"), "accelerance")
    assert quantity_units("mobility", "N, mm, t, s") == "mm/(N s)"


def test_grid_in_hz(receptance):
    f = receptance.omega / (2 * np.pi)
    frf = _frf(f"analysis.frf.omega={list(map(float, f))}", "analysis.frf.units=Hz").frf
    np.testing.assert_allclose(frf.omega, receptance.omega, rtol=1e-15)
    np.testing.assert_allclose(frf.H, receptance.H, rtol=1e-12)


def test_quantity_kept_in_the_results_file(tmp_path):
    result = _frf("analysis.frf.quantity=accelerance", "output.pictures=false")
    back = hdf5.load(hdf5.save(result, tmp_path / "r.h5"))
    assert back.frf.quantity == "accelerance"


@pytest.fixture(scope="module")
def result_file(tmp_path_factory):
    out = tmp_path_factory.mktemp("run")
    assert cli.main(["run", str(CASE), "--out", str(out), "--quiet",
                     "--set", "analysis.frf.quantity=mobility",
                     "--set", "output.pictures=false"]) == 0
    return out / "tapered_rod.h5"


def test_export_uff_reads_back_exactly(result_file, tmp_path, capsys):
    assert cli.main(["export", str(result_file), "--format", "uff", "--out",
                     str(tmp_path)]) == 0
    result = hdf5.load(result_file)
    sets = read_uff(tmp_path / "tapered_rod.uff")
    types = [s["type"] for s in sets]
    assert types == [15] + [55] * len(result.modes) + [58] * 3 + [2414] * len(result.modes)
    lam, shapes_2414 = modes_from_2414(sets)  # the exact copy of the modes
    np.testing.assert_array_equal(lam, result.modes.eigenvalues)
    np.testing.assert_array_equal(shapes_2414, result.modes.shapes)
    frfs = [s for s in sets if s["type"] == 58]
    for i, s in enumerate(frfs):
        np.testing.assert_array_equal(s["data"], result.frf.H[:, i, 0])
        np.testing.assert_array_equal(s["x"], result.frf.omega / (2 * np.pi))
        assert s["ordinate_spec_data_type"] == 11  # velocity: mobility
    shapes = [s for s in sets if s["type"] == 55]
    np.testing.assert_allclose(shapes[0]["r1"], result.modes.shapes[:, 0], rtol=1e-5,
                               atol=1e-5 * np.abs(result.modes.shapes[:, 0]).max())
    # a second export refuses to overwrite, one line, exit 2
    assert cli.main(["export", str(result_file), "--format", "uff", "--out",
                     str(tmp_path)]) == 2
    assert "exists; use --force" in capsys.readouterr().err


def test_compare_itself_and_a_variant(result_file, tmp_path, capsys):
    image = tmp_path / "mac.png"
    assert cli.main(["compare", str(result_file), str(result_file), "--json"]) == 0
    same = json.loads(capsys.readouterr().out)
    mac = np.array(same["mac"])
    np.testing.assert_allclose(np.diag(mac), 1.0, rtol=1e-12)
    assert np.all(mac[~np.eye(len(mac), dtype=bool)] < 0.999)
    assert all(r["difference"] == 0 for r in same["rows"])
    assert cli.main(["compare", str(result_file), str(result_file), "--variant-b",
                     "without_eq52", "--image", str(image), "--json"]) == 0
    other = json.loads(capsys.readouterr().out)
    result = hdf5.load(result_file)
    rows = other["rows"]
    assert [r["freq_a_hz"] for r in rows] == pytest.approx(list(result.modes.freq_hz))
    paired = [result.variants["without_eq52"].freq_hz[r["mode_b"] - 1] for r in rows]
    assert [r["freq_b_hz"] for r in rows] == pytest.approx(paired)
    assert image.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert cli.main(["compare", str(result_file), str(result_file), "--variant-a",
                     "nope"]) == 2
    assert "has no variant 'nope'" in capsys.readouterr().err
