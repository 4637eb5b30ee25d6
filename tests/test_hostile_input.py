"""Hostile input that the bad-case corpus cannot hold: FIFOs, devices, huge and inflating files,
and the numeric validation itself.

Every refusal is one line (a :class:`CaseError` in-process, exit code 2 and one line on stderr
through the command line) that comes before anything large is read or allocated, and fast.
"""

from __future__ import annotations

import io
import os
import struct
import subprocess
import sys
import time
import zipfile
import zlib
from pathlib import Path

import numpy as np
import pytest

from substruct import cli
from substruct.case import mesh_files
from substruct.case.errors import CaseError, show_value
from substruct.case.expressions import ExpressionError, compile_expression, scalar
from substruct.case.loader import load_case, parse_case
from substruct.case.mesh_files import MeshFileError, mesh_file_problem, read_mesh_file
from substruct.case.numbers import BigNumber, array_problem, digits_problem, number_problem
from substruct.case.yaml_io import apply_overrides, load_yaml

ROOT = Path(__file__).resolve().parent.parent
THREE = (ROOT / "cases" / "three_dof_frf.yaml").read_text(encoding="utf-8")
SOLID = """\
name: solid_case
substructures:
  - {name: beam, type: solid, mesh: MESH, E: 2.1e11, nu: 0.3, rho: 7850}
analysis:
  modes: {count: 4}
"""
MATRICES = """\
name: three_dof
substructures:
  - name: P
    type: matrices
    M: [[1, 0, 0], [0, 2, 0], [0, 0, 4]]
    K: {file: FILE}
analysis:
  frf: {omega: [2.0], inputs: [P@q1], outputs: [P@q1]}
"""


def refused(capsys, *args) -> str:
    """Run the command line; assert exit code 2 and one line; return the line."""
    start = time.perf_counter()
    code = cli.main([str(a) for a in args])
    stdout, stderr = capsys.readouterr()
    assert code == 2, stderr
    assert stdout == "" and stderr.count("\n") == 1 and "Traceback" not in stderr, stderr
    assert time.perf_counter() - start < 10
    return stderr.rstrip("\n")


def case_error(text: str, base: Path, overrides=()) -> str:
    with pytest.raises(CaseError) as info:
        parse_case(text, "case.yaml", base, overrides)
    message = str(info.value)
    assert "\n" not in message and message.isprintable()
    return message


# --------------------------------------------------------------------------- case files


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this system")
def test_a_fifo_as_case_file_is_refused_without_blocking(tmp_path, capsys):
    fifo = tmp_path / "case.yaml"
    os.mkfifo(fifo)
    line = refused(capsys, "run", fifo, "--out", tmp_path / "out")
    assert line == f"substruct: error: {fifo}: is a FIFO (named pipe), not a case file: a case " \
                   f"is read from a regular file"
    assert not (tmp_path / "out").exists()


@pytest.mark.skipif(not os.path.exists("/dev/zero"), reason="no /dev/zero")
def test_a_device_as_case_file_is_refused_before_reading(tmp_path, capsys):
    for path in (Path("/dev/zero"), tmp_path / "zero.yaml"):
        if path.parent == tmp_path:
            path.symlink_to("/dev/zero")
        line = refused(capsys, "run", path, "--out", tmp_path / "out")
        assert line == f"substruct: error: {path}: is a device, not a case file: a case is " \
                       f"read from a regular file"


@pytest.mark.skipif(not os.path.exists("/dev/stdin"), reason="no /dev/stdin")
def test_stdin_that_is_a_pipe_is_refused_in_a_real_process(tmp_path):
    """``substruct run /dev/stdin`` with a pipe that never ends: refused at once."""
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg"}
    with subprocess.Popen([sys.executable, "-m", "substruct.cli", "run", "/dev/stdin", "--out",
                           str(tmp_path / "out")], stdin=subprocess.PIPE,
                          stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=tmp_path,
                          env=env, text=True) as proc:
        try:
            out, err = proc.communicate(timeout=60)  # stdin stays open: a read would block
        except subprocess.TimeoutExpired:
            proc.kill()
            pytest.fail("substruct run /dev/stdin blocked on its input")
    assert proc.returncode == 2, err
    assert out == "" and err.count("\n") == 1
    assert err.startswith("substruct: error: /dev/stdin: is a FIFO (named pipe), not a case file")


