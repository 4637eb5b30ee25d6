"""OP4 files: every layout the writer makes read back bit for bit, pyyeti's files and ours read
alike by both readers (when pyyeti is installed), and damaged files refused in one line naming
the file, the matrix and the problem."""

from __future__ import annotations

import itertools
import re
import struct
import warnings
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from substruct.case.op4 import Op4Error, op4_names, read_op4
from substruct.io.op4 import write_op4


def _matrices(exponents: float = 200) -> dict:
    rng = np.random.default_rng(1)
    # exponents of 1, 2 and 3 digits
    A = rng.standard_normal((7, 5)) * np.logspace(-exponents, exponents, 5)
    A[2:4, 1] = 0  # a gap inside a column: two sparse strings
    A[:, 3] = 0  # an empty column: left out
    A[0, 0] = 0
    C = rng.standard_normal((4, 6)) + 1j * rng.standard_normal((4, 6))
    C[1, 2] = 0
    B = rng.standard_normal((5, 5))
    return {"A": A, "SYM": B @ B.T, "C": C,
            "SP": sp.random(9, 4, density=0.4, random_state=2, format="csc")}


def _decimal(x: np.ndarray, digits: int) -> np.ndarray:
    """The numbers of ``x`` as text with ``digits`` after the point, read back as float64."""
    def one(v: float) -> float:
        return float(f"{v:.{digits}E}")
    if np.iscomplexobj(x):
        return np.vectorize(lambda z: one(z.real) + 1j * one(z.imag))(x).astype(complex)
    return np.vectorize(one)(x).astype(float)


LAYOUTS = [(False, "<", 4)] + [(True, o, i) for o in "<>" for i in (4, 8)]


@pytest.mark.parametrize("binary,order,isz", LAYOUTS)
@pytest.mark.parametrize("storage", ["dense", "sparse", "bigmat"])
@pytest.mark.parametrize("precision", ["double", "single"])
def test_round_trip_bit_for_bit(tmp_path: Path, binary: bool, order: str, isz: int,
                                storage: str, precision: str) -> None:
    mats = _matrices()
    if precision == "single":  # float32's range
        mats = {k: v for k, v in mats.items() if k != "A"}
    path = tmp_path / "m.op4"
    write_op4(path, mats, binary=binary, order=order, int_bytes=isz, storage=storage,
              precision=precision)
    got = read_op4(path)
    assert list(got) == list(mats)
    for name, want in mats.items():
        want = want.toarray() if sp.issparse(want) else want
        if precision == "single":  # the file holds the float32 values, read exactly
            want = want.astype(np.complex64 if np.iscomplexobj(want) else np.float32)
            if not binary:  # ... as the 10 significant digits written, kept in float64
                want = _decimal(want, 9)
        m = got[name]
        assert m.storage == storage and (m.rows, m.cols) == want.shape
        assert m.type == (4 if np.iscomplexobj(want) else 2) - (precision == "single")
        assert np.array_equal(m.dense(), want)
    assert got["SYM"].form == 6 and got["C"].form == 2
    assert op4_names(path) == list(mats)


def test_text_at_fewer_digits_rounds_to_what_was_written(tmp_path: Path) -> None:
    """Text with 8 digits after the point: each number within half a unit of the 9th
    significant digit (the precision written), and exactly the decimal printed."""
    A = np.random.default_rng(3).standard_normal((6, 6))
    write_op4(tmp_path / "a.op4", {"A": A}, digits=8)
    got = read_op4(tmp_path / "a.op4")["A"].dense()
    assert np.all(np.abs(got - A) <= 0.5e-8 * np.abs(A) * (1 + 1e-12))
    assert np.array_equal(got, np.array([[float(f"{x:.8E}") for x in r] for r in A]))


def test_names_selected_without_regard_to_case(tmp_path: Path) -> None:
    mats = _matrices()
    write_op4(tmp_path / "m.op4", mats, binary=True)
    got = read_op4(tmp_path / "m.op4", ["sym", "c"])
    assert sorted(got) == ["C", "SYM"]
    with pytest.raises(Op4Error, match=r"m\.op4: no matrix 'KAA' \(it has A, SYM, C, SP\)"):
        read_op4(tmp_path / "m.op4", ["KAA"])


