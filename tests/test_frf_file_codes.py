"""FRF files read by substruct: UFF 58 header codes honoured (receptance, mobility and
accelerance turned into receptances exactly; real ordinates) or refused in one line naming the
file, the dataset, the record and the value (time responses, other abscissas, other
ordinates, declared counts that disagree with the data, duplicates that differ, nodes not in
the file's 15); sizes checked before anything is allocated (UFF and NPZ); the FRF checks of a
case (grids, channel names) made before the model is built."""

from __future__ import annotations

import io
import struct
import time
import tracemalloc
import zipfile

import numpy as np
import pytest

from substruct.case.frf_files import read_frf_file
from substruct.case.loader import CaseError, load_case
from substruct.case.npz_files import read_npz
from substruct.case.transient import read_table
from substruct.io.uff import uff15_set, uff58_sets, write_uff
from substruct.run.runner import build_model, run_case
from uff_plain import ascii58

F = np.array([0.5, 1.25, 3.0, 7.5])  # Hz, exact in E13.5
W = 2 * np.pi * F
H = np.array([1e-3 - 2e-4j, -4e-4 + 1e-5j, 2.5e-5 - 3e-6j, 1e-6 + 7e-7j])


def _file(tmp_path, *datasets, name="f.uff"):
    path = tmp_path / name
    path.write_text("".join(datasets))
    return path


def _refused(path, *fragments):
    with pytest.raises(ValueError) as err:
        read_frf_file(path)
    message = str(err.value)
    assert "\n" not in message and message.startswith(path.name)
    for f in fragments:
        assert f in message, message
    return message


def test_receptance_mobility_and_accelerance_are_read_as_receptances(tmp_path):
    """``V = i omega H`` and ``A = -omega^2 H`` written as velocity (11) and acceleration (12)
    over force come back as ``H``: to the 13 digits of E20.12, the conversion adding one or two
    roundings."""
    for code, factor in ((8, 1), (11, 1j * W), (12, -W ** 2)):
        path = _file(tmp_path, ascii58(F, H * factor, numerator=code), name=f"{code}.uff")
        omega, labels, Y = read_frf_file(path)
        assert labels == ["1:x"]
        np.testing.assert_allclose(omega, W, rtol=1e-15)
        np.testing.assert_allclose(Y[:, 0, 0], H, rtol=5e-12, atol=0)


def test_real_ordinate_is_a_receptance_without_imaginary_part(tmp_path):
    path = _file(tmp_path, ascii58(F, H.real, real=True))
    Y = read_frf_file(path)[2][:, 0, 0]
    assert np.all(Y.imag == 0)
    np.testing.assert_allclose(Y.real, H.real, rtol=5e-12)


@pytest.mark.parametrize("codes, fragments", [
    ({"func_type": 1}, ["record 6 field 1, function type 1 (time response)",
                        "only 4 (frequency response function)"]),
    ({"func_type": 0}, ["function type 0 (general or unknown)"]),
    ({"load_case": 3}, ["record 6 field 4, load case 3"]),
    ({"abscissa": 17}, ["record 8 field 1, abscissa data type 17"]),
    ({"units": "rad/s"}, ["record 8 field 6, abscissa units 'rad/s'"]),
    ({"numerator": 2}, ["records 9-10 field 1, ordinate 2 over 13"]),
    ({"denominator": 9}, ["ordinate 8 over 9"]),
    ({"num_pts": 5}, ["record 12 holds 12 values, record 7 declares 15"]),
    ({"num_pts": 3}, ["record 12 holds more values than the 9 that record 7 declares"]),
    ({"rsp": (1, 0)}, ["record 6 field 7 (response direction): UFF direction 0 is not one "
                       "of 1..6"]),
])
def test_header_codes_refused(tmp_path, codes, fragments):
    path = _file(tmp_path, ascii58(F, H, **codes))
    message = _refused(path, "dataset 1 (58, line 1)", *fragments)
    assert len(message) < 300