def test_a_huge_case_file_is_refused_without_reading_it(tmp_path, capsys, monkeypatch):
    big = tmp_path / "big.yaml"
    with open(big, "wb") as f:
        f.truncate(10 ** 10)  # 10 GB that take no room
    reads = []
    real_read = os.read
    monkeypatch.setattr(os, "read", lambda fd, n: reads.append(n) or real_read(fd, n))
    line = refused(capsys, "run", big, "--out", tmp_path / "out")
    assert line == f"substruct: error: {big}: a case file of 10000000000 bytes, more than the " \
                   f"200000 bytes read (put matrices in .npz/.mtx files)"
    assert reads == []


def test_a_case_file_with_windows_line_ends_reads_like_the_original(tmp_path):
    path = tmp_path / "three.yaml"
    path.write_bytes(THREE.encode().replace(b"\n", b"\r\n"))
    case = load_case(path)
    assert case.text == THREE and case.name == "three_dof_frf"


# ----------------------------------------------------------------------- --set values


def test_an_alias_bomb_through_set_is_refused_fast_and_small(tmp_path):
    bomb = "[" + ", ".join(f"&a{k} [" + ", ".join([f"*a{k - 1}"] * 10) + "]" if k else
                           "&a0 [1, 1, 1, 1, 1, 1, 1, 1, 1, 1]" for k in range(9)) + "]"
    start = time.perf_counter()
    message = case_error(THREE, tmp_path, [f"parameters.m1={bomb}"])
    assert time.perf_counter() - start < 2
    assert message.startswith("case.yaml: --set parameters.m1: invalid YAML: aliases expand to "
                               "more than 1000000 values")


def test_set_values_are_read_like_the_file():
    data = {"a": 1}
    assert apply_overrides(data, ["a=6e6", "b=0x10"]) == ["a", "b"]
    assert data == {"a": 6e6, "b": 16}
    apply_overrides(data, ["c=" + "9" * 6000])
    assert isinstance(data["c"], BigNumber) and data["c"].digits == 6000
    with pytest.raises(CaseError, match="nested more than 20 levels deep"):
        apply_overrides({}, ["a=" + "[" * 200 + "]" * 200])
    with pytest.raises(CaseError, match="could not determine a constructor"):
        apply_overrides({}, ["a=!!python/name:os.system"])


# ----------------------------------------------------------------------- the numbers


def test_the_numeric_range():
    for ok in (0, 0.0, -0.0, 1e30, -1e30, 1e-30, -1e-30, 10 ** 29, 2.5, np.float64(3.0),
               np.int64(7)):
        assert number_problem(ok) is None, ok
    assert number_problem(True) == "must be a number, not true/false"
    for inf in (float("nan"), float("inf"), -float("inf")):
        assert number_problem(inf) == "must be a finite number"
    assert number_problem(1.0000001e30).startswith("out of range: too large")
    assert number_problem(9.9e-31).startswith("out of range: too small")
    assert number_problem(5e-324).startswith("out of range: too small")  # the least subnormal
    assert number_problem(10 ** 31).startswith("out of range: an integer of 32 digits")
    assert number_problem(-(10 ** 5000)).startswith("out of range: an integer of 5001 digits")
    assert number_problem(BigNumber("-0x" + "f" * 50)).startswith(
        "out of range: an integer of 50 digits")
    assert number_problem("1e999") is None  # text is judged where it is read


