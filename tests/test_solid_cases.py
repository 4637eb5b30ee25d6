"""Solids from case files: the two solid cases through the command line (HDF5, pictures,
VTU/XDMF), tied halves against the monolithic mesh, dense against sparse coupled modes,
Craig-Bampton against the unreduced model, and bad solid input as one line with exit code 2."""

import json
from pathlib import Path

import meshio
import numpy as np
import pytest

from substruct.case.loader import parse_case
from substruct.run.runner import build_model, run_case
from cli_helpers import run

ROOT = Path(__file__).resolve().parent.parent
CASES = ROOT / "cases"
MESHES = ROOT / "meshes"
BOX_BEAM = CASES / "box_beam_tmd.yaml"
PLATE = CASES / "plate_2d.yaml"

#: Regression values, not an independent reference: the two lowest y-bending frequencies
#: (rad/s) of the box beam of cases/box_beam_tmd.yaml (meshes/box_beam_left.msh and
#: box_beam_right.msh tied, each reduced by Craig-Bampton), as substruct computed them when the
#: solid cases were added.  The absorbers act in z, so these modes are those of the bare beam.
#: A change beyond rtol 2e-4 means the meshes, the elements or the reduction changed.
REGRESSION_Y_BENDING = (611.50, 3547.2)

#: Regression values as above: the three lowest frequencies (rad/s) of the box beam with its
#: absorbers, unreduced and undamped, on the matching meshes; tied to a finer right half by
#: interpolation (non-matching) it must stay within 1e-3 of them.
REGRESSION_MATCHING = (530.554, 611.503, 654.919)

#: the box beam unreduced and undamped: 4900 coordinates, solved by the sparse path
FULL_UNDAMPED = ["substructures.left.reduce=null", "substructures.right.reduce=null",
                 "substructures.tmd1.damping=0", "substructures.tmd2.damping=0",
                 "analysis.frf=null", "output.pictures=false"]


def omegas(capsys, *args):
    code, out, err = run(capsys, "run", *args, "--json", "--quiet")
    assert code == 0, err
    return json.loads(out)


def assert_picture(path: Path) -> None:
    import matplotlib.image as mpimg
    img = mpimg.imread(path)[..., :3]
    assert img.shape[0] > 300 and img.shape[1] > 300
    # not blank: many distinct colours, and more than a thin frame differs from the background
    assert len(np.unique((img * 255).astype(int).reshape(-1, 3), axis=0)) > 50
    background = np.median(img.reshape(-1, 3), axis=0)
    assert np.mean(np.abs(img - background).max(axis=2) > 0.1) > 0.02


# ------------------------------------------------------------------- the two cases


@pytest.mark.slow  # the two longest runs of the suite (15 s and 7 s on one core)
@pytest.mark.parametrize("path, n_modes", [(BOX_BEAM, 8), (PLATE, 6)],
                         ids=["box_beam_tmd", "plate_2d"])
def test_solid_case_runs_writes_pictures_and_exports(path, n_modes, tmp_path, capsys):
    from substruct.io import hdf5 as results
    code, out, err = run(capsys, "run", path, "--out", tmp_path)
    assert code == 0, err
    name = path.stem
    assert f"{n_modes} physical mode(s), generalized-inverse:" in out
    h5 = tmp_path / f"{name}.h5"
    back = results.load(h5)
    assert len(back.modes.omega) == n_modes
    assert back.modes.residual.max() < 1e-10
    assert max(back.modes.agreement.values()) < 1e-8
    assert back.frf.constraint_residual < 1e-10 and back.frf.agreement["kkt"] < 1e-8
    assert [d.kind for d in back.model.drawings][0].startswith(
        "craig-bampton" if name == "box_beam_tmd" else "modal")
    if name == "box_beam_tmd":
        assert_tuned(back.modes.omega, back.modes.damping_ratio)
    for png in (f"{name}_modes.png", f"{name}_frf.png"):
        assert_picture(tmp_path / png)
    for fmt in ("vtu", "xdmf"):
        code, out, err = run(capsys, "export", h5, "--format", fmt, "--modes", "1-3",
                             "--out", tmp_path / fmt)
        assert code == 0, err
    mesh = meshio.read(tmp_path / "vtu" / f"{name}_modes.vtu")
    cell = "hexahedron" if name == "box_beam_tmd" else "triangle"
    assert cell in [c.type for c in mesh.cells]
    assert np.abs(mesh.point_data["mode_1_real"]).max() > 0
    with meshio.xdmf.TimeSeriesReader(tmp_path / "xdmf" / f"{name}_modes.xdmf") as reader:
        points, cells = reader.read_points_cells()
        assert reader.num_steps == 3 and len(points) == len(mesh.points)
        assert np.abs(reader.read_data(0)[1]["shape_real"]).max() > 0


