"""Exports of a model as matrices: the coupled model of two Craig-Bampton superelements (its
constraints eliminated) and one of its parts, written by ``substruct export --format op4|npz``
and read back as superelements, give the modes of the run to 1e-10; what cannot be exported is
refused in one line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cli_helpers import assert_one_line_error, run
from substruct.case.loader import load_case
from substruct.io.hdf5 import load
from substruct.io.op4 import write_op4
from substruct.models.craig_bampton import craig_bampton
from substruct.run.runner import run_case
from test_recovery import CLAMP, CONNECT, _dof_rows, _frames


@pytest.fixture(scope="module")
def coupled(tmp_path_factory):
    """Two frames reduced by Craig-Bampton (a: boundary grids 1 and 3, 5 modes; b: grid 10, 4
    modes), coupled at 3/10, clamped at 1, with a damping matrix on b; run with its matrices
    stored."""
    tmp = tmp_path_factory.mktemp("export")
    a, b = _frames()
    for sub, bnd, g, name in ((a, (1, 3), 5, "a"), (b, (10,), 4, "b")):
        idx = [k for k, lab in enumerate(sub.dof_labels) if int(lab.split(":")[0]) in bnd]
        red = craig_bampton(sub, idx, g)
        mats = {"MAA": red.M.toarray(), "KAA": red.K.toarray(), "DOFS": _dof_rows(red.dof_labels)}
        if name == "b":
            mats["BAA"] = 1e-4 * red.K.toarray()
        write_op4(tmp / f"{name}.op4", mats)
    (tmp / "case.yaml").write_text(f"""name: coupled
substructures:
  - {{name: a, type: superelement, file: a.op4, M: MAA, K: KAA, dofs: {{key: DOFS}}}}
  - {{name: b, type: superelement, file: b.op4, M: MAA, K: KAA, C: BAA, dofs: {{key: DOFS}}}}
connections:
{CONNECT}
constraints:
{CLAMP}
analysis:
  modes: {{count: 12, method: generalized-inverse}}
output: {{matrices: true, pictures: false}}
""")
    return tmp


def _read_back(tmp: Path, file: str, count: int = 12):
    fmt = Path(file).suffix
    keys = "M: MAA, K: KAA, C: BAA" if fmt == ".op4" else "M: M, K: K, C: C"
    (tmp / "back.yaml").write_text(f"""name: back
substructures:
  - {{name: all, type: superelement, file: {file}, {keys}, dofs: {{key: DOFS}}}}
analysis:
  modes: {{count: {count}, method: generalized-inverse}}
""")
    return run_case(load_case(tmp / "back.yaml"))


@pytest.mark.parametrize("fmt", ["op4", "npz"])
def test_coupled_model_round_trip(coupled: Path, capsys, fmt: str) -> None:
    out = coupled / f"out_{fmt}"
    code, _, err = run(capsys, "run", coupled / "case.yaml", "--out", out, "--force")
    assert code == 0, err
    code, text, err = run(capsys, "export", out / "coupled.h5", "--format", fmt)
    assert code == 0, err
    assert text.strip() == str(out / f"coupled_model.{fmt}")
    ref = load(out / "coupled.h5").modes
    back = _read_back(out, f"coupled_model.{fmt}")
    np.testing.assert_allclose(back.modes.eigenvalues, ref.eigenvalues, rtol=1e-10)
    # the clamped grid 1 and one side of each tie are eliminated: 17 + 10 - 6 - 6 coordinates
    assert back.model.offsets[-1] == 15
    labels = back.model.dof_labels
    assert sum(lab.startswith("all.mode:") for lab in labels) == 9
    assert not any(lab.startswith("all.1:") for lab in labels)


def test_part_round_trip_and_refusals(coupled: Path, capsys) -> None:
    out = coupled / "out_part"
    code, _, err = run(capsys, "run", coupled / "case.yaml", "--out", out, "--force")
    assert code == 0, err
    code, text, err = run(capsys, "export", out / "coupled.h5", "--format", "npz", "--part", "b")
    assert code == 0, err
    with np.load(out / "coupled_b.npz") as z:
        ref = _op4(coupled / "b.op4")
        assert np.array_equal(z["K"], ref["KAA"]) and np.array_equal(z["C"], ref["BAA"])
        assert list(z["labels"][:2]) == ["mode:1", "mode:2"]
        assert np.array_equal(z["DOFS"], ref["DOFS"])
    code, out_text, err = run(capsys, "export", out / "coupled.h5", "--format", "op4",
                              "--part", "zz")
    assert_one_line_error(code, out_text, err, "--part 'zz' is not a part of the model "
                          "(it has a, b)")
    code, out_text, err = run(capsys, "export", out / "coupled.h5", "--format", "npz",
                              "--part", "b")
    assert_one_line_error(code, out_text, err, "exists")
    code, out_text, err = run(capsys, "export", out / "coupled.h5", "--format", "vtu",
                              "--part", "b")
    assert_one_line_error(code, out_text, err, "--part applies to --format op4 and npz")


def _op4(path: Path) -> dict:
    """The matrices of an OP4 file, dense, by name."""
    from substruct.case.op4 import read_op4

    return {k: v.dense() for k, v in read_op4(path).items()}


def test_no_matrices_or_unmappable_labels(tmp_path: Path, coupled: Path, capsys) -> None:
    text = (coupled / "case.yaml").read_text().replace("matrices: true", "matrices: false")
    (tmp_path / "case.yaml").write_text(text.replace("file: ", f"file: {coupled}/"))
    code, _, err = run(capsys, "run", tmp_path / "case.yaml", "--out", tmp_path, "--force")
    assert code == 0, err
    code, out, err = run(capsys, "export", tmp_path / "coupled.h5", "--format", "op4")
    assert_one_line_error(code, out, err, "holds no matrices: run the case with output: "
                          "{matrices: true}")
    (tmp_path / "rod.yaml").write_text("""name: rod
