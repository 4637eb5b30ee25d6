"""The Python API a notebook uses (issue 14): the public names listed by dir(substruct),
load_case from a path, a dict or YAML text, receptances by point label, figures returned."""

from pathlib import Path

import numpy as np
import pytest
import yaml

import substruct

CASES = Path(__file__).resolve().parent.parent / "cases"
THREE = CASES / "three_dof_frf.yaml"


def test_dir_lists_the_public_names_and_each_resolves():
    names = [n for n in dir(substruct) if not n.startswith("_")]
    for name in ("load_case", "run_case", "build_model", "load_result", "frf_figure",
                 "modes_figure", "plot_frf", "plot_modes", "Result", "CaseError"):
        assert name in names
    for name in names:
        assert getattr(substruct, name) is not None
    from substruct.io import hdf5
    assert substruct.load_result is hdf5.load
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        substruct.nope


def test_load_case_takes_a_path_a_dict_or_yaml_text():
    from_path = substruct.run_case(substruct.load_case(THREE))
    data = yaml.safe_load(THREE.read_text())
    from_dict = substruct.load_case(data)
    from_text = substruct.load_case(THREE.read_text(), ["analysis.modes.count=1"])
    assert from_dict.source == "<dict>" and from_text.source == "<string>"
    assert from_text.analysis.modes.count == 1
    np.testing.assert_allclose(substruct.run_case(from_dict).frf.H, from_path.frf.H, rtol=1e-12)
    data["substructures"][0]["M"] = "not a matrix"
    with pytest.raises(substruct.CaseError, match=r"^<dict>: substructures\.P\.M"):
        substruct.load_case(data)


def test_receptance_by_point_label():
    result = substruct.run_case(substruct.load_case(THREE))
    # eq (40) of the paper: H_21 = H_12 = 0.0082 - 0.0098i at 2 rad/s
    h = result.frf.at("P@q1", "P@q2")
    assert h.shape == (1,)
    assert abs(h[0] - (0.0082 - 0.0098j)) < 6e-5
    np.testing.assert_array_equal(result.frf.at("P@q3", "P@q2"), result.frf.H[:, 1, 2])
    with pytest.raises(KeyError, match=r"'P@q9' is not an input .* \(inputs: P@q1, P@q2, P@q3\)"):
        result.frf.at("P@q9", "P@q1")
    rod = substruct.run_case(substruct.load_case(CASES / "tapered_rod.yaml"))
    curve = rod.frf.at("rod@200", "rod@50")          # the example
    assert curve.shape == rod.frf.omega.shape and np.all(np.isfinite(curve))


def test_figures_are_returned_and_written(tmp_path):
    from matplotlib.figure import Figure
    from matplotlib.image import imread

    result = substruct.run_case(substruct.load_case(CASES / "tapered_rod.yaml"))
    fig = substruct.frf_figure(result, tmp_path / "frf.png")
    assert isinstance(fig, Figure) and len(fig.axes) >= 2
    assert imread(tmp_path / "frf.png").shape[:2] == tuple(
        int(v) for v in fig.get_size_inches()[::-1] * fig.dpi)
    fig = substruct.modes_figure(result, tmp_path / "modes.png", n_modes=2)
    shown = fig.axes[0].images[0].get_array()
    written = imread(tmp_path / "modes.png")
    assert shown.shape[:2] == written.shape[:2]
    np.testing.assert_allclose(np.asarray(shown)[..., :3] / 255, written[..., :3], atol=1 / 255)
    assert substruct.frf_figure(result).axes  # no path: nothing written
    assert sorted(p.name for p in tmp_path.iterdir()) == ["frf.png", "modes.png"]
