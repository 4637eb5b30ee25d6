"""Ansys FULL files (``Jobname.FULL``) as a superelement.

``tests/data/ansys/file.full`` is ansys-mapdl-reader's example (321 nodes of ``UX UY UZ``, 63
equations held by constraints) and ``file_reference.npz`` the same file read by
ansys-mapdl-reader 0.56.0 (an independent reader; see the README there).  substruct's reader
gives the reference's matrices and DOF map, the model read as ``type: superelement`` gives
the reference matrices' modes, and malformed files (each a copy of the example with one word
changed) are refused in one line naming the file, the record and the problem."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sl

from substruct.case.ansys_full import _INT_FLAG, _REAL_FLAG, _Records, read_full
from substruct.case.errors import CaseError
from substruct.case.loader import load_case
from substruct.run.runner import run_case

DATA = Path(__file__).parent / "data" / "ansys"
FULL = DATA / "file.full"
HEADER = 105        # the word of the FULL header's item 1 (the key -4)


def _reference(name: str = "file") -> tuple[np.ndarray, np.ndarray, list[tuple[int, int]]]:
    """The reference's K and M (stored as one triangle, the constrained equations zero) made
    whole, without the constrained equations, and their (node, component): the file's labels
    are UX UY UZ, so the reference's 0-based index in the node is the component less 1."""
    ref = np.load(DATA / f"{name}_reference.npz")
    held = {tuple(int(x) for x in row) for row in ref["const"]}
    dof = [(int(n), int(j)) for n, j in ref["dof_ref"]]
    keep = [k for k, d in enumerate(dof) if d not in held]
    whole = [A + A.T - np.diag(np.diag(A)) for A in (ref["K"], ref["M"])]
    K, M = (A[np.ix_(keep, keep)] for A in whole)
    return K, M, [(dof[k][0], dof[k][1] + 1) for k in keep]


def test_matrices_and_dof_map_equal_the_reference() -> None:
    got = read_full(FULL, FULL.name)
    K, M, dofs = _reference()
    assert got.dofs == dofs and len(dofs) == 900 and len(got.constrained) == 63
    # the same doubles from the same file: equal to the last bit
    assert np.array_equal(got.K.toarray(), K)
    assert np.array_equal(got.M.toarray(), M)


def test_compressed_records_equal_the_reference() -> None:
    """``sparse.full`` (MAPDL 20.1) writes its DOF table as a windowed-sparse integer record
    (flags 0x90000000: 115 nodes of 3 degrees of freedom as one repeated value): read, it
    gives the reference's matrices and DOF map."""
    path = DATA / "sparse.full"
    w = np.fromfile(path, "<i4")
    assert w[24861:24869].tolist() == [5, 0x90000000 - (1 << 32), 115, 1, 0, -115, 3, 5]
    got = read_full(path, path.name)
    K, M, dofs = _reference("sparse")
    assert got.dofs == dofs and len(dofs) == 345 and got.constrained == []
    assert np.array_equal(got.K.toarray(), K)
    assert np.array_equal(got.M.toarray(), M)
    assert np.count_nonzero(K) > 0 and np.count_nonzero(M) > 0


def _record(body: list[int], flags: int) -> np.ndarray:
    """Words of a file holding one record ``body`` with ``flags``."""
    return np.array([len(body), flags - (1 << 32) if flags >> 31 else flags, *body,
                     len(body)], dtype="<i4")


def _doubles(*values: float) -> list[int]:
    return np.array(values, "<f8").view("<i4").tolist()