def assert_tuned(w, zeta):
    """The y-bending modes of the box beam (the absorbers move in z) are those of the bare
    beam, undamped; each z-bending mode is split in two by its absorber, about the y one."""
    undamped = w[zeta < 1e-9]
    np.testing.assert_allclose(undamped[:2], REGRESSION_Y_BENDING, rtol=2e-4)
    # each z-bending mode is split in two by its absorber, about the y one
    assert w[0] < undamped[0] < w[2] and w[3] < undamped[1] < w[5]
    assert np.all(zeta[[0, 2, 3, 5]] > 0.04)


# ------------------------------------------------------- tied halves = monolithic mesh


def _merged_mesh(path: Path) -> None:
    """The two halves of the box beam as one mesh (interface nodes merged)."""
    halves = [meshio.read(MESHES / f"box_beam_{side}.msh", file_format="gmsh")
              for side in ("left", "right")]
    points, cells, offset = [], [], 0
    for m in halves:
        hexa = np.vstack([c.data for c in m.cells if c.type == "hexahedron"])
        points.append(m.points)
        cells.append(hexa + offset)
        offset += len(m.points)
    points = np.vstack(points)
    key = np.round(points / 1e-9).astype(np.int64)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    merged = meshio.Mesh(points[first], [("hexahedron", inverse.ravel()[np.vstack(cells)])])
    meshio.write(path, merged)


MONOLITHIC = """\
name: monolithic
substructures:
  - name: beam
    type: solid
    mesh: beam.vtu
    E: 2.1e11
    nu: 0.3
    rho: 7850
    fixed: [{box: [[0, 0, 0], [0, 0.1, 0.1]]}]
  - {name: tmd1, type: free-free, mass: 0.6, stiffness: 2.035e5}
  - {name: tmd2, type: free-free, mass: 0.6, stiffness: 6.84e6}
connections:
  - ["beam@1,0.05,0.1:z", tmd1]
  - ["beam@1,0.05,0:z", tmd2]
constraints:
  - name: no_twist
    terms:
      beam@1,0,0.1:z: 1
      beam@1,0.1,0.1:z: -1
analysis:
  modes: {count: 8, check: [null-space]}
output: {pictures: false}
"""


def test_tied_halves_equal_the_monolithic_mesh(tmp_path, capsys):
    tied = omegas(capsys, BOX_BEAM, "--out", tmp_path / "tied",
                  *[a for s in FULL_UNDAMPED for a in ("--set", s)])
    assert tied["model"]["n_dof"] == 4900
    assert tied["modes"]["method"] == "null-space/sparse"  # the production path
    assert tied["modes"]["agreement"]["kkt-residual"] < 1e-9
    assert tied["modes"]["agreement"]["generalized-inverse-residual"] < 1e-9
    _merged_mesh(tmp_path / "beam.vtu")
    (tmp_path / "monolithic.yaml").write_text(MONOLITHIC)
    mono = omegas(capsys, tmp_path / "monolithic.yaml", "--out", tmp_path / "mono")
    assert mono["model"]["n_dof"] == 4804  # the 96 interface coordinates once
    assert mono["modes"]["method"] == "null-space/sparse"
    a, b = np.array(tied["modes"]["omega"]), np.array(mono["modes"]["omega"])
    assert len(a) == len(b) == 8
    np.testing.assert_allclose(a, b, rtol=1e-6)
    assert np.max(np.abs(a - b) / b) < 1e-8  # in fact to round-off