def test_pyyeti_reads_ours_and_we_read_pyyetis(tmp_path: Path) -> None:
    """An independent reader and writer (pyyeti's): both ways, every storage, both byte
    orders, bit for bit.  (pyyeti's text numbers overflow their width at exponents of three
    digits, so the matrices here stay within 1e+-99.)"""
    op4 = pytest.importorskip("pyyeti.nastran.op4")
    mats = {k: v for k, v in _matrices(50).items() if k != "SP"}
    storages = {"dense": "dense", "nonbigmat": "sparse", "bigmat": "bigmat"}
    for binary, theirs, order in itertools.product([False, True], storages, "<>"):
        if not binary and order == ">":
            continue
        op4.write(str(tmp_path / "y.op4"), mats, binary=binary, sparse=theirs, endian=order)
        got = read_op4(tmp_path / "y.op4")
        for name, want in mats.items():
            assert np.array_equal(got[name].dense(), want), (binary, theirs, name)
        write_op4(tmp_path / "z.op4", mats, binary=binary, storage=storages[theirs],
                  order=order)
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            back = op4.read(str(tmp_path / "z.op4"), sparse=False)
        for name, want in mats.items():
            assert np.array_equal(back[name.lower()], want), (binary, theirs, name)


# ------------------------------------------------------------------------- bad files


def _binary(tmp_path: Path) -> bytes:
    write_op4(tmp_path / "k.op4", {"KAA": np.diag([1.0, 2.0, 3.0])}, binary=True)
    return (tmp_path / "k.op4").read_bytes()


def _refused(tmp_path: Path, data: bytes, pattern: str, name: str = "bad.op4") -> None:
    path = tmp_path / name
    path.write_bytes(data)
    with pytest.raises(Op4Error) as err:
        read_op4(path)
    text = str(err.value)
    assert "\n" not in text and text.startswith(f"{name}: ")
    assert re.search(pattern, text), text


def test_truncated_binary(tmp_path: Path) -> None:
    data = _binary(tmp_path)
    for cut in (len(data) - 3, len(data) - 24, 40, 30):
        _refused(tmp_path, data[:cut], r"truncated")
    _refused(tmp_path, data[:-3], r"matrix 'KAA': truncated")
    _refused(tmp_path, data[:30], r"bad\.op4: matrix header: truncated")


def test_huge_declared_size_refused_before_allocating(tmp_path: Path) -> None:
    head = struct.pack("<5i8si", 24, 900_000, 900_000, 2, 2, b"KAA     ", 24)
    col = struct.pack("<4i2di", 20, 1, 1, 2, 1.0, 0.0, 20)[:-8] + struct.pack("<i", 20)
    col = struct.pack("<4id", 20, 1, 1, 2, 1.0) + struct.pack("<i", 20)
    _refused(tmp_path, head + col, r"matrix 'KAA' \(900000 x 900000, dense\) would need "
             r"about 6\.48 TB of memory, more than the 4 GB allowed")
    head = struct.pack("<5i8si", 24, 5, 2_000_000, 2, 2, b"KAA     ", 24)
    _refused(tmp_path, head, r"matrix 'KAA': 2000000 rows declared; 1 to 1000000")


def test_wrong_record_lengths(tmp_path: Path) -> None:
    data = bytearray(_binary(tmp_path))
    # the first column record starts after the 32-byte header: its length 12 + 8 = 20
    bad = bytearray(data)
    bad[32:36] = struct.pack("<i", 28)
    bad[32 + 4 + 28:32 + 8 + 28] = struct.pack("<i", 28)
    _refused(tmp_path, bytes(bad), r"matrix 'KAA': wrong record length: column 1 declares "
             r"2 words \(20 bytes\) in a record of 28 bytes")
    bad = bytearray(data)
    bad[56:60] = struct.pack("<i", 21)  # the closing marker of that record
    _refused(tmp_path, bytes(bad), r"starts with 20 and ends with 21")
    bad = bytearray(data)
    bad[0:4] = bad[28:32] = struct.pack("<i", 28)
    _refused(tmp_path, bytes(bad), r"not an OP4 file")
    bad = bytearray(data)
    bad[32:36] = struct.pack("<i", 10 ** 9)
    _refused(tmp_path, bytes(bad), r"a record of 1000000000 bytes at byte 32, but \d+ are left")