def test_compressed_record_forms() -> None:
    """The windowed-sparse and bit-sparse forms as ansys-mapdl-reader's record reader reads
    them (one value at an index, a run, a repeated value; a mask), and their malformed
    variants refused in one line."""
    def read(body: list[int], flags: int, flag: int, most: int = 100) -> np.ndarray:
        return _Records(_record(body, flags), "x.full", "<").record(0, "table", flag, most)[0]

    ints = read([10, 3, 2, 7, -4, 2, 4, 5, -7, -3, 9], 0x90000000, _INT_FLAG)
    assert ints.tolist() == [0, 0, 7, 0, 4, 5, 0, 9, 9, 9]
    vals = np.frombuffer(read([6, 2, 1, *_doubles(2.5), -3, -3, *_doubles(-1.25)],
                              0x10000000, _REAL_FLAG).tobytes(), "<f8")
    assert vals.tolist() == [0, 2.5, 0, -1.25, -1.25, -1.25]
    vals = np.frombuffer(read([5, 0b10110, *_doubles(1.5, 2.5, 3.5)], 0x08000000,
                              _REAL_FLAG).tobytes(), "<f8")
    assert vals.tolist() == [0, 1.5, 2.5, 0, 3.5]
    assert read([4, 0b1001, 8, 9], 0x88000000, _INT_FLAG).tolist() == [8, 0, 0, 9]

    for body, flags, most, message in [
        ([10**9, 0], 0x90000000, 100, "1000000000 values declared; 0 to 100 are accepted"),
        ([4, 1, -2, 3, 1, 2, 3], 0x90000000, 100, r"window 1 covers indices 2 to 4, not after "
                                                  r"the previous window and within 0 to 3"),
        ([4, 2, 2, 7, 1, 8], 0x90000000, 100, "window 2 covers indices 1 to 1, not after"),
        ([4, 1, 0, 0, 5], 0x90000000, 100, r"window 1 \(at index 0\) has length 0"),
        ([4, 1, 0, 3, 5], 0x90000000, 100, "its values run past its 5 words"),
        ([4, 1, 1, 5, 6], 0x90000000, 100, "1 words left after its 1 windows"),
        ([4, 0b10000, 5], 0x88000000, 100, r"mask 0x10 marks values beyond the 4 declared"),
        ([4, 0b11, 5], 0x88000000, 100, "its values run past its 3 words"),
        ([4, 0], 0xA0000000, 100, r"has flags 0xa0000000, not integers: a zlib-compressed "
                                  r"record; read are plain records \(0x80000000\)"),
    ]:
        with pytest.raises(CaseError, match=r"^x\.full: table: .*" + message):
            read(body, flags, _INT_FLAG, most)


def _case(tmp: Path, sub: str, count: int) -> Path:
    shutil.copy(FULL, tmp / "part.full")
    path = tmp / "case.yaml"
    path.write_text(f"""name: ansys
substructures:
  - {{name: part, type: superelement, file: part.full, {sub}}}
analysis:
  modes: {{count: {count}}}
""")
    return path


def test_superelement_modes_equal_the_reference_modes(tmp_path: Path) -> None:
    """The model is held by its constraints (free: false); its 8 lowest modes, solved by the
    run, against a dense solve of the reference matrices.  A backward-stable solve moves an
    eigenvalue by about eps lambda_max (eps times the norm of M^-1/2 K M^-1/2): the lowest
    pair, 6.5e7 against a largest eigenvalue of 4.2e15, is known to about 1.4e-8 of itself,
    and two dense LAPACK drivers on the same matrices differ there by 4e-9.  The tolerance is
    ten times that bound."""
    count = 8
    case = load_case(_case(tmp_path, "M: M, K: K, free: false", count))
    spec = case.substructures[0]
    K, M, dofs = _reference()
    assert spec.dof_table() == dofs
    lam = run_case(case).modes.omega[:count] ** 2
    ref = sl.eigh(K, M, eigvals_only=True)
    bound = 10 * np.finfo(float).eps * ref[-1]
    assert np.all(np.abs(lam - ref[:count]) <= bound), (lam - ref[:count]) / bound
    # the pairs of a symmetric section (modes 1-2, 4-5, 7-8) stay pairs
    assert np.all(np.abs(lam[[1, 4, 7]] - lam[[0, 3, 6]]) <= bound)


def _mutated(tmp: Path, edits: dict[int, int]) -> Path:
    w = np.fromfile(FULL, "<i4")
    for k, v in edits.items():
        w[k] = v
    path = tmp / "bad.full"
    w.tofile(path)
    return path


K_PTR = 536         # the first stiffness column: [1] [int flag] [row 1] [1], then its value


