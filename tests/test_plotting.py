"""Pictures: mode-shape grids (pyvista off-screen) and receptance plots (matplotlib Agg)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from matplotlib import image as mpimg

from substruct.viz import plotting
from substruct.viz.frf_picture import draw_frf
from substruct.viz.layout import MIN_SPRING, aligned, deformed, layout
from substruct.builder.drawing import Drawing
from substruct.analysis.results import Modes, Receptance
from substruct.run.result import ModelInfo, Result


# ----------------------------------------------------------------------------- synthetic results


def _modes(shapes: np.ndarray, omega: np.ndarray, zeta: float = 0.0) -> Modes:
    k = shapes.shape[1]
    lam = omega * (-zeta + 1j * np.sqrt(1 - zeta**2))
    return Modes(method="generalized-inverse", eigenvalues=lam, omega=omega,
                      damping_ratio=np.full(k, zeta), shapes=shapes, residual=np.zeros(k),
                      spurious=np.zeros(0, complex), spurious_reason=[])


def _model(drawings: list[Drawing], n: int) -> ModelInfo:
    return ModelInfo(dof_labels=[f"q{i}" for i in range(n)],
                     substructure_names=[d.name for d in drawings],
                     substructure_kinds=[d.kind for d in drawings], offsets=np.array([0, n]),
                     A=sp.csr_array((0, n)), b=np.zeros(0), R=sp.csr_array((0, n)),
                     constraint_labels=[], drawings=drawings)


def rod_result(n_modes: int = 3) -> Result:
    """A fixed-free rod of 2-node line cells along x, a fixed-free mass at L/2 and an absorber
    at L.  Coordinates: 40 nodal rod displacements, the mass, the absorber (mass, boundary)."""
    L, ne = 10.0, 40
    xs = np.linspace(0.0, L, ne + 1)
    n = ne + 3
    rod = Drawing(
        name="rod", kind="rod/fe-P1", points=np.column_stack([xs, 0 * xs, 0 * xs]),
        cells=[("line", np.column_stack([np.arange(ne), np.arange(1, ne + 1)]))],
        interp=sp.csr_array((np.ones(ne), (3 * np.arange(1, ne + 1), np.arange(ne))),
                            shape=(3 * (ne + 1), n)),
        glyphs={"x=5": ne // 2, "x=10": ne},
    )
    spring = Drawing(name="a", kind="fixed-free", points=np.array([[5.0, 0, 0], [5.0, -1, 0]]),
                     cells=[("line", np.array([[0, 1]]))],
                     interp=sp.csr_array(([1.0], ([0], [ne])), shape=(6, n)),
                     glyphs={"mass": 0, "boundary": 0, "ground": 1})
    absorber = Drawing(name="d", kind="free-free", points=np.array([[L, 0, 0], [L, -1, 0]]),
                       cells=[("line", np.array([[0, 1]]))],
                       interp=sp.csr_array(([1.0, 1.0], ([0, 3], [ne + 1, ne + 2])),
                                           shape=(6, n)),
                       glyphs={"boundary": 0, "mass": 1})
    shapes = np.zeros((n, n_modes), complex)
    for k in range(n_modes):
        u = np.sin((2 * k + 1) * np.pi * xs / (2 * L))
        shapes[:ne, k] = u[1:]
        shapes[ne, k] = u[ne // 2]
        shapes[ne + 1, k] = u[-1]
        shapes[ne + 2, k] = 1.6 * (-1) ** k * u[-1]
    shapes *= np.exp(0.7j)  # an arbitrary phase: the plot must rotate it away
    omega = (2 * np.arange(n_modes) + 1) * np.pi / (2 * L) * 1000.0
    return Result(case_name="rod_demo", case_yaml="name: rod_demo\n",
                  model=_model([rod, spring, absorber], n), modes=_modes(shapes, omega, 0.02),
                  variants={"no absorber": _modes(shapes[:, :2], omega[:2])})


def solid_result() -> Result:
    """A 4 x 2 x 2 hexahedral cantilever box (3 DOFs a node, clamped at x = 0), 4 modes."""
    nx, ny, nz = 4, 2, 2
    g = np.stack(np.meshgrid(np.linspace(0, 4, nx + 1), np.linspace(0, 1, ny + 1),
                             np.linspace(0, 1, nz + 1), indexing="ij"), -1).reshape(-1, 3)
    idx = np.arange(len(g)).reshape(nx + 1, ny + 1, nz + 1)
    hexa = np.array([[idx[i, j, k], idx[i + 1, j, k], idx[i + 1, j + 1, k], idx[i, j + 1, k],
                      idx[i, j, k + 1], idx[i + 1, j, k + 1], idx[i + 1, j + 1, k + 1],
                      idx[i, j + 1, k + 1]]
                     for i in range(nx) for j in range(ny) for k in range(nz)])
    n = 3 * len(g)
    x = g[:, 0] / 4
    fields = [np.column_stack([0 * x, 0 * x, x**2]),              # bending in z
              np.column_stack([0 * x, x**2, 0 * x]),              # bending in y
              np.column_stack([0 * x, -(g[:, 2] - .5) * x, (g[:, 1] - .5) * x]),  # torsion
              np.column_stack([x, 0 * x, 0 * x])]                 # axial
    shapes = np.column_stack([f.ravel() for f in fields]).astype(complex)
    block = Drawing(name="box", kind="solid/hex8", points=g, cells=[("hexahedron", hexa)],
                    interp=sp.csr_array(sp.identity(n, format="csr")), glyphs={})
    return Result(case_name="box_demo", case_yaml="", model=_model([block], n),
                  modes=_modes(shapes, np.array([10.0, 12.0, 40.0, 90.0])))


def frf_result(n_omega: int = 200, n_out: int = 2, n_in: int = 2) -> Result:
    r = rod_result()
    omega = np.linspace(100.0, 1200.0, n_omega) if n_omega > 1 else np.array([2.0])
    wn = np.array([157.08, 471.24, 785.4])
    H = np.zeros((n_omega, n_out, n_in), complex)
    for i in range(n_out):
        for j in range(n_in):
            H[:, i, j] = sum((1 + i + j) / (w**2 - omega**2 + 2j * 0.02 * w * omega) for w in wn)
    r.frf = Receptance(method="generalized-inverse", omega=omega, H=H,
                      inputs=[f"rod@{x}" for x in range(n_in)],
                      outputs=[f"out{i}" for i in range(n_out)],
                      agreement={"kkt": 1e-14}, constraint_residual=2e-16)
    return r


# ----------------------------------------------------------------------------- checks


def _image(path) -> np.ndarray:
    img = mpimg.imread(path)
    assert img.ndim == 3 and img.shape[2] in (3, 4)
    return img[..., :3].astype(float)


def _coloured(img: np.ndarray) -> np.ndarray:
    """Pixels that are clearly coloured (not white, grey or black): the deformed shapes."""
    return (img.max(axis=2) - img.min(axis=2)) > 0.25


def _panels_with_colour(img: np.ndarray, rows: int, cols: int, header: int) -> list[int]:
    body = _coloured(img[header:])
    h, w = body.shape
    return [int(body[r * h // rows:(r + 1) * h // rows, c * w // cols:(c + 1) * w // cols].sum())
            for r in range(rows) for c in range(cols)]


def test_rod_modes_png_shows_every_mode(tmp_path):
    path = plotting.plot_modes(rod_result(), tmp_path / "pics" / "modes.png", n_modes=6)
    assert path == tmp_path / "pics" / "modes.png"
    assert sorted(p.name for p in path.parent.iterdir()) == ["modes.png"]
    img = _image(path)
    assert img.shape[1] == 1600
    assert img.std() > 0.05  # not blank
    # 3 modes available -> one row of 3 panels, each holding a coloured deformed rod
    counts = _panels_with_colour(img, 1, 3, header=100)
    assert min(counts) > 500, counts


def test_rod_is_drawn_in_the_axial_view():
    lay = layout(rod_result().model.drawings)
    assert lay.axial == 0 and lay.transverse == 1
    # the short attachment springs are stretched to a readable length (schematic)
    assert np.ptp(lay.points[:, 1]) >= MIN_SPRING * lay.size * 0.999
    pos, mag = deformed(lay, rod_result().modes.shapes[:, 0])
    assert np.isclose(abs(pos[:, 1] - lay.points[:, 1]).max(),
                      plotting.SCALE_FRACTION * lay.size)
    assert np.isclose(mag.max(), 1.0) and np.allclose(pos[:, [0, 2]], lay.points[:, [0, 2]])


def test_phase_alignment_recovers_a_real_shape():
    u = np.array([[1.0, 0, 0], [-2.0, 0, 0], [0.5, 0, 0]])
    rotated = u * np.exp(2.1j)
    # rotated back to real, with the largest entry (-2) made positive
    np.testing.assert_allclose(aligned(rotated), -u, atol=1e-12)


def test_solid_modes_png(tmp_path):
    result = solid_result()
    lay = layout(result.model.drawings)
    assert lay.axial is None  # solids are warped by the displacement vector
    path = plotting.plot_modes(result, tmp_path / "box.png", n_modes=4)
    img = _image(path)
    assert img.std() > 0.05
    counts = _panels_with_colour(img, 2, 2, header=100)
    assert min(counts) > 500, counts


def test_variant_and_errors(tmp_path):
    r = rod_result()
    path = plotting.plot_modes(r, tmp_path / "v.png", variant="no absorber")
    assert _image(path).std() > 0.05
    with pytest.raises(ValueError, match="no variant 'nope'.*'no absorber'"):
        plotting.plot_modes(r, tmp_path / "x.png", variant="nope")
    with pytest.raises(ValueError, match="n_modes must be >= 1"):
        plotting.plot_modes(r, tmp_path / "x.png", n_modes=0)
    r.modes = None
    with pytest.raises(ValueError, match="holds no modes"):
        plotting.plot_modes(r, tmp_path / "x.png")
    with pytest.raises(ValueError, match="holds no FRF"):
        plotting.plot_frf(r, tmp_path / "x.png")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["v.png"]


def test_failed_png_write_leaves_nothing(tmp_path, monkeypatch):
    def boom(*args, **kwargs):
        raise OSError("disk full")
    monkeypatch.setattr(mpimg, "imsave", boom)
    with pytest.raises(OSError, match="disk full"):
        plotting.plot_modes(rod_result(n_modes=1), tmp_path / "m.png", n_modes=1)
    assert list(tmp_path.iterdir()) == []


def test_frf_png(tmp_path):
    path = plotting.plot_frf(frf_result(), tmp_path / "frf.png")
    img = _image(path)
    assert img.std() > 0.05 and _coloured(img).sum() > 2000


def test_frf_many_pairs_are_limited(tmp_path):
    result = frf_result(n_omega=50, n_out=4, n_in=4)  # 16 pairs
    fig = draw_frf(result, max_curves=9)
    ax_mag, ax_phase = fig.axes[:2]
    curves = [line for line in ax_mag.get_lines() if "\u2190" in line.get_label()]
    # the first nine pairs, outputs varying slowest: out0 <- rod@0 .. rod@3, out1 <- ..., out2
    assert [line.get_label() for line in curves] == \
        [f"out{i} \u2190 rod@{j}" for i in range(4) for j in range(4)][:9]
    marks = len(ax_mag.get_lines()) - len(curves)  # natural frequencies inside the range
    assert marks == 3
    assert len(ax_phase.get_lines()) == 9 + marks
    assert ax_mag.get_legend().get_title().get_text() == "output \u2190 input (+7 pairs not shown)"
    np.testing.assert_array_equal(curves[5].get_ydata(), abs(result.frf.H[:, 1, 1]))
    path = plotting.plot_frf(result, tmp_path / "frf.png", max_curves=9)
    assert _image(path).std() > 0.05


def test_frf_single_frequency_is_a_matrix(tmp_path):
    path = plotting.plot_frf(frf_result(n_omega=1, n_out=3, n_in=3), tmp_path / "frf1.png")
    img = _image(path)
    assert img.std() > 0.05 and _coloured(img).sum() > 5000
    assert sorted(p.name for p in tmp_path.iterdir()) == ["frf1.png"]