def test_bad_codes_and_columns(tmp_path: Path) -> None:
    def head(cols: int, rows: int, form: int, mtype: int) -> bytes:
        return struct.pack("<5i8si", 24, cols, rows, form, mtype, b"X       ", 24)

    def col(icol: int, irow: int, values: list[float]) -> bytes:
        n = 12 + 8 * len(values)
        return struct.pack(f"<4i{len(values)}di", n, icol, irow, 2 * len(values), *values, n)

    _refused(tmp_path, head(2, 2, 3, 2), r"matrix 'X': form 3 is not read")
    _refused(tmp_path, head(2, 2, 1, 7), r"matrix 'X': type 7 is not 1-4")
    _refused(tmp_path, head(2, 3, 1, 2), r"form 1 \(square\) but 3 rows and 2 columns")
    _refused(tmp_path, head(2, 2, 2, 2) + col(2, 1, [1]) + col(1, 1, [1]),
             r"column 1 after column 2")
    _refused(tmp_path, head(2, 2, 2, 2) + col(1, 2, [1, 2]) + col(3, 1, [1]),
             r"column 1 covers rows 2 to 3, outside 1 to 2")
    _refused(tmp_path, head(2, 2, 2, 4) + col(1, 1, [1, 2, 3]) + col(3, 1, [1]),
             r"holds 3 numbers, not pairs of a complex matrix")


def test_bad_text(tmp_path: Path) -> None:
    write_op4(tmp_path / "t.op4", {"KAA": np.eye(3), "MAA": np.eye(3)}, storage="sparse")
    lines = (tmp_path / "t.op4").read_text().splitlines(keepends=True)
    _refused(tmp_path, "".join(lines[:-3]).encode(), r"matrix 'MAA': truncated")
    bad = list(lines)
    bad[3] = bad[3].replace("E", "Q")
    _refused(tmp_path, "".join(bad).encode(), r"matrix 'KAA': line 4: expected 1 numbers")
    _refused(tmp_path, b"       1" * 200 + b"\n", r"line 1 is longer than 1024")
    sparse_string = [k for k, ln in enumerate(lines) if ln.strip().isdigit()][0]
    bad = list(lines)
    bad[sparse_string] = f"{(9 << 16) + 1}\n"  # a string of 8 words in a column of 3
    _refused(tmp_path, "".join(bad).encode(), r"string 1 declares 8 words, not a positive "
             r"multiple of 2 within the column's 3 words")


def test_text_column_header_with_more_than_its_integers(tmp_path: Path) -> None:
    """A column header is three integers of 8 characters: a fourth, or a number wider than
    its field (a count of 12 digits), was cut off and the rest read as if it were not there."""
    write_op4(tmp_path / "t.op4", {"KAA": 2 * np.eye(2)})
    lines = (tmp_path / "t.op4").read_text().splitlines(keepends=True)
    assert lines[1] == f"{1:8}{1:8}{1:8}\n"  # the first column: 1 number from row 1
    for tail in ("       7", "9999"):
        bad = list(lines)
        bad[1] = lines[1].rstrip("\n") + tail + "\n"
        _refused(tmp_path, "".join(bad).encode(), r"matrix 'KAA': line 2: expected 3 integers "
                 r"of 8 characters, but the line holds more")


def test_text_count_the_file_does_not_hold_allocates_nothing(tmp_path: Path) -> None:
    """A dense column declaring 99,999,999 numbers in a file of a few lines: refused as
    truncated without the 800 MB array of the declared count being allocated first."""
    import tracemalloc

    write_op4(tmp_path / "t.op4", {"KAA": 2 * np.eye(2)})
    lines = (tmp_path / "t.op4").read_text().splitlines(keepends=True)
    lines[1] = f"{1:8}{1:8}{99_999_999:8}\n"
    tracemalloc.start()
    try:
        _refused(tmp_path, "".join(lines).encode(), r"matrix 'KAA': line 3: expected 3 numbers")
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 10_000_000, peak


def test_limit_refuses_before_reading(tmp_path: Path) -> None:
    write_op4(tmp_path / "k.op4", {"KAA": np.ones((100, 100))}, binary=True)
    with pytest.raises(Op4Error, match=r"k\.op4: matrix 'KAA' \(100 x 100, dense\) would "
                       r"need about 0\.08 MB"):
        read_op4(tmp_path / "k.op4", limit=50_000)


# ------------------------------------------------------- files of other writers (pyyeti's tests)

DATA = Path(__file__).parent / "data" / "op4"