def test_big_integers_are_read_as_text_and_never_converted():
    data = load_yaml("a: " + "1" * 5000 + "\nb: 123\nc: -" + "2" * 31 + "\nd: 1e400\n", "x")
    assert isinstance(data["a"], BigNumber) and data["a"].digits == 5000
    assert data["b"] == 123 and isinstance(data["c"], BigNumber) and data["d"] == float("inf")
    assert str(data["a"]) == "111111111111111111111111...11111111 (5000 digits)"
    assert show_value(data["a"]) == str(data["a"])
    assert show_value([data["a"], 10 ** 5000]) == \
        '["111111111111111111111111...11111111 (5000 digits)", "an integer of about 50...'


def test_expressions_refuse_long_integers_before_parsing_and_values_out_of_range():
    with pytest.raises(ExpressionError, match="has 1900 digits"):
        compile_expression("x + " + "7" * 1900)
    with pytest.raises(ExpressionError, match="has 31 digits"):
        compile_expression("1" + "0" * 30 + "*x")
    # a long fraction is a precise constant, not a big number
    compile_expression("3.1415926535897932384626433832795028841971*x")
    assert digits_problem("1e0000000000000000000000000000000000001") is None
    with pytest.raises(ExpressionError, match="number '1e-40' in '1e-40\\*x': out of range"):
        compile_expression("1e-40*x")
    with pytest.raises(ExpressionError, match=r"'1e20\*1e20' = 1e\+40: out of range"):
        scalar("1e20*1e20", {})
    with pytest.raises(ExpressionError, match=r"'\(1e25\*1e25\)\*\*7' = inf: must be a finite"):
        scalar("(1e25*1e25)**7", {})
    assert scalar("1e15*1e15", {}) == pytest.approx(1e30)


def test_points_refuse_long_digit_runs_even_after_a_letter(tmp_path):
    text = THREE.replace("P@q3: 2}", "P@q" + "3" * 40 + ": 2}")
    message = case_error(text, tmp_path)
    assert "constraints.eq38.terms" in message and "has 40 digits" in message


def test_arrays_from_files():
    assert array_problem(np.eye(3) * 1e-40 + np.ones((3, 3))) is None  # rounding beside 1
    assert array_problem(np.zeros((2, 2))) is None
    assert "not finite" in array_problem(np.array([1.0, np.nan]))
    assert "magnitude 2e+31" in array_problem(np.array([1.0, -2e31]))
    assert "largest entry is of magnitude 1e-35" in array_problem(np.array([1e-35, 0.0]))


def test_messages_escape_terminal_control_characters(tmp_path):
    text = THREE.replace("units:", '"\\e]0;owned\\a\\e[2J\\u202e": 1\nunits:')
    message = case_error(text, tmp_path)
    assert "\x1b" not in message and "\u202e" not in message
    assert message.startswith("case.yaml: '\\x1b]0;owned\\x07\\x1b[2J\\u202e': unknown key")


# ------------------------------------------------------------------------ matrix files


