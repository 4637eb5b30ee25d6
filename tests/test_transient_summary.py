"""What ``run`` and ``info`` print about a transient response: the form, integrator, steps,
the drift figure, the checks' agreement and the peaks at the output points (against the
histories themselves), in the table and in ``--json``."""

import json

import numpy as np

from cli_helpers import run
from substruct.cli.transient_summary import peaks
from substruct.io import hdf5 as results
from test_transient_io import _with_transient


def test_peaks_are_the_signed_extremes_of_the_histories():
    t = np.array([0.0, 1.0, 2.0, 3.0])
    v = np.array([[0.0, 1.0], [-5.0, 2.0], [4.0, 3.0], [1.0, -2.5]])
    assert peaks(v, t) == [(-5.0, 1.0), (3.0, 2.0)]


def test_info_lists_the_transient_group(tmp_path, capsys):
    r = _with_transient()
    r.attrs["units"] = "N, mm, t, s"
    tr = r.transient
    path = results.save(r, tmp_path / "r.h5")
    code, out, err = run(capsys, "info", path)
    assert code == 0, err
    assert "transient (generalized-alpha, rho_inf 0.8, generalized-inverse): 40 steps" in out
    assert f"constraint drift max|A q - b| / max|q|: {tr.drift:.1e}" in out
    assert f"null-space {tr.agreement['null-space']:.1e}" in out
    assert "peaks at the output points (N, mm, t, s)" in out
    k = int(np.argmax(np.abs(tr.acceleration[:, 1])))
    assert f"{tr.acceleration[k, 1]:.4g} ({tr.t[k]:.4g})" in out.split("absorber")[1]
    code, out, err = run(capsys, "info", path, "--json")
    assert code == 0, err
    data = json.loads(out)["transient"]
    assert data["steps"] == 40 and data["outputs"] == ["m1", "absorber"]
    assert data["drift"] == tr.drift and data["agreement"] == tr.agreement
    assert data["peaks"]["displacement"]["m1"]["value"] == float(
        tr.displacement[np.argmax(np.abs(tr.displacement[:, 0])), 0])
    lam = tr.constraint_forces[:, 1]
    assert data["peaks"]["constraint_forces"]["tie 2-3"]["value"] == float(
        lam[np.argmax(np.abs(lam))])
