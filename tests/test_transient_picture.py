"""The transient picture: drawn by ``substruct run`` beside the result (listed in its set),
its curves the histories of the result, its axes labelled in the case's units."""

from pathlib import Path

import numpy as np
import pytest

from cli_helpers import run
from substruct.io import hdf5 as results
from substruct.viz.transient_picture import transient_figure, unit_names

CASES = Path(__file__).resolve().parents[1] / "cases"


def test_unit_names_of_a_case():
    assert unit_names("N, mm, t, s") == {"force": "N", "length": "mm", "time": "s"}
    assert unit_names("")["length"] == "length"


def test_run_draws_the_histories_in_the_case_units(tmp_path, capsys):
    out = tmp_path / "out"
    code, text, err = run(capsys, "run", CASES / "tapered_rod_impact.yaml", "--out", out)
    assert code == 0, err
    png = out / "tapered_rod_impact_transient.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert str(png) in text and "transient (newmark, generalized-inverse): 5000 steps" in text
    r = results.load(out / "tapered_rod_impact.h5")
    assert results.listed_pictures(out / "tapered_rod_impact.h5") == [png.name]
    fig = transient_figure(r)
    axes = fig.axes
    assert [a.get_ylabel() for a in axes] == [
        "displacement [mm]", "velocity [mm/s]", "acceleration [mm/s²]", "constraint force λ [N]"]
    assert axes[-1].get_xlabel() == "time [s]"
    tr = r.transient
    for ax, values in zip(axes, (tr.displacement, tr.velocity, tr.acceleration,
                                 tr.constraint_forces)):
        lines = ax.get_lines()
        assert len(lines) == values.shape[1]
        for j, line in enumerate(lines):
            assert np.array_equal(line.get_xdata(), tr.t)
            assert np.array_equal(line.get_ydata(), values[:, j])


def test_a_result_without_transient_has_no_picture():
    from test_export import make_result
    with pytest.raises(ValueError, match="holds no transient response"):
        transient_figure(make_result())