def test_accelerance_at_zero_frequency_is_refused(tmp_path):
    f = np.array([0.0, 1.0])
    _refused(_file(tmp_path, ascii58(f, H[:2], numerator=12)),
             "record 12, frequency 0 Hz", "needs omega > 0")


def test_duplicates_identical_accepted_different_refused(tmp_path):
    one = read_frf_file(_file(tmp_path, ascii58(F, H), name="one.uff"))
    two = read_frf_file(_file(tmp_path, ascii58(F, H), ascii58(F, H), name="two.uff"))
    assert two[1] == one[1]
    np.testing.assert_array_equal(two[2], one[2])
    # the same function through a flipped pair of directions (-x/-x) is the same values
    flipped = _file(tmp_path, ascii58(F, H), ascii58(F, H, rsp=(1, -1), ref=(1, -1)),
                    name="flip.uff")
    np.testing.assert_array_equal(read_frf_file(flipped)[2], one[2])
    _refused(_file(tmp_path, ascii58(F, H), ascii58(F, 2 * H), name="bad.uff"),
             "dataset 2 (58, line 19)", "the function 1:x/1:x is also in dataset 1",
             "with other values")
    _refused(_file(tmp_path, ascii58(F, H), ascii58(F, H, rsp=(1, -1)), name="sign.uff"),
             "with other values")


def test_nodes_must_be_those_of_the_files_15(tmp_path):
    path = write_uff(tmp_path / "n.uff", [uff15_set(2)])
    with open(path, "a") as fh:
        fh.write(ascii58(F, H, rsp=(3, 1), ref=(3, 1)))
    _refused(path, "record 6 field 6 (response node) 3 is not a node of the file's datasets "
             "15/2411")
    ok = write_uff(tmp_path / "ok.uff", [uff15_set(3)])
    with open(ok, "a") as fh:
        fh.write(ascii58(F, H, rsp=(3, 1), ref=(3, 1)))
    assert read_frf_file(ok)[1] == ["3:x"]


def test_binary_58_counts(tmp_path):
    """58b: substruct's own files (the byte count of record 12 in the id line), pyuff's
    (which writes num_pts * 8 there) are read exactly; any other count is refused."""
    labels = ["1:x", "2:y"]
    Y = np.stack([H, 2 * H, 2 * H, 3 * H], axis=1).reshape(4, 2, 2)
    path = write_uff(tmp_path / "s.uff", uff58_sets(W, Y, labels, labels))
    np.testing.assert_array_equal(read_frf_file(path)[2], Y)
    import pyuff

    d = pyuff.prepare_58(binary=1, func_type=4, rsp_node=1, rsp_dir=1, ref_node=1, ref_dir=1,
                         data=H, x=F, abscissa_spacing=0, abscissa_spec_data_type=18,
                         ordinate_spec_data_type=8, orddenom_spec_data_type=13)
    pyuff.UFF(str(tmp_path / "p.uff")).write_sets([d], mode="add")
    assert b"          32     0" in (tmp_path / "p.uff").read_bytes()[:100]  # 4 points * 8
    np.testing.assert_array_equal(read_frf_file(tmp_path / "p.uff")[2][:, 0, 0], H)
    raw = (tmp_path / "p.uff").read_bytes().replace(b"          32     0",
                                                    b"          40     0", 1)
    (tmp_path / "q.uff").write_bytes(raw)
    _refused(tmp_path / "q.uff", "id line field 6 declares 40 bytes of data, record 7 96")
    cut = (tmp_path / "p.uff").read_bytes()
    (tmp_path / "cut.uff").write_bytes(cut[:-30])
    _refused(tmp_path / "cut.uff", "record 7 declares 4 points (96 bytes or more) but 73 bytes "
             "of the file are left")


def test_an_8m_point_declaration_is_refused_before_reading(tmp_path):
    """The header says 8,000,000 points: refused from record 7, with the rest of the file
    never read (here there is none)."""
    text = ascii58(F, H, num_pts=8_000_000)
    message = _refused(_file(tmp_path, text), "record 7 field 2 declares 8000000 points; 1 to "
                       "1000000 are read")
    assert "record 12" not in message
    big = _file(tmp_path, ascii58(F, H, num_pts=1_000_000), name="lie.uff")
    _refused(big, "record 7 declares 1000000 points", "bytes of the file are left")