substructures:
  - {name: s, type: spring, stiffness: 1.0e+3, ground: true}
  - {name: m, type: mass, mass: 2.0}
connections: [[s@i, m@mass]]
analysis: {modes: {count: 1}}
output: {matrices: true, pictures: false}
""")
    code, _, err = run(capsys, "run", tmp_path / "rod.yaml", "--out", tmp_path, "--force")
    assert code == 0, err
    code, out, err = run(capsys, "export", tmp_path / "rod.h5", "--format", "npz")
    assert_one_line_error(code, out, err, "is neither <grid>:<component> nor a mode")


def test_units_travel_with_an_npz_export(tmp_path: Path, coupled: Path, capsys) -> None:
    """A case that declares ``units`` writes them into its NPZ export (member ``units``); a
    case reading the file back must declare the same units (commas and spaces aside): other
    units, or none, are refused at the superelement's ``file`` rather than silently mixed.
    The part read back in the same units is the part written: its matrices ``==``."""
    text = (coupled / "case.yaml").read_text().replace("file: ", f"file: {coupled}/")
    (tmp_path / "case.yaml").write_text('units: "N, mm, t, s"\n' + text)
    code, _, err = run(capsys, "run", tmp_path / "case.yaml", "--out", tmp_path, "--force")
    assert code == 0, err
    code, _, err = run(capsys, "export", tmp_path / "coupled.h5", "--format", "npz",
                       "--part", "b")
    assert code == 0, err
    with np.load(tmp_path / "coupled_b.npz") as z:
        assert str(z["units"]) == "N, mm, t, s"
    body = """substructures:
  - {name: b, type: superelement, file: coupled_b.npz, M: M, K: K, C: C, dofs: {key: DOFS},
     free: false}
analysis: {modes: {count: 3}}
output: {pictures: false}
"""
    for k, (units, problem) in enumerate((('"N,mm,t,s"', None),
                           ('"N, m, kg, s"', "declares its units 'N, mm, t, s' (member "
                            "'units'), not the case's 'N, m, kg, s'"),
                           (None, "declares its units 'N, mm, t, s' (member 'units') and the "
                            "case none"))):
        head = "name: back\n" + (f"units: {units}\n" if units else "")
        (tmp_path / "back.yaml").write_text(head + body)
        code, out, err = run(capsys, "run", tmp_path / "back.yaml", "--out",
                             tmp_path / f"back{k}", "--force")
        if problem is None:
            assert code == 0, err
            spec = load_case(tmp_path / "back.yaml").substructures[0]
            assert np.array_equal(spec.matrix("K"), _op4(coupled / "b.op4")["KAA"])
        else:
            assert_one_line_error(code, out, err, "substructures.b.file: coupled_b.npz",
                                  problem)
            assert not (tmp_path / f"back{k}" / "back.h5").exists()
