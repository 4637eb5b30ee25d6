"""The stored fields of a transient run to ParaView: ``substruct export RESULT.h5 --format xdmf
--transient`` writes an XDMF time series that meshio's TimeSeriesReader reads back equal to the
fields of the HDF5 result (interp @ q_k) to round-off, for a solid and for a rod."""

from pathlib import Path

import meshio
import numpy as np
import pytest

from cli_helpers import assert_one_line_error, run
from substruct.io import hdf5 as results
from substruct.io.export import combined_mesh

SOLID_AND_ROD = """\
name: beam_and_rod
units: "N, m, kg, s"
substructures:
  - name: beam
    type: solid
    box: {lengths: [0.5, 0.1, 0.1], divisions: [4, 1, 1]}
    E: 2.1e11
    nu: 0.3
    rho: 7850
    fixed: [xmin]
  - name: rod
    type: rod
    length: 0.4
    EA: 2.1e7
    m: 0.785
    support: free-free
    discretization: {method: fe, elements: 6, order: 1}
connections:
  - ["beam@0.5,0.05,0.1:x", rod@0]
analysis:
  transient:
    t_end: 2.0e-3
    dt: 1.0e-4
    loads:
      - {point: "beam@0.5,0.05,0.1:z", amplitude: -1000, shape: step}
      - {point: rod@0.4, amplitude: 500, shape: half-sine, duration: 1.0e-3}
    outputs: ["beam@0.5,0.05,0.1:z", rod@0.4]
    field_every: 4
output: {pictures: false}
"""


@pytest.fixture(scope="module")
def solved(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("transient_export")
    case = tmp / "beam_and_rod.yaml"
    case.write_text(SOLID_AND_ROD)
    code = __import__("substruct.cli", fromlist=["main"]).main(
        ["run", str(case), "--out", str(tmp / "out"), "--no-pictures"])
    assert code == 0
    return tmp / "out" / "beam_and_rod.h5"


def test_xdmf_time_series_reads_back_as_the_stored_fields(solved, tmp_path, capsys):
    code, out, err = run(capsys, "export", solved, "--format", "xdmf", "--transient",
                         "--out", tmp_path)
    assert code == 0, err
    path = tmp_path / "beam_and_rod_transient.xdmf"
    assert out.split() == [str(path), str(path.with_suffix(".h5"))]
    result = results.load(solved)
    tr = result.transient
    assert np.allclose(tr.snapshot_t, 1e-4 * np.arange(0, 21, 4))  # 0, 4, ..., 20 steps
    mesh = combined_mesh(result.model)
    kinds = {d.kind.split("/")[0] for d in result.model.drawings}
    assert {"solid", "rod"} <= kinds
    with meshio.xdmf.TimeSeriesReader(path) as reader:
        points, cells = reader.read_points_cells()
        np.testing.assert_array_equal(points, mesh.points)
        assert {c.type for c in cells} >= {"hexahedron", "line"}
        assert reader.num_steps == len(tr.snapshot_t)
        peak = 0.0
        for k in range(reader.num_steps):
            t, data, _ = reader.read_data(k)
            assert t == tr.snapshot_t[k]
            expected = np.asarray(mesh.interp @ tr.snapshots[k]).reshape(-1, 3)
            np.testing.assert_allclose(data["displacement"], expected, rtol=0,
                                       atol=1e-15 * max(np.abs(expected).max(), 1e-300))
            peak = max(peak, float(np.abs(expected).max()))
    assert peak > 1e-7  # the structure moved: the fields are not all zero
    # the rod's points move along x by the rod's own coordinates
    rod = [i for i, d in enumerate(result.model.drawings) if d.name == "rod"][0]
    lo, hi = mesh.point_offsets[rod], mesh.point_offsets[rod + 1]
    assert np.abs(expected[lo:hi, 0]).max() > 0 and np.abs(expected[lo:hi, 1:]).max() == 0


def test_export_without_fields_or_in_the_wrong_format_is_one_line(solved, tmp_path, capsys):
    code, out, err = run(capsys, "export", solved, "--format", "vtu", "--transient",
                         "--out", tmp_path)
    assert_one_line_error(code, out, err, "--transient exports the stored fields as --format xdmf")
    case = tmp_path / "no_fields.yaml"
    case.write_text(SOLID_AND_ROD.replace("field_every: 4", "field_every: 0"))
    assert run(capsys, "run", case, "--out", tmp_path / "o", "--no-pictures")[0] == 0
    code, out, err = run(capsys, "export", tmp_path / "o" / "beam_and_rod.h5", "--format",
                         "xdmf", "--transient", "--out", tmp_path / "x")
    assert_one_line_error(code, out, err, "stored no fields", "field_every")
    assert not (tmp_path / "x").exists() or not any((tmp_path / "x").iterdir())