def test_text_single_precision_keeps_the_digits_written(tmp_path: Path) -> None:
    """A type 1 (or 3) text matrix holds the decimals written; they are read as float64, not
    rounded to float32.  Text written at 17 digits from a binary single file reads as that
    file, bit for bit."""
    text = ("       2       2       6       1KAA     1P,3E23.16\n"
            "       1       1       1\n 1.2345678901234567E+00\n"
            "       2       2       1\n 9.8765432109876543E-01\n"
            "       3       1       1\n 1.0000000000000000E+00\n"
            "       1       1       2       3C        1P,3E23.16\n"
            "       1       1       2\n 1.2345678901234567E+00-2.2222222222222222E-01\n"
            "       2       1       1\n 1.0000000000000000E+00\n")
    (tmp_path / "t.op4").write_text(text)
    got = read_op4(tmp_path / "t.op4")
    assert got["KAA"].type == 1 and got["C"].type == 3
    assert got["KAA"].dense()[0, 0] == 1.2345678901234567  # not 1.2345678806304932
    assert got["KAA"].dense()[1, 1] == 0.98765432109876543
    assert got["C"].dense()[0, 0] == 1.2345678901234567 - 0.22222222222222222j

    A = np.random.default_rng(5).standard_normal((4, 3))
    write_op4(tmp_path / "b.op4", {"A": A}, binary=True, precision="single")
    write_op4(tmp_path / "a.op4", {"A": A}, binary=False, precision="single", digits=16)
    binary, ascii_ = read_op4(tmp_path / "b.op4")["A"], read_op4(tmp_path / "a.op4")["A"]
    assert binary.type == ascii_.type == 1
    assert np.array_equal(ascii_.dense(), binary.dense())
    assert np.array_equal(binary.dense(), A.astype(np.float32))


def test_text_closing_column_counted_in_words() -> None:
    """Nastran's text files declare the closing column's one number as 2 words for a double
    matrix (``double_nonbigmat_ascii.op4.other``, ``cdbin_ascii_sparse_bigmat.op4``) or as
    1: both are read, and give the numbers of the binary files of the same matrices to the
    digits written."""
    a = read_op4(DATA / "double_nonbigmat_ascii.op4.other")
    b = read_op4(DATA / "double_nonbigmat_be.op4.other")
    assert list(a) == list(b) == ["KAA", "MAA"]
    for k in a:
        assert a[k].type == 2 and a[k].storage == "sparse" and a[k].dense().shape == (16, 16)
        A, B = a[k].dense(), b[k].dense()
        assert np.array_equal(A != 0, B != 0)
        assert np.all(np.abs(A - B) <= 0.5e-9 * np.abs(B))  # 1P,5E16.9: 10 digits
    assert a["KAA"].dense()[0, 0] == 2.136230469e-03 and b["KAA"].dense()[0, 0] == 0.00213623046875
    assert a["MAA"].dense()[6, 6] == 1.0

    c = read_op4(DATA / "cdbin_ascii_sparse_bigmat.op4")
    d = read_op4(DATA / "cdbin.op4")
    assert list(c) == list(d) == ["C1", "C2", "C3", "C4", "C5"]
    for k in c:
        C, D = c[k].dense(), d[k].dense()
        assert c[k].type == 4 and C.shape == D.shape
        assert np.all(np.abs(C - D) <= 0.5e-15 * np.abs(D) + 1e-300)  # 1P,3E22.15
    assert c["C1"].storage == "bigmat" and c["C1"].dense().shape == (5, 6)
    assert c["C1"].dense()[0, 0] == 1.233140833282189 - 1.364201536870681j
    assert c["C3"].dense()[0, 0] == 3 + 7j


def test_repeated_names_refused_only_when_asked_for() -> None:
    """A nas2cam file writes ``SE_START`` once per superelement: the file is read, and only a
    name asked for that is written more than once is refused, naming its occurrences."""
    path = DATA / "inboard_nas2cam.op4"
    assert op4_names(path) == ["SE_START", "LAMBDA", "MAA", "KAA", "SE_START", "LOOP_END"]
    got = read_op4(path, ["maa", "KAA", "lambda"])
    assert sorted(got) == ["KAA", "LAMBDA", "MAA"]
    K, M, lam = got["KAA"].dense(), got["MAA"].dense(), got["LAMBDA"].dense()
    assert K.shape == M.shape == (84, 84) and lam.shape == (60, 1)
    assert K[0, 0] == 434961.12333316356 and K[0, 1] == 1584010.9166389694
    assert M[0, 0] == 6.354653044080377
    assert lam[0, 0] == 1483.1597900390625
    assert np.abs(K - K.T).max() <= 1e-10 * np.abs(K).max()
    for names in (["KAA", "se_start"], None):
        with pytest.raises(Op4Error, match=r"^inboard_nas2cam\.op4: matrix 'SE_START' is "
                           r"written 2 times \(matrices 1 and 5 of the file\)"):
            read_op4(path, names)