def test_a_file_with_more_data_than_declared_is_not_read_whole(tmp_path):
    """200,000 data lines (10.6 MB) after a header declaring 4 points: refused at the fifth,
    with a peak of Python memory far below the file's size."""
    f = np.linspace(1.0, 2.0, 200_000)
    path = _file(tmp_path, ascii58(f, np.ones(f.size), num_pts=4))
    assert path.stat().st_size > 10_000_000
    tracemalloc.start()
    _refused(path, "record 12 holds more values than the 12 that record 7 declares, at line 18")
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 1_000_000


def test_a_line_without_end_is_refused(tmp_path):
    path = tmp_path / "long.uff"
    path.write_bytes(b"    -1\n    58\n" + b"x" * 5_000_000)
    _refused(path, "line 3 is longer than 1024 characters")


# ----------------------------------------------------------------------------------- NPZ


def _member(name, shape, dtype="<c16", payload=b""):
    """An .npy member: a header declaring ``shape`` and ``payload`` bytes after it."""
    head = io.BytesIO()
    np.lib.format.write_array_header_1_0(head, {"descr": dtype, "fortran_order": False,
                                                "shape": shape})
    return name, head.getvalue() + payload


def _npz(path, *members, deflate=True):
    how = zipfile.ZIP_DEFLATED if deflate else zipfile.ZIP_STORED
    with zipfile.ZipFile(path, "w", compression=how) as z:
        for name, data in members:
            z.writestr(name, data)
    return path


def _frf_npz(tmp_path, H_member, name="h.npz"):
    labels = np.array(["1:x", "2:x"])
    buf = io.BytesIO()
    np.lib.format.write_array(buf, labels)
    w = io.BytesIO()
    np.lib.format.write_array(w, W)
    return _npz(tmp_path / name, H_member, ("labels.npy", buf.getvalue()),
                ("omega.npy", w.getvalue()))


def test_npz_declaring_6_gb_is_refused_from_its_header(tmp_path):
    """H declared (375000, 32, 32) complex: 6.1 GB (12 GB with its copy); the archive is a few
    hundred bytes.  Refused in one line before anything is allocated."""
    path = _frf_npz(tmp_path, _member("H.npy", (375_000, 32, 32)))
    start = time.perf_counter()
    tracemalloc.start()
    _refused(path, "the arrays (H 375000 x 32 x 32 complex128",
             "would need about 12.3 GB of memory, more than the 4 GB allowed")
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert time.perf_counter() - start < 2 and peak < 10_000_000


def test_npz_zip_bomb_and_lying_members_are_refused(tmp_path):
    # a member inflating past its header (2 x 2 declared, 64 MB of zeros deflated to 64 kB)
    bomb = _frf_npz(tmp_path, _member("H.npy", (4, 2, 2), payload=bytes(64 << 20)))
    assert bomb.stat().st_size < 200_000
    _refused(bomb, "member 'H' declares a 4 x 2 x 2 array of complex128 (256 bytes) but the "
             "archive says it holds 67108864")
    # a crafted directory entry (uncompressed size raised in both headers): ratio > deflate's
    path = _frf_npz(tmp_path, _member("H.npy", (4, 2, 2), payload=bytes(256)), name="c.npz")
    raw = bytearray(path.read_bytes())
    for sig, off in ((b"PK\x03\x04", 22), (b"PK\x01\x02", 24)):
        at = raw.index(sig)
        raw[at + off:at + off + 4] = struct.pack("<I", 0xFFFF0000)
    path.write_bytes(bytes(raw))
    _refused(path, "member 'H' inflates", "a ratio above the 1100 deflate allows")
    # object arrays, and strings where numbers belong
    _refused(_frf_npz(tmp_path, _member("H.npy", (4, 2, 2), dtype="|O"), name="o.npz"),
             "member 'H' holds object entries, not numbers or strings")
    _refused(_frf_npz(tmp_path, _member("H.npy", (4, 2, 2), dtype="<U3",
                                        payload=bytes(16 * 12)), name="u.npz"),
             "H holds <U3 entries, not numbers")
    _refused(_npz(tmp_path / "empty.npz"), "needs arrays H, labels and omega (or freq_hz); "
             "it has none")