def test_a_real_deflate_bomb_npz_is_refused_from_its_header(tmp_path):
    """A 5000 x 5000 dense matrix (200 MB) in an .npz of about 200 kB: refused before it is
    inflated."""
    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(header, np.lib.format.header_data_from_array_1_0(
        np.zeros((5000, 5000))))
    with zipfile.ZipFile(tmp_path / "K.npz", "w", compression=zipfile.ZIP_DEFLATED) as z:
        with z.open("K.npy", "w", force_zip64=True) as member:
            member.write(header.getvalue())
            chunk = bytes(1 << 22)
            for _ in range(5000 * 5000 * 8 // len(chunk) + 1):
                member.write(chunk)
    assert (tmp_path / "K.npz").stat().st_size < 1_000_000
    start = time.perf_counter()
    message = case_error(MATRICES.replace("FILE", "K.npz"), tmp_path)
    assert time.perf_counter() - start < 2
    assert "substructures.P.K.file: a dense 5000 x 5000 matrix has 25000000 entries, more " \
           "than the 16000000 accepted" in message


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this system")
def test_matrix_and_mesh_files_that_are_fifos_or_devices_are_refused(tmp_path):
    os.mkfifo(tmp_path / "K.npy")
    message = case_error(MATRICES.replace("FILE", "K.npy"), tmp_path)
    assert "substructures.P.K.file: " in message and "is a FIFO, a device or a socket, not a " \
        "matrix file, got 'K.npy'" in message
    os.mkfifo(tmp_path / "beam.vtu")
    message = case_error(SOLID.replace("MESH", "beam.vtu"), tmp_path)
    assert message == "case.yaml: substructures.beam.mesh: is a FIFO, a device or a socket, " \
                      "not a mesh file (a mesh is read from a regular file), got 'beam.vtu'"
    if os.path.exists("/dev/zero"):
        (tmp_path / "zero.mtx").symlink_to("/dev/zero")
        assert "is a FIFO, a device or a socket" in \
            case_error(MATRICES.replace("FILE", "zero.mtx"), tmp_path)
        (tmp_path / "zero.msh").symlink_to("/dev/zero")
        assert "is a FIFO, a device or a socket" in \
            case_error(SOLID.replace("MESH", "zero.msh"), tmp_path)


def test_matrix_market_headers(tmp_path):
    def header_of(text: str) -> str:
        (tmp_path / "K.mtx").write_text(text)
        return case_error(MATRICES.replace("FILE", "K.mtx"), tmp_path)

    banner = "%%MatrixMarket matrix coordinate real general\n"
    assert "the size line must be 3 integers" in header_of(banner + "3 3\n")
    assert "no size line" in header_of(banner + "% only comments\n")
    assert "must be a real matrix, the file holds a complex one" in \
        header_of("%%MatrixMarket matrix coordinate complex hermitian\n3 3 1\n1 1 1 0\n")
    assert "unknown format, field or symmetry" in \
        header_of("%%MatrixMarket matrix coordinate real weird\n3 3 1\n1 1 1\n")
    long_comment = banner + "%" + "x" * 70_000 + "\n3 3 3\n"
    assert "no size line in its first 65536 bytes" in header_of(long_comment)
    # a valid file still reads
    (tmp_path / "K.mtx").write_text(banner + "3 3 3\n1 1 20\n2 2 30\n3 3 20\n")
    parse_case(MATRICES.replace("FILE", "K.mtx"), "case.yaml", tmp_path)


# -------------------------------------------------------------------------- mesh files


def test_gmsh_version_4_headers_are_read_ascii_and_binary(tmp_path):
    ascii4 = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 5000000 1 5000000\n"
    (tmp_path / "a.msh").write_text(ascii4)
    assert mesh_file_problem(tmp_path / "a.msh") == \
        "the header declares 5000000 points, more than the 2000000 accepted"
    binary = (b"$MeshFormat\n4.1 1 8\n" + struct.pack("<i", 1) + b"\n$EndMeshFormat\n$Nodes\n"
              + struct.pack("<QQQQ", 1, 3, 1, 3) + b"\n$EndNodes\n$Elements\n"
              + struct.pack("<QQQQ", 1, 9_000_000, 1, 9_000_000))
    (tmp_path / "b.msh").write_bytes(binary)
    assert mesh_file_problem(tmp_path / "b.msh") == \
        "the header declares 9000000 cells, more than the 4000000 accepted"
    assert mesh_file_problem(ROOT / "meshes" / "plate.msh") is None


def test_xdmf_data_items_read_only_files_beside_the_xdmf_file(tmp_path):
    """An XDMF file names the files its arrays are in: an HDF5 file by '../' or an absolute
    path, or a raw Binary file (which meshio opens from the working directory, and which may
    be a device or a FIFO), was read; now only an HDF5 file beside the XDMF file is."""
    import meshio

    pts = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1],
                    [1, 1, 1], [0, 1, 1]], dtype=float)
    case = tmp_path / "case"
    case.mkdir()
    meshio.write(case / "m.xdmf", meshio.Mesh(pts, [("hexahedron", np.arange(8)[None])]))
    assert mesh_file_problem(case / "m.xdmf") is None
    assert read_mesh_file(case / "m.xdmf").points.shape == (8, 3)
    text = (case / "m.xdmf").read_text()
    assert "m.h5:/data0" in text
    (tmp_path / "outside.h5").write_bytes((case / "m.h5").read_bytes())
    (2 * pts).tofile(tmp_path / "points.bin")
    for name, shown in (("../outside.h5", "'../outside.h5:/data0'"),
                        (str(tmp_path / "outside.h5"), "'/"),
                        ("nope.h5", "'nope.h5:/data0': no such regular file")):
        (case / "bad.xdmf").write_text(text.replace("m.h5:/data0", f"{name}:/data0"))
        problem = mesh_file_problem(case / "bad.xdmf")
        assert problem is not None and problem.startswith(f"an XDMF data item names {shown}"), \
            problem
        with pytest.raises(MeshFileError, match="an XDMF data item names"):
            read_mesh_file(case / "bad.xdmf")
    if hasattr(os, "symlink"):
        os.symlink(tmp_path / "outside.h5", case / "link.h5")
        (case / "bad.xdmf").write_text(text.replace("m.h5:/data0", "link.h5:/data0"))
        assert "a link leads out of it" in (mesh_file_problem(case / "bad.xdmf") or "")
    binary = text.replace('Format="HDF" Precision="8">m.h5:/data0',
                          f'Format="Binary" Precision="8">{tmp_path / "points.bin"}')
    assert "Binary" in binary
    (case / "bad.xdmf").write_text(binary)
    assert (mesh_file_problem(case / "bad.xdmf") or "").startswith(
        "an XDMF data item of format 'Binary'")


