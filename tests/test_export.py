"""Mode shapes to VTU / XDMF: the files open with meshio and carry ``interp @ shape``."""

from __future__ import annotations

import meshio
import numpy as np
import pytest
import scipy.sparse as sp

from substruct.io import export
from substruct.builder.drawing import Drawing
from substruct.analysis.results import Modes
from substruct.run.result import ModelInfo, Result


def make_result(n_modes: int = 3, seed: int = 0) -> Result:
    """A rod of line cells along x (axial DOFs), a two-tetra solid and a vertex; complex modes."""
    rng = np.random.default_rng(seed)
    n_rod, n = 6, 6 + 15
    xs = np.linspace(0.0, 5.0, n_rod + 1)
    rod = Drawing(
        name="rod", kind="rod/fe-P1", points=np.column_stack([xs, 0 * xs, 0 * xs]),
        cells=[("line", np.column_stack([np.arange(n_rod), np.arange(1, n_rod + 1)]))],
        interp=sp.csr_array((np.ones(n_rod), (3 * np.arange(1, n_rod + 1), np.arange(n_rod))),
                            shape=(3 * (n_rod + 1), n)),
        glyphs={"x=5": n_rod},
    )
    pts = np.array([[0, 0, 1.0], [1, 0, 1], [0, 1, 1], [0, 0, 2], [1, 1, 2]])
    solid = Drawing(
        name="block", kind="solid/tet4", points=pts,
        cells=[("tetra", np.array([[0, 1, 2, 3], [1, 2, 3, 4]])), ("vertex", np.array([[4]]))],
        interp=sp.csr_array(sp.hstack([sp.csr_array((15, n_rod)), sp.identity(15)])),
        glyphs={},
    )
    shapes = rng.standard_normal((n, n_modes)) + 1j * rng.standard_normal((n, n_modes))
    omega = np.arange(1, n_modes + 1) * 10.0
    modes = Modes(method="generalized-inverse", eigenvalues=1j * omega, omega=omega,
                       damping_ratio=np.full(n_modes, 0.01), shapes=shapes,
                       residual=np.zeros(n_modes), spurious=np.zeros(0, complex),
                       spurious_reason=[])
    model = ModelInfo(dof_labels=[f"q{i}" for i in range(n)], substructure_names=["rod", "block"],
                      substructure_kinds=["rod/fe-P1", "solid/tet4"],
                      offsets=np.array([0, n_rod, n]), A=sp.csr_array((0, n)), b=np.zeros(0),
                      R=sp.csr_array((0, n)), constraint_labels=[], drawings=[rod, solid])
    variant = Modes(**{**modes.__dict__, "shapes": shapes[:, :1] * 2, "omega": omega[:1],
                            "eigenvalues": 1j * omega[:1], "damping_ratio": np.zeros(1),
                            "residual": np.zeros(1)})
    return Result(case_name="demo case", case_yaml="", model=model, modes=modes,
                  variants={"half": variant})


def expected(result: Result, k: int, modes=None) -> np.ndarray:
    """``interp @ shape`` of mode ``k`` (1-based) over all drawings, as ``(N, 3)``."""
    mr = modes or result.modes
    return np.vstack([np.asarray(d.interp @ mr.shapes[:, k - 1]).reshape(-1, 3)
                      for d in result.model.drawings])


def test_vtu_carries_every_mode(tmp_path):
    r = make_result()
    paths = export.export_modes(r, tmp_path / "out", "vtu")
    assert paths == [tmp_path / "out" / "demo_case_modes.vtu"]
    mesh = meshio.read(paths[0])
    np.testing.assert_allclose(mesh.points, np.vstack([d.points for d in r.model.drawings]))
    for k in (1, 2, 3):
        u = expected(r, k)
        np.testing.assert_allclose(mesh.point_data[f"mode_{k}_real"], u.real, rtol=0, atol=1e-14)
        np.testing.assert_allclose(mesh.point_data[f"mode_{k}_imag"], u.imag, rtol=0, atol=1e-14)
    np.testing.assert_array_equal(mesh.field_data["mode_numbers"], [1, 2, 3])
    np.testing.assert_allclose(mesh.field_data["omega"], [10.0, 20.0, 30.0])
    np.testing.assert_allclose(mesh.field_data["freq_hz"], np.array([10.0, 20, 30]) / 2 / np.pi)
    types = [c.type for c in mesh.cells]
    assert types == ["line", "tetra", "vertex"]
    # tetra connectivity is offset by the rod's 7 points
    np.testing.assert_array_equal(mesh.cells[1].data, [[7, 8, 9, 10], [8, 9, 10, 11]])
    np.testing.assert_array_equal(np.concatenate(mesh.cell_data["drawing"]),
                                  [0] * 6 + [1, 1, 1])
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["demo_case_modes.vtu"]