def test_npz_reader_keeps_exact_values_and_the_transient_table_uses_it(tmp_path):
    t = np.linspace(0, 1, 11)
    np.savez(tmp_path / "ok.npz", t=t, value=t ** 2)
    tt, vv = read_table(tmp_path / "ok.npz")
    np.testing.assert_array_equal(tt, t)
    np.testing.assert_array_equal(vv, t ** 2)
    np.savez(tmp_path / "c.npz", t=t, value=t + 1j)
    with pytest.raises(ValueError, match="member 'value' holds complex128 entries, not real"):
        read_table(tmp_path / "c.npz")
    big = _npz(tmp_path / "big.npz", _member("t.npy", (10 ** 9,), "<f8"),
               _member("value.npy", (10 ** 9,), "<f8"))
    with pytest.raises(ValueError, match="has 1000000000 entries, at most 1000000 expected"):
        read_table(big)
    with pytest.raises(ValueError, match=r"would need about 2.4 GB of memory, more than the "
                       r"1 GB allowed"):
        read_npz(_npz(tmp_path / "m.npz", _member("a.npy", (10 ** 8,), "<f8")), ["a"],
                 {"a": np.complex128}, limit=1e9)


# ---------------------------------------------------------------- checks before computing


CASE = """
name: early
substructures:
  - {name: P, type: matrices, M: [[1.0]], K: [[1000.0]]}
  - {name: meas, type: frf, file: part.npz}
connections:
  - [CONN, meas@1:x]
analysis:
  frf: {omega: GRID, inputs: [INPUT], outputs: [meas@2:x]}
"""


@pytest.mark.parametrize("edit, fragment", [
    ({"GRID": "[1.0, 2.0, 3.0, 4.0]"}, "substructures.meas.interpolate: the frequency grid of "
                                       "meas differs from analysis.frf.omega (3 vs 4"),
    ({"INPUT": "meas@9:x"}, "analysis.frf.inputs[0]: meas has no coordinate '9:x'"),
    ({"CONN": "P@q9"}, "connections[0][0]: 'P' has no coordinate 'q9'"),
    ({"INPUT": "P@q7"}, "analysis.frf.inputs[0]: 'P' has no coordinate 'q7'"),
    ({"GRID": "{start: 0.5, stop: 3, num: 6}", "file: part.npz": "file: part.npz, "
      "interpolate: linear"}, "meas covers 1 to 3 rad/s, not the grid of analysis.frf.omega"),
])
def test_frf_checks_run_before_the_model_is_built(tmp_path, monkeypatch, edit, fragment):
    """A typo or a grid that does not fit is reported before any assembly or sweep."""
    Y = np.zeros((3, 2, 2), complex)
    Y[:, 0, 0], Y[:, 1, 1], Y[:, 0, 1], Y[:, 1, 0] = 1e-3, 2e-3, 1e-4, 1e-4
    np.savez(tmp_path / "part.npz", H=Y, labels=np.array(["1:x", "2:x"]),
             omega=np.array([1.0, 2.0, 3.0]))
    text = CASE
    for k, v in {"GRID": "[1.0, 2.0, 3.0]", "INPUT": "meas@2:x", "CONN": "P@q1",
                 **edit}.items():
        text = text.replace(k, v)
    (tmp_path / "c.yaml").write_text(text)
    import substruct.builder.frf_parts as frf_parts
    import substruct.run.frf_route as frf_route

    def computed(*args, **kwargs):
        raise AssertionError("the model was built or swept before the check")

    monkeypatch.setattr(frf_parts, "assemble_case", computed)
    monkeypatch.setattr(frf_route, "frf_result", computed)
    with pytest.raises(CaseError) as err:
        case = load_case(tmp_path / "c.yaml")
        run_case(case, model=build_model(case))
    assert fragment in str(err.value), str(err.value)
