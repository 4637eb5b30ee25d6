"""Abaqus matrix files (``*MATRIX GENERATE`` / ``*MATRIX OUTPUT`` text ``.mtx``) as a
superelement: a frame's stiffness and mass written by a small writer of this test in the
nodes layout (one triangle, or the square matrix) and in the coordinate layout with a DOF map,
read back bit for bit, clamped, give the frame's own modes to round-off; malformed files are
refused in one line naming the file, the line and the problem."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sl

from substruct.case.loader import CaseError, load_case
from substruct.models.beam import Material, Section
from substruct.models.frame import FRAME_COMPONENTS, Beam, frame
from substruct.run.runner import run_case

SEC = Section(A=2.85e-3, Iy=1.94e-5, Iz=1.42e-6, J=7.0e-8)
MAT = Material(E=2.1e11, G=8.1e10, rho=7850.0)


def _frame():
    return frame("arm", {1: (0.0, 0.0, 0.0), 2: (1.5, 0.0, 0.0), 3: (1.5, 1.0, 0.4)},
                 [Beam((1, 2), SEC, MAT, (0, 0, 1), divisions=4),
                  Beam((2, 3), SEC, MAT, (0, 0, 1), divisions=3)],
                 node_masses={3: 25.0})


def _node_dofs(sub) -> list[tuple[int, int]]:
    out = []
    for lab in sub.dof_labels:
        g, c = lab.split(":")
        out.append((int(g), FRAME_COMPONENTS.index(c) + 1))
    return out


def write_nodes(path: Path, A: np.ndarray, dofs, storage: str) -> None:
    """Abaqus's matrix input layout: ``node, dof, node, dof, value``, the non-zeros of the
    lower triangle, the upper one or the whole matrix, row by row."""
    lines = ["** written by the test"]
    for i, j in zip(*np.nonzero(A)):
        if (storage == "lower" and j > i) or (storage == "upper" and j < i):
            continue
        lines.append(f"{dofs[i][0]},{dofs[i][1]}, {dofs[j][0]},{dofs[j][1]}, {float(A[i, j])!r}")
    path.write_text("\n".join(lines) + "\n")


def write_coordinate(path: Path, A: np.ndarray) -> None:
    """Abaqus's coordinate layout: ``row, column, value``, 1-based, lower triangle."""
    path.write_text("".join(f"{i + 1} {j + 1} {A[i, j]:.17E}\n".replace(" ", ",", 2)
                            for i, j in zip(*np.nonzero(np.tril(A)))))


def write_coordinate_blank(path: Path, A: np.ndarray) -> None:
    """The coordinate layout as Abaqus 2024 writes it (``FORMAT=COORDINATE``): ``row column
    value`` separated by blanks, 1-based, by rows of the upper triangle, each off-diagonal term
    followed by its mirror (``1 2  3.749985979900784e+08`` then ``2 1  3.7499...e+08``), the
    value in ``% .15e``."""
    lines = []
    for i, j in zip(*np.nonzero(np.triu(A))):
        lines.append(f"{i + 1} {j + 1} {A[i, j]: .15e}")
        if i != j:
            lines.append(f"{j + 1} {i + 1} {A[j, i]: .15e}")
    path.write_text("\n".join(lines) + "\n")


CLAMP = "\n".join(f"  - {{name: c{c}, terms: {{arm@1:{c}: 1}}}}" for c in FRAME_COMPONENTS)


def _case(tmp: Path, sub_text: str, count: int = 6) -> Path:
    path = tmp / "case.yaml"
    path.write_text(f"""name: abaqus
substructures:
  - {{name: arm, type: superelement, {sub_text}}}
constraints:
{CLAMP}
analysis:
  modes: {{count: {count}, method: generalized-inverse}}
""")
    return path


def _same_model_from_npz(tmp: Path, sub, count: int = 6) -> np.ndarray:
    """The eigenvalues of the same case with the frame's matrices given as NPZ arrays."""
    np.savez(tmp / "arm.npz", M=sub.M.toarray(), K=sub.K.toarray(),
             DOFS=np.array(_node_dofs(sub), dtype=float))
    res = run_case(load_case(_case(tmp, "file: arm.npz, M: M, K: K, dofs: {key: DOFS}",
                                   count)))
    return res.modes.omega[:count] ** 2


def _reference(sub, count: int) -> np.ndarray:
    """The clamped frame's lowest eigenvalues, dense."""
    keep = [k for k, lab in enumerate(sub.dof_labels) if not lab.startswith("1:")]
    K, M = sub.K.toarray()[np.ix_(keep, keep)], sub.M.toarray()[np.ix_(keep, keep)]
    return sl.eigh(K, M, eigvals_only=True, subset_by_index=[0, count - 1])