def test_abaqus_includes_read_only_files_beside_the_including_file(tmp_path, monkeypatch):
    """meshio reads an Abaqus *INCLUDE by any path (absolute, '..', first from the working
    directory): such a mesh was read from outside its directory; now only a file beside the
    including file is, once, and not through a loop."""
    nodes = "".join(f"{k + 1}, {x:.1f}, {y:.1f}, {z:.1f}\n" for k, (x, y, z) in enumerate(
        [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1),
         (0, 1, 1)]))
    part = f"*NODE\n{nodes}*ELEMENT, TYPE=C3D8, ELSET=ALL\n1, 1, 2, 3, 4, 5, 6, 7, 8\n"
    case, other = tmp_path / "case", tmp_path / "other"
    case.mkdir()
    other.mkdir()
    (case / "part.inp").write_text(part)
    (tmp_path / "part.inp").write_text(part.replace("1.0", "2.0"))
    main = case / "m.inp"
    main.write_text("*HEADING\n*INCLUDE, INPUT=part.inp\n")
    assert mesh_file_problem(main) is None
    assert read_mesh_file(main).points.max() == 1.0
    for name in ("../part.inp", str(tmp_path / "part.inp")):
        main.write_text(f"*HEADING\n*include,input={name}\n")
        assert (mesh_file_problem(main) or "").startswith(
            f"m.inp: line 2: *INCLUDE names {name!r}: a file named by a mesh file is named "
            "relative to it, inside its directory"), mesh_file_problem(main)
    main.write_text("*HEADING\n*INCLUDE, INPUT=part.inp\n")
    monkeypatch.chdir(tmp_path)  # meshio would take ./part.inp, the one with 2.0
    assert "meshio would read the file of that name in the working directory" in \
        (mesh_file_problem(main) or "")
    monkeypatch.chdir(other)
    (case / "part.inp").write_text("*INCLUDE, INPUT=m.inp\n")
    assert mesh_file_problem(main) == "m.inp includes itself (through its *INCLUDE lines)"


def test_meshio_exit_is_an_error_and_prints_nothing(tmp_path, capsys):
    from substruct.models.mesh_io import read_mesh

    bad = tmp_path / "bad.vtu"
    bad.write_text('<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid">')
    with pytest.raises(MeshFileError, match=r"cannot read mesh file .*bad.vtu \(not a readable "
                                            r"vtu file\)"):
        read_mesh_file(bad)
    with pytest.raises(ValueError, match="not a readable vtu file"):
        read_mesh(str(bad))  # the Python API: a ValueError, not SystemExit
    assert capsys.readouterr() == ("", "")


