"""DMIG entries in bulk data as a superelement: the stiffness and mass of a bulk data element
model (cases/frame_arm.bdf: CBARs and a CONM2 with offset and inertia) written as DMIG
(symmetric IFO 6 with one triangle in free field at 17 digits; square IFO 1 in small field)
and read back equal that model's matrices and modes; malformed entries refused in one line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from substruct.case.dmig import dmig_matrices, read_dmig
from substruct.case.loader import CaseError, load_case
from substruct.run.runner import run_case

ARM = Path(__file__).resolve().parents[1] / "cases" / "frame_arm.bdf"


def _case(tmp: Path, sub: str, count: int = 14) -> Path:
    path = tmp / "case.yaml"
    path.write_text(f"""name: arm
substructures:
  - {sub}
analysis:
  modes: {{count: {count}, method: generalized-inverse}}
output: {{matrices: true, pictures: false}}
""")
    return path


@pytest.fixture(scope="module")
def element_model(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("arm")
    (tmp / "arm.bdf").write_text(ARM.read_text())
    return run_case(load_case(_case(tmp, "{name: arm, type: nastran, file: arm.bdf}")))


def _dofs(result) -> list[tuple[int, int]]:
    out = []
    for lab in result.model.dof_labels:
        g, c = lab.split(".", 1)[1].split(":")
        out.append((int(g), int(c)))
    return out


def _free(name: str, A: sp.csr_array, dofs, lower: bool) -> str:
    """Free-field DMIG of a symmetric matrix: the lower (or upper) triangle, 17 digits."""
    lines = [f"DMIG,{name},0,6,2"]
    C = sp.csc_array(sp.tril(A) if lower else sp.triu(A))
    for j in range(C.shape[1]):
        rows, vals = C.indices[C.indptr[j]:C.indptr[j + 1]], C.data[C.indptr[j]:C.indptr[j + 1]]
        if not len(rows):
            continue
        g, c = dofs[j]
        terms = [f"{dofs[i][0]},{dofs[i][1]},{v:.16E}," for i, v in zip(rows, vals)]
        lines.append(f"DMIG,{name},{g},{c},," + terms[0])
        lines += ["," + ",".join(terms[k:k + 2]) for k in range(1, len(terms), 2)]
    return "\n".join(lines) + "\n"


def _small(name: str, A: np.ndarray, dofs) -> str:
    """Small-field DMIG, square form IFO 1, every non-zero of every column (8-character
    numbers)."""
    def f(x: object) -> str:
        return str(x)[:8].ljust(8)

    def real(v: float) -> str:
        s = f"{v:.2E}".replace("E", "")
        return s.ljust(8)

    lines = ["DMIG    " + f(name) + f(0) + f(1) + f(1)]
    for j in range(A.shape[1]):
        rows = np.flatnonzero(A[:, j])
        if not rows.size:
            continue
        g, c = dofs[j]
        terms = [f(dofs[i][0]) + f(dofs[i][1]) + real(A[i, j]) + " " * 8 for i in rows]
        lines.append("DMIG    " + f(name) + f(g) + f(c) + " " * 8 + terms[0])
        lines += ["        " + "".join(terms[k:k + 2]) for k in range(1, len(terms), 2)]
    return "\n".join(lines) + "\n"


def test_dmig_model_equals_the_element_model(tmp_path: Path, element_model) -> None:
    """Free-field IFO 6, 17 significant digits: the matrices bit for bit, the modes of the two
    cases equal to 1e-10 (the same matrices, the same solver)."""
    K, M = element_model.model.matrices["K"], element_model.model.matrices["M"]
    dofs = _dofs(element_model)
    (tmp_path / "arm_dmig.bdf").write_text("$ arm as DMIG\n" + _free("KAAX", K, dofs, True) +
                                           _free("MAAX", M, dofs, False) + "ENDDATA\n")
    got_dofs, mats, nbytes = dmig_matrices(tmp_path / "arm_dmig.bdf", "arm_dmig.bdf",
                                           ["KAAX", "MAAX"])
    assert got_dofs == sorted(dofs) == dofs and nbytes == 8
    assert np.array_equal(mats["KAAX"], K.toarray())
    assert np.array_equal(mats["MAAX"], M.toarray())
    case = _case(tmp_path, "{name: arm, type: superelement, file: arm_dmig.bdf, M: MAAX, "
                           "K: kaax, grids: {100: [0, 0, 1], 101: [0.2, 0, 1], 102: [0.4, 0, 1],"
                           " 103: [0.6, 0, 1], 104: [0.8, 0, 1]}}")
    got = run_case(load_case(case))
    ref = element_model.modes.omega
    elastic = ref > 1e-6 * ref.max()
    assert elastic.sum() == 8
    np.testing.assert_allclose(got.modes.omega[elastic], ref[elastic], rtol=1e-10)
    assert got.model.dof_labels[0] == "arm.100:ux"
    # the rigid-body mass: the bars' rho A L plus the tool's 20 kg
    props = load_case(case).substructures[0].rigid_body()
    assert props["mass"] == pytest.approx(7850.0 * 1.2e-3 * 0.8 + 20.0, rel=1e-12)


def test_square_small_field_form(tmp_path: Path, element_model) -> None:
    """IFO 1 in small field: every term of both triangles, numbers of 3 significant digits:
    the matrix read is the one written (to its digits) and symmetric to them."""
    K = element_model.model.matrices["K"].toarray()
    dofs = _dofs(element_model)
    (tmp_path / "k.dat").write_text(_small("KSQ", K, dofs))
    _, mats, nbytes = dmig_matrices(tmp_path / "k.dat", "k.dat", ["KSQ"])
    assert nbytes == 4
    np.testing.assert_allclose(mats["KSQ"], K, rtol=5e-3, atol=0)
    assert read_dmig(tmp_path / "k.dat", "k.dat")["KSQ"].form == 1


def test_ncol_on_square_and_symmetric_forms_not_used() -> None:
    """A Nastran punch file writes NCOL on IFO 1 and IFO 6 headers too, where Nastran does not
    use it: read, with the numbers pyYeti's reader gives for this file."""
    path = Path(__file__).parent / "data" / "nastran" / "dmig" / "matrix_factory_real.pch"
    mats = read_dmig(path, path.name)
    assert (mats["PATRN"].form, mats["IDENT"].form) == (1, 6)
    dofs, got, nbytes = dmig_matrices(path, path.name, ["PATRN", "IDENT"])
    assert dofs == [(g, c) for g in (1, 2, 3) for c in range(1, 7)] + [(10, 0), (11, 0), (12, 0)]
    assert nbytes == 4  # IFO 1 counts as single precision for the symmetry check
    assert np.array_equal(got["PATRN"], np.tile(np.arange(1.0, 22.0), (21, 1)))
    assert np.array_equal(got["IDENT"], np.eye(21))