@pytest.mark.parametrize("storage_k,storage_m", [("lower", "upper"), ("square", "lower")])
def test_nodes_layout_gives_the_frame_modes(tmp_path: Path, storage_k: str,
                                            storage_m: str) -> None:
    sub = _frame()
    dofs = _node_dofs(sub)
    write_nodes(tmp_path / "arm_STIF1.mtx", sub.K.toarray(), dofs, storage_k)
    write_nodes(tmp_path / "arm_MASS1.mtx", sub.M.toarray(), dofs, storage_m)
    case = load_case(_case(tmp_path, "M: arm_MASS1.mtx, K: arm_STIF1.mtx"))
    spec = case.substructures[0]
    # the DOF map is the files' (node, dof) in ascending order; the matrices bit for bit
    order = sorted(range(len(dofs)), key=lambda k: dofs[k])
    assert spec.dof_table() == [dofs[k] for k in order]
    for name, A in (("K", sub.K), ("M", sub.M)):
        assert np.array_equal(spec.matrix(name), A.toarray()[np.ix_(order, order)])
    _check_modes(tmp_path, sub, run_case(case).modes.omega[:6] ** 2)


def _check_modes(tmp: Path, sub, lam: np.ndarray) -> None:
    """The same eigenvalues as the NPZ model to round-off (the same matrices in another
    order), and as a dense solve of the clamped frame to the formulation's accuracy (measured
    1.8e-8 on the first mode: the constraint projection of the generalized inverse)."""
    np.testing.assert_allclose(lam, _same_model_from_npz(tmp, sub), rtol=1e-10)
    np.testing.assert_allclose(lam, _reference(sub, 6), rtol=1e-6)


def test_coordinate_layout_with_a_dof_map(tmp_path: Path) -> None:
    sub = _frame()
    dofs = _node_dofs(sub)
    write_coordinate(tmp_path / "arm_STIF1.mtx", sub.K.toarray())
    write_coordinate(tmp_path / "arm_MASS1.mtx", sub.M.toarray())
    (tmp_path / "arm.csv").write_text("".join(f"{g},{c}\n" for g, c in dofs))
    case = load_case(_case(tmp_path, "M: arm_MASS1.mtx, K: arm_STIF1.mtx, "
                                     "dofs: {file: arm.csv}"))
    spec = case.substructures[0]
    assert spec.dof_table() == dofs
    assert np.array_equal(spec.matrix("K"), sub.K.toarray())
    _check_modes(tmp_path, sub, run_case(case).modes.omega[:6] ** 2)


WRITERS = {
    "nodes lower": lambda p, A, d: write_nodes(p, A, d, "lower"),
    "nodes upper": lambda p, A, d: write_nodes(p, A, d, "upper"),
    "nodes square": lambda p, A, d: write_nodes(p, A, d, "square"),
    "coordinate commas": lambda p, A, d: write_coordinate(p, A),
    "coordinate blanks": lambda p, A, d: write_coordinate_blank(p, A),
}


def test_every_layout_reads_to_the_same_matrices(tmp_path: Path) -> None:
    """The same stiffness and mass written in each layout and storage read back to the same
    matrices, ``==``, on the same DOF map (the nodes layout sorts its map; the coordinate one
    keeps the map given, here already sorted).  Values whose ``% .15e`` text differs from the
    double are rounded first, so that every writer writes the same numbers."""
    sub = _frame()
    dofs = _node_dofs(sub)
    order = sorted(range(len(dofs)), key=lambda k: dofs[k])
    dofs = [dofs[k] for k in order]
    mats = {n: np.array([[float(f"{v: .15e}") for v in row]
                         for row in A.toarray()[np.ix_(order, order)]])
            for n, A in (("K", sub.K), ("M", sub.M))}
    (tmp_path / "arm.csv").write_text("".join(f"{g},{c}\n" for g, c in dofs))
    seen = {}
    for name, write in WRITERS.items():
        d = tmp_path / name.replace(" ", "_")
        d.mkdir()
        for key, A in mats.items():
            write(d / f"arm_{key}.mtx", A, dofs)
        dofs_text = ", dofs: {file: ../arm.csv}" if name.startswith("coordinate") else ""
        case = load_case(_case(d, f"M: arm_M.mtx, K: arm_K.mtx{dofs_text}"))
        spec = case.substructures[0]
        assert spec.dof_table() == dofs, name
        seen[name] = {key: spec.matrix(key) for key in mats}
        for key, A in mats.items():
            assert np.array_equal(seen[name][key], A), (name, key)
    assert len(seen) == len(WRITERS)