def _vtu_bomb(path: Path, inflated: int) -> None:
    """A VTU of one hexahedron whose compressed points inflate to ``inflated`` bytes."""
    import base64

    import meshio

    pts = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1],
                    [1, 1, 1], [0, 1, 1]], dtype=float)
    meshio.write(path, meshio.Mesh(pts, [("hexahedron", np.arange(8)[None])]),
                 compression="zlib")
    packer = zlib.compressobj(9)
    chunk = bytes(1 << 22)
    blob = b"".join(packer.compress(chunk) for _ in range(inflated // len(chunk))) + \
        packer.flush()
    head = np.array([1, inflated, inflated, len(blob)], dtype=np.uint32).tobytes()
    data = base64.b64encode(head).decode() + base64.b64encode(blob).decode()
    text = path.read_text()
    start = text.index(">", text.index('Name="Points"')) + 1
    end = text.index("</DataArray>", start)
    path.write_text(text[:start] + data + text[end:])


def test_a_mesh_that_inflates_beyond_the_memory_cap_is_refused(tmp_path, monkeypatch,
                                                               capsys):
    if mesh_files._vm_size() is None:
        pytest.skip("no address-space limit on this system")
    monkeypatch.setattr(mesh_files, "MESH_READ_MEMORY", 100_000_000)
    _vtu_bomb(tmp_path / "bomb.vtu", 800_000_000)
    assert mesh_file_problem(tmp_path / "bomb.vtu") is None  # its header is small
    (tmp_path / "case.yaml").write_text(SOLID.replace("MESH", "bomb.vtu"))
    line = refused(capsys, "run", tmp_path / "case.yaml", "--out", tmp_path / "out")
    assert line.endswith("reading it would take more than the 0.1 GB of memory allowed for a "
                         "mesh, got 'bomb.vtu'")
    assert not (tmp_path / "out").exists()
    np.ones(50_000_000)  # the cap is lifted again


def test_the_memory_cap_is_lifted_after_the_read():
    if mesh_files._vm_size() is None:
        pytest.skip("no address-space limit on this system")
    with pytest.raises(MemoryError):
        with mesh_files._memory_cap(50_000_000):
            np.ones(200_000_000)
    assert np.ones(50_000_000).sum() == 50_000_000


def test_a_mirrored_hexahedron_reads_and_a_collapsed_one_is_named(tmp_path):
    """Every corner negative (the numbering of a mirror image) integrates like the original;
    one corner at zero is refused with the cell and its nodes."""
    import meshio

    pts = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1],
                    [1, 1, 1], [0, 1, 1]], dtype=float)
    mirrored = np.array([[4, 5, 6, 7, 0, 1, 2, 3]])
    meshio.write(tmp_path / "m.vtu", meshio.Mesh(pts, [("hexahedron", mirrored)]))
    assert len(read_mesh_file(tmp_path / "m.vtu").points) == 8
    flat = pts.copy()
    flat[6] = [1, 1, 0]  # the top corner pushed down onto the bottom face
    meshio.write(tmp_path / "f.vtu", meshio.Mesh(flat, [("hexahedron", np.arange(8)[None])]))
    with pytest.raises(MeshFileError, match=r"hexahedron cell 0 is collapsed \(a zero Jacobian"):
        read_mesh_file(tmp_path / "f.vtu")
    tri = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0]], dtype=float)
    meshio.write(tmp_path / "t.vtu", meshio.Mesh(tri, [("triangle", np.array([[0, 1, 3],
                                                                              [0, 1, 2]]))]))
    with pytest.raises(MeshFileError, match=r"triangle cell 1 is collapsed .*: nodes \[0, 1, 2\]"):
        read_mesh_file(tmp_path / "t.vtu")