@pytest.mark.parametrize("text,fragment", [
    ("DMIG,K,0,6,2\nDMIG,K,1,1,,1,1,2.0,\nDMIG,K,1,1,,1,2,1.0,\n",
     "line 3: DMIG K: column 1:1 of DMIG K is given twice (also on line 2)"),
    ("DMIG,K,0,6,2\nDMIG,K,1,1,,1,2,1.0,\nDMIG,K,1,2,,1,1,1.0,\n",
     "DMIG K is symmetric (IFO 6): give one triangle, but term (1:1, 1:2) is given in both"),
    ("DMIG,K,0,6,4\n", "DMIG K: TIN: TIN 1 and 2 (real) are read"),
    ("DMIG,K,0,2,2,,,,3\n", "DMIG K: IFO: IFO 6 (symmetric) and 1 (square) are read"),
    ("DMIG,K,0,6,2,,,,-3\nDMIG,K,1,1,,1,1,2.0,\n", "NCOL: NCOL (not used for IFO 1 "
     "and 6) is blank or a count of columns, not negative"),
    ("DMIG,K,0,6,2,,,,x\nDMIG,K,1,1,,1,1,2.0,\n", "NCOL: must be an integer"),
    ("DMIG,K,0,6,2,,,7,\nDMIG,K,1,1,,1,1,2.0,\n", "field 8 of a DMIG header is blank"),
    ("DMIG,K,1,1,,1,1,2.0,\n", "a column of DMIG K with no header entry"),
    ("DMIG,K,0,6,2\nDMIG,K,1,7,,1,1,2.0,\n", "GJ component: a component is 1-6"),
    ("DMIG,K,0,6,2\nDMIG,K,1,1,,1,1,2.0,3.0\n", "B (the imaginary part) is blank"),
    ("DMIG,K,0,6,2\nGRID,1,,0.,0.,0.\n", "card GRID is not read from a file of DMIG matrices"),
    ("DMIG,KX,0,6,2\nDMIG,KX,1,1,,1,1,2.0,\n", "no DMIG 'K' (it has KX)"),
    ("DMIG,K,0,6,2\nDMIG,K,5,0,,5,0,2.0,\nDMIG,K,5,1,,5,1,2.0,\n",
     "id 5 is named as a scalar point (component 0) and as a grid (components 1-6)"),
])
def test_bad_dmig_is_one_line(tmp_path: Path, text: str, fragment: str) -> None:
    (tmp_path / "m.bdf").write_text(text)
    case = _case(tmp_path, "{name: s, type: superelement, file: m.bdf, M: K, K: K}", 1)
    with pytest.raises(CaseError) as err:
        load_case(case)
    msg = str(err.value)
    assert fragment in msg and "substructures.s.file: " in msg and "\n" not in msg, msg


def test_dofs_with_dmig_refused(tmp_path: Path) -> None:
    (tmp_path / "m.bdf").write_text("DMIG,K,0,6,2\nDMIG,K,1,1,,1,1,2.0,\n")
    case = _case(tmp_path, "{name: s, type: superelement, file: m.bdf, M: K, K: K, "
                           "dofs: [[1, '1']]}", 1)
    with pytest.raises(CaseError, match=r"substructures\.s\.dofs: m\.bdf is bulk data: the DOF "
                       r"map is that of its DMIG entries"):
        load_case(case)