GOOD = "1,1, 1,1, 2.0\n1,2, 1,1, 0.5\n1,2, 1,2, 3.0\n"


@pytest.mark.parametrize("text,message", [
    (GOOD + "1,2, 1,1, 0.5\n", r"arm_STIF1\.mtx: line 4: term \(1:2, 1:1\) is given twice "
     r"\(also on line 2\)"),
    (GOOD + "1,2, 1,1\n", r"arm_STIF1\.mtx: line 4: expected 'node, dof, node, dof, value' "
     r"\(comma-separated\) or 'row column value' \(blank- or comma-separated numbers\), got "
     r"'1,2, 1,1'"),
    (GOOD + "1 2 1 1 0.5\n", r"line 4: expected 'node, dof, node, dof, value' \(comma"),
    (GOOD + "1,3, 1,3,  1.000000000000000e+36\n", r"line 4: 1e36 is the diagonal Abaqus writes "
     r"for a degree of freedom held by a boundary condition; .*, got '1.000000000000000e\+36'"),
    (GOOD + "1,2, 1,1, 1.0x\n", r"line 4: expected"),
    (GOOD + "1,11, 1,1, 1.0\n", r"line 4: degree of freedom 11 is not a displacement or a "
     r"rotation \(1-6\)"),
    (GOOD + "-24,1, 1,1, 1.0\n", r"line 4: node -24 is an internal node of Abaqus"),
    ("*MATRIX INPUT\n" + GOOD, r"line 1: a keyword line"),
    (GOOD + "1, 2, 1.0\n", r"line 4: a coordinate line in a file of nodes lines"),
    (GOOD + "1,1, 1,2, 0.5\n1,1, 1,3, 0.1\n", r"line 5: term \(1:1, 1:3\) has no mirror term"),
    (GOOD + "1,3, 1,3, nan\n", r"line 4: expected"),
    (GOOD + "1,3, 1,3, 1e999\n", r"line 4: the value is not a finite number"),
    ("** nothing\n", r"arm_STIF1\.mtx: no matrix terms in the file"),
])
def test_bad_files(tmp_path: Path, text: str, message: str) -> None:
    (tmp_path / "arm_STIF1.mtx").write_text(text)
    (tmp_path / "arm_MASS1.mtx").write_text("1,1, 1,1, 1.0\n1,2, 1,2, 1.0\n")
    if not message.startswith("arm_"):
        message = r"arm_STIF1\.mtx: " + message
    with pytest.raises(CaseError, match=r"case\.yaml: substructures\.arm\.K: " + message):
        load_case(_case(tmp_path, "M: arm_MASS1.mtx, K: arm_STIF1.mtx, free: false"))


@pytest.mark.parametrize("sub_text,stiff,message", [
    ("M: m.mtx, K: k.mtx", "1, 1, 2.0\n", r"substructures\.arm\.M: m\.mtx: a file of 'row, "
     r"column, value' lines \(Abaqus's coordinate format\) needs the DOF map: give dofs"),
    ("M: m.mtx, K: k.mtx, dofs: [[1, '1']]", "1, 1, 2.0\n2, 2, 1.0\n",
     r"substructures\.arm\.K: k\.mtx: line 2: equation number 2 is beyond the 1 rows of the "
     r"DOF map"),
    ("M: m.mtx, K: k.mtx, dofs: [[1, '1']]", "1,1, 1,1, 2.0\n",
     r"substructures\.arm\.M: m\.mtx: the matrix files mix the nodes layout"),
    ("M: MAA, K: k.mtx", "1,1, 1,1, 2.0\n", r"substructures\.arm\.file: the file of the "
     r"matrices is required .* but M is 'MAA'"),
])
def test_bad_combinations(tmp_path: Path, sub_text: str, stiff: str, message: str) -> None:
    (tmp_path / "k.mtx").write_text(stiff)
    (tmp_path / "m.mtx").write_text("1, 1, 1.0\n")
    with pytest.raises(CaseError, match=message):
        load_case(_case(tmp_path, sub_text))


def test_bad_file_through_the_command_line(tmp_path: Path, capsys) -> None:
    """Exit code 2, one line, nothing written."""
    from substruct import cli

    (tmp_path / "k.mtx").write_text(GOOD + "1,2, 1,1, 0.5\n")
    (tmp_path / "m.mtx").write_text("1,1, 1,1, 1.0\n1,2, 1,2, 1.0\n")
    case = _case(tmp_path, "M: m.mtx, K: k.mtx")
    assert cli.main(["run", str(case), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].endswith("k.mtx: line 4: term (1:2, 1:1) is given twice "
                                             "(also on line 2)")
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())