@pytest.mark.parametrize("edits,message", [
    ({0: 99}, r"standard header: an Ansys binary file starts with a 100-word record \(either "
              r"byte order\), got 99"),
    ({2: 12}, r"standard header: file number 12, not 4"),
    ({HEADER: -3}, r"FULL header: key -3, not -4"),
    ({HEADER + 13: 1}, r"FULL header keyuns: unsymmetric matrices are not read, got 1"),
    ({HEADER + 14: 3}, r"FULL header extopt: layout 3 is not read"),
    ({HEADER + 20: 2}, r"FULL header ncefull: constraint equations are not read, got 2"),
    ({HEADER + 28: 500}, r"FULL header ptrDMP: a damping matrix is not read, got 500"),
    ({HEADER + 7: 2}, r"FULL header: 321 nodes of 2 degrees of freedom do not make the 963"),
    ({208: 7}, r"DOF labels: 3 labels from 1 to 6 \(UX-ROTZ\) are read, got \[7, 2, 3\]"),
    ({HEADER + 8: 2**31 - 1}, r"K terms: 2147483647 terms declared, more than the file's "
                              r"212992 words can hold"),
    ({HEADER + 8: 39022}, r"K column 963: more terms than the 39022 the header declares"),
    ({HEADER + 5: 30}, r"K column \d+ rows: \d+ rows, more than the longest column of the "
                       r"header \(wfmax 30\)"),
    ({K_PTR + 2: 964}, r"K column 1 rows: row 964 is outside 1..963"),
    ({K_PTR + 5: 0x40000000}, r"K column 1 values: record at word 540 has flags 0x40000000, "
                              r"not double-precision reals"),
    ({K_PTR + 6: 0, K_PTR + 7: 0x7FF80000}, r"K column 1: row 1 holds nan, not a finite"),
    ({K_PTR + 3: 7}, r"K column 1 rows: record at word 536 declares 1 words but ends with "
                     r"the length 7: wrong record length"),
])
def test_malformed_files_are_refused(tmp_path: Path, edits: dict[int, int],
                                     message: str) -> None:
    path = _mutated(tmp_path, edits)
    with pytest.raises(CaseError, match=r"^bad\.full: " + message):
        read_full(path, path.name)


def test_truncated_file(tmp_path: Path) -> None:
    path = tmp_path / "cut.full"
    path.write_bytes(FULL.read_bytes()[:4 * 130000])
    with pytest.raises(CaseError, match=r"^cut\.full: DOF table: record at word 130136 lies "
                                        r"beyond the end of the file \(130000 words\)"):
        read_full(path, path.name)


def test_a_term_given_twice(tmp_path: Path) -> None:
    """The first column of two rows or more with its first row made equal to its second."""
    w = np.fromfile(FULL, "<i4")
    pos, col = K_PTR, 1
    while w[pos] < 2:                    # skip a column: its rows and its values records
        pos += int(w[pos]) + 3
        pos += int(w[pos]) + 3
        col += 1
    w[pos + 2] = w[pos + 3]
    path = tmp_path / "twice.full"
    w.tofile(path)
    with pytest.raises(CaseError, match=rf"^twice\.full: K column {col}: term \(\d+, "
                                        r"\d+\) is given twice"):
        read_full(path, path.name)


@pytest.mark.parametrize("sub,message", [
    ("M: MASS, K: K", r"substructures\.part\.M: an Ansys FULL file holds the matrices K and M "
                      r"only: M of part\.full must be 'M'"),
    ("M: M, K: K, C: C", r"substructures\.part\.C: an Ansys FULL file holds the matrices K "
                         r"and M only, not C"),
    ("M: M, K: K, dofs: [[1, '123']]", r"substructures\.part\.dofs: part\.full is an Ansys "
                                       r"FULL file: the DOF map is that of its equations"),
    ("M: M, K: K, dofs: {key: DOFS}", r"substructures\.part\.file: part\.full is an Ansys FULL "
                                      r"file: it holds K and M with their DOF map, not DOFS"),
])
def test_bad_combinations(tmp_path: Path, sub: str, message: str) -> None:
    with pytest.raises(CaseError, match=message):
        load_case(_case(tmp_path, sub, 2))