def test_vtu_selected_modes_and_per_mode_files(tmp_path):
    r = make_result()
    paths = export.export_modes(r, tmp_path / "m.vtu", "vtu", modes=[3, 1], per_mode=True)
    assert [p.name for p in paths] == ["m.vtu", "m_mode_3.vtu", "m_mode_1.vtu"]
    mesh = meshio.read(paths[0])
    assert set(mesh.point_data) == {"mode_3_real", "mode_3_imag", "mode_1_real", "mode_1_imag"}
    np.testing.assert_allclose(mesh.field_data["omega"], [30.0, 10.0])
    one = meshio.read(paths[1])
    np.testing.assert_allclose(one.point_data["shape_real"], expected(r, 3).real, atol=1e-14)
    np.testing.assert_allclose(one.point_data["shape_imag"], expected(r, 3).imag, atol=1e-14)


def test_export_of_a_reloaded_result(tmp_path):
    from substruct.io import hdf5 as results

    r = make_result()
    back = results.load(results.save(r, tmp_path / "r.h5"))
    (path,) = export.export_modes(back, tmp_path / "vtu", "vtu", modes="2")
    np.testing.assert_allclose(meshio.read(path).point_data["mode_2_imag"], expected(r, 2).imag,
                               atol=1e-14)


def test_variant_modes(tmp_path):
    r = make_result()
    (path,) = export.export_modes(r, tmp_path, "vtu", variant="half")
    mesh = meshio.read(path)
    np.testing.assert_allclose(mesh.point_data["mode_1_real"],
                               expected(r, 1, r.variants["half"]).real, atol=1e-14)
    with pytest.raises(ValueError, match="no variant 'x'"):
        export.export_modes(r, tmp_path, "vtu", variant="x")


def test_xdmf_time_series_one_step_per_mode(tmp_path, monkeypatch):
    r = make_result()
    monkeypatch.chdir(tmp_path)  # meshio alone would put the .h5 in the working directory
    out = tmp_path / "x"
    paths = export.export_modes(r, out, "xdmf", modes="2-3")
    assert paths == [out / "demo_case_modes.xdmf", out / "demo_case_modes.h5"]
    assert sorted(p.name for p in out.iterdir()) == ["demo_case_modes.h5",
                                                     "demo_case_modes.xdmf"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x"]
    with meshio.xdmf.TimeSeriesReader(paths[0]) as reader:
        points, cells = reader.read_points_cells()
        assert [c.type for c in cells] == ["line", "tetra", "vertex"]
        assert reader.num_steps == 2
        for step, k in enumerate((2, 3)):
            t, point_data, _ = reader.read_data(step)
            assert t == k
            np.testing.assert_allclose(point_data["shape_real"], expected(r, k).real, atol=1e-14)
            np.testing.assert_allclose(point_data["shape_imag"], expected(r, k).imag, atol=1e-14)


def test_xdmf_single_cell_type(tmp_path):
    r = make_result()
    r.model.drawings = r.model.drawings[:1]
    paths = export.export_modes(r, tmp_path, "xdmf", modes=[1])
    with meshio.xdmf.TimeSeriesReader(paths[0]) as reader:
        _, cells = reader.read_points_cells()
        assert [c.type for c in cells] == ["line"]


@pytest.mark.parametrize("bad, message", [
    ([0], "no mode 0; the result has 3 modes"),
    ([1, 4], "no mode 4; the result has 3 modes"),
    ([1.5], "mode numbers are integers, got 1.5"),
    ([True], "mode numbers are integers, got True"),
    ("1-x", "expected numbers and ranges"),
    ("3-1", "runs backwards"),
    ([], "no mode selected"),
])
def test_bad_mode_numbers_are_named(tmp_path, bad, message):
    with pytest.raises(ValueError, match=message):
        export.export_modes(make_result(), tmp_path, "vtu", modes=bad)
    assert list(tmp_path.iterdir()) == []


def test_parse_modes():
    assert export.parse_modes("1-3,5, 7 - 8") == [1, 2, 3, 5, 7, 8]
    assert export.select_modes(make_result().modes, "3,1,3") == [3, 1]


def test_other_bad_input(tmp_path):
    r = make_result()
    with pytest.raises(ValueError, match="format must be one of vtu, xdmf"):
        export.export_modes(r, tmp_path, "vtk")
    with pytest.raises(ValueError, match=r"does not end in \.xdmf"):
        export.export_modes(r, tmp_path / "a.vtu", "xdmf")
    r.modes = None
    with pytest.raises(ValueError, match="holds no modes"):
        export.export_modes(r, tmp_path, "vtu")
    r = make_result()
    r.model.drawings = []
    with pytest.raises(ValueError, match="no drawings"):
        export.export_modes(r, tmp_path, "vtu")
    assert list(tmp_path.iterdir()) == []


def test_failed_writes_leave_nothing(tmp_path, monkeypatch):
    def boom(*args, **kwargs):
        raise OSError("disk full")
    monkeypatch.setattr(meshio, "write", boom)
    with pytest.raises(OSError, match="disk full"):
        export.export_modes(make_result(), tmp_path, "vtu")
    monkeypatch.setattr(meshio.xdmf.TimeSeriesWriter, "write_data", boom)
    with pytest.raises(OSError, match="disk full"):
        export.export_modes(make_result(), tmp_path, "xdmf")
    assert list(tmp_path.iterdir()) == []