def test_craig_bampton_box_beam_is_close_to_the_unreduced_model(tmp_path, capsys):
    full = omegas(capsys, BOX_BEAM, "--out", tmp_path / "full",
                  *[a for s in FULL_UNDAMPED for a in ("--set", s)])
    cb = omegas(capsys, BOX_BEAM, "--out", tmp_path / "cb",
                *[a for s in FULL_UNDAMPED[2:] for a in ("--set", s)])
    assert cb["modes"]["method"] == "generalized-inverse"  # 238 + 4 coordinates: dense
    a, b = np.array(cb["modes"]["omega"]), np.array(full["modes"]["omega"])
    err = (a - b) / b  # 20 fixed-interface modes per half: 4e-7 on the first bending modes
    assert np.all(err > -1e-9) and err[:3].max() < 2e-6 and err.max() < 5e-4


# ----------------------------------------------------------- small solid cases (boxes)


def small_case(left_reduce="null", right_reduce="null", solver="auto", damping=0,
               check="[null-space, kkt]", count=6) -> str:
    return f"""\
name: halves
substructures:
  - name: left
    type: solid
    box: {{lengths: [0.5, 0.1, 0.1], divisions: [4, 2, 2]}}
    E: 2.1e11
    nu: 0.3
    rho: 7850
    fixed: [xmin]
    reduce: {left_reduce}
  - name: right
    type: solid
    box: {{lengths: [0.5, 0.1, 0.1], divisions: [4, 2, 2], origin: [0.5, 0, 0]}}
    E: 2.1e11
    nu: 0.3
    rho: 7850
    reduce: {right_reduce}
  - {{name: tmd, type: free-free, mass: 0.5, stiffness: 2.0e5, damping: {damping}}}
interfaces:
  - {{name: joint, between: [left, right], nodes: {{box: [[0.5, 0, 0], [0.5, 0.1, 0.1]]}}}}
connections:
  - ["right@1,0.05,0.1:z", tmd]
constraints:
  - name: mpc
    terms:
      right@1,0,0.1:z: 1
      right@0.75,0.1,0.1:z: -1
analysis:
  modes: {{count: {count}, solver: {solver}, check: {check}}}
output: {{pictures: false}}
"""


def modes_of(text: str, *overrides: str):
    case = parse_case(text, "small.yaml", ROOT, overrides)
    return run_case(case).modes


def test_dense_and_sparse_solvers_agree_on_a_small_solid_case():
    dense = modes_of(small_case(solver="dense"))
    sparse = modes_of(small_case(solver="sparse"))
    assert dense.method == "generalized-inverse" and sparse.method == "null-space/sparse"
    assert dense.shapes.shape == sparse.shapes.shape and sparse.shapes.dtype == complex
    np.testing.assert_allclose(sparse.omega, dense.omega, rtol=1e-9)
    assert max(dense.agreement.values()) < 1e-8 and max(sparse.agreement.values()) < 1e-8
    assert sparse.residual.max() < 1e-12 and dense.residual.max() < 1e-12
    assert np.all(sparse.damping_ratio == 0) and len(sparse.spurious) == 0
    # the same shapes up to sign, u^T M u = 1 both
    for j in range(len(dense.omega)):
        u, v = dense.shapes[:, j].real, sparse.shapes[:, j].real
        assert min(np.abs(u - v).max(), np.abs(u + v).max()) < 1e-6 * np.abs(u).max()


def test_auto_solver_is_dense_when_small_and_sparse_solves_damped_models():
    assert modes_of(small_case(check="[]")).method == "generalized-inverse"
    # damped models are no longer refused by the sparse path (tests/test_sparse_damped.py)
    damped = modes_of(small_case(solver="sparse", damping=10))
    assert damped.method == "null-space/sparse" and damped.damping_ratio.max() > 1e-3
    assert set(damped.agreement) == {"kkt-residual", "generalized-inverse-residual"}


def test_craig_bampton_converges_to_the_unreduced_model():
    reference = modes_of(small_case(solver="sparse", check="[]", count=8)).omega
    errors = []
    for g in (1, 3, 8, 20):
        cb = f"{{method: craig-bampton, modes: {g}}}"
        w = modes_of(small_case(cb, cb, check="[]", count=8)).omega
        errors.append(np.max((w - reference) / reference))
        assert np.all(w >= reference * (1 - 1e-10))  # Rayleigh-Ritz: from above
    assert all(a > b for a, b in zip(errors, errors[1:])), errors
    assert errors[0] > 1e-2 and errors[-1] < 1e-4, errors


def test_modal_truncation_of_a_solid_and_points_by_node():
    model = build_model(parse_case(small_case(left_reduce="{modes: 10}"), "small.yaml", ROOT))
    left = model.assembly.substructures[0]
    assert left.kind == "modal" and left.n_dof == 10
    # the node form reads the same row as the coordinates of that node
    case = parse_case(small_case(), "small.yaml", ROOT)
    sub = build_model(case).assembly.substructures[1]
    node = int(np.flatnonzero(np.all(np.isclose(sub.geometry.points, [1, 0.05, 0.1]),
                                      axis=1))[0])
    text = small_case().replace('["right@1,0.05,0.1:z", tmd]', f'["right@n{node}:z", tmd]')
    a = build_model(parse_case(text, "small.yaml", ROOT)).assembly.A.toarray()
    b = build_model(case).assembly.A.toarray()
    np.testing.assert_array_equal(a, b)


# --------------------------------------------------------------------- bad solid input


@pytest.mark.parametrize("overrides, fragment", [
    (["substructures.left.fixed=[clmp]"],
     "substructures.left.fixed[0]: no named set 'clmp' in the mesh of 'left' (it has: clamp, "
     "interface, solid)"),
    (["substructures.left.mesh=../meshes/nope.msh"],
     "substructures.left.mesh: no such mesh file"),
    (["substructures.right.mesh=../meshes/box_beam_right_fine.msh"],
     "interfaces.joint: interface left-right: nodes do not match within 5e-09: 0 of 32 nodes of "
     "left and 64 of 96 nodes of right are unmatched; worst distance 0.0141 at [0.5, 0.01, "
     "0.01] (set matching: false for non-matching meshes)"),
    (["connections[0][0]=right@1.5,0.05,0.1:z"],
     "connections[0][0]: right: point [1.5, 0.05, 0.1] is outside the mesh, got "
     "'right@1.5,0.05,0.1:z'"),
    (["connections[0][0]=right@1,0.05,0.1:w"],
     "connections[0][0]: no displacement component 'w' on solid 'right' (one of x, y, z)"),
    (["connections[0][0]=right@1,0.05,0.1"],
     "connections[0][0]: a point on solid 'right' needs a displacement component"),
], ids=["unknown set", "missing mesh", "non-matching interface", "point off the mesh",
        "bad component", "no component"])
def test_bad_solid_input_is_one_line_and_exit_2(overrides, fragment, tmp_path, capsys):
    args = [a for s in overrides for a in ("--set", s)]
    code, out, err = run(capsys, "run", BOX_BEAM, "--out", tmp_path / "out", *args)
    assert code == 2, err
    assert err.startswith(f"substruct: error: {BOX_BEAM}: ") and err.count("\n") == 1, err
    assert fragment in err and "Traceback" not in err and out == ""
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


def test_non_matching_interface_runs_with_matching_false(capsys, tmp_path):
    """The finer right half first: its 96 interface nodes follow the left half's surface
    (288 rows); the lowest modes are those of the matching meshes to 3e-4."""
    s = omegas(capsys, BOX_BEAM, "--out", tmp_path,
               "--set", "substructures.right.mesh=../meshes/box_beam_right_fine.msh",
               "--set", "interfaces.joint.matching=false",
               "--set", "interfaces.joint.between=[right, left]",
               *[a for s in FULL_UNDAMPED for a in ("--set", s)])
    w = np.array(s["modes"]["omega"])
    assert len(s["model"]["constraints"]) == 3 + 288
    assert max(s["modes"]["residual"]) < 1e-10
    np.testing.assert_allclose(w[:3], REGRESSION_MATCHING, rtol=1e-3)
