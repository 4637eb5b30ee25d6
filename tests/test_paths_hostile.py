"""Hostile command lines against every command that writes (run, study, converge, export,
compare): one path policy (``substruct.io.paths``), every writer a set under the directory's
lock (``substruct.io.file_set``).

Each test runs the real command (``cli.main``) and asserts the exit code, the one line on
stderr and the files on disk: nothing outside the chosen directory, nothing half-written, no
temporary file left, no input overwritten.  Failures of the file system (full disk, read-only
folder) are injected where the file is written (the tests run as root on some machines, where
permissions do not stop a write).
"""

import errno
import os
import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest

from cli_helpers import assert_one_line_error, run
from substruct import cli
from substruct.io.file_set import OutputDir
from substruct.io.paths import STEM_BYTES, plain_name, safe_stem

ROOT = Path(__file__).resolve().parent.parent
CASES = ROOT / "cases"
FRF = CASES / "three_dof_frf.yaml"
NAME = "three_dof_frf"
ROD = CASES / "tapered_rod.yaml"
TUNING = CASES / "tapered_rod_tuning.yaml"
STUDY = ["--set", "study.grid.parameters[0]={parameter: kc, values: [1140.0, 1160.0]}",
         "--set", "study.grid.parameters[1]={parameter: cc, values: [3.5, 4.0]}",
         "--set", "analysis.frf.omega={start: 30, stop: 39, num: 61, spacing: linear}"]
TINY = "assumed=4,8; enriched=2,4; p1=8,16; p2=4,8"


def tree(folder: Path) -> list[str]:
    """Every path under ``folder``, relative, hidden ones included."""
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


@pytest.fixture(scope="module")
def result(tmp_path_factory) -> Path:
    """A result of ``cases/three_dof_frf.yaml`` (modes, variants and receptances)."""
    out = tmp_path_factory.mktemp("result")
    assert cli.main(["run", str(FRF), "--out", str(out), "--quiet", "--no-pictures"]) == 0
    return out / f"{NAME}.h5"


@pytest.fixture(scope="module")
def rod(tmp_path_factory) -> Path:
    """A result of ``cases/tapered_rod.yaml`` (modes and drawings: UFF, VTU and XDMF)."""
    out = tmp_path_factory.mktemp("rod")
    assert cli.main(["run", str(ROD), "--out", str(out), "--quiet", "--no-pictures"]) == 0
    return out / "tapered_rod.h5"


def doctored(result: Path, folder: Path, name: str = "doctored.h5", **attrs) -> Path:
    """A copy of ``result`` in ``folder`` with root attributes replaced."""
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / name
    shutil.copy(result, path)
    with h5py.File(path, "r+") as f:
        for key, value in attrs.items():
            f.attrs[key] = value
    return path


def enospc(*args, **kwargs):
    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


# ------------------------------------------------------------------------- safe_stem


@pytest.mark.parametrize("name", ["../x", "/etc/passwd", "..", ".", "", "a/../../b",
                                  "a\\..\\b", "x\x00y", "\x1b[2J\x1b]0;t\x07", "\u202etxt.exe",
                                  "é" * 400, ".hidden", "C:\\x", "-" * 3, "\n"])
def test_safe_stem_is_one_plain_name_of_bounded_length(name):
    stem = safe_stem(name)
    assert plain_name(stem) and plain_name(stem + ".uff")
    assert not stem.startswith(".") and ".." not in stem.split(os.sep)
    assert all(c.isalnum() or c in "_.+-" for c in stem), stem
    assert 0 < len(stem.encode()) <= STEM_BYTES
    assert safe_stem(stem) == stem  # a safe name stays as it is


# --------------------------------------------------------------------- --out '' and ..


@pytest.mark.parametrize("args", [
    ["run", FRF, "--no-pictures"],
    ["converge", ROD, "--levels", TINY, "--variants", "constrained"],
    ["study", TUNING, "--no-pictures", *STUDY],
], ids=["run", "converge", "study"])
def test_an_empty_out_is_refused_before_anything_runs(args, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert_one_line_error(*run(capsys, *args, "--out", ""), "--out '': an empty directory name")
    assert tree(tmp_path) == []


@pytest.mark.parametrize("fmt", ["uff", "vtu", "xdmf"])
def test_an_empty_export_out_is_refused(fmt, result, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert_one_line_error(*run(capsys, "export", result, "--format", fmt, "--out", ""),
                          "--out '': an empty directory name")
    assert tree(tmp_path) == []


def test_dot_dot_after_a_missing_folder_is_the_resolved_directory(tmp_path, capsys,
                                                                  monkeypatch):
    """``--out a/b/../c`` with ``a/b`` missing: the directory ``a/c`` (as the kernel would
    resolve it once ``a/b`` existed), created; ``a/b`` is not."""
    monkeypatch.chdir(tmp_path)
    code, out, err = run(capsys, "run", FRF, "--out", "a/b/../c", "--no-pictures", "--quiet")
    assert (code, err) == (0, "")
    assert tree(tmp_path) == ["a", "a/c", f"a/c/{NAME}.h5"]


def test_dot_dot_in_an_export_out(rod, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, out, err = run(capsys, "export", rod, "--format", "uff", "--out", "x/y/../z")
    assert (code, err) == (0, "")
    assert Path(out.strip()) == tmp_path / "x" / "z" / "tapered_rod.uff"
    assert tree(tmp_path) == ["x", "x/z", "x/z/tapered_rod.uff"]


def test_an_out_below_a_file_is_one_line(tmp_path, capsys):
    (tmp_path / "f").write_text("mine\n")
    assert_one_line_error(*run(capsys, "run", FRF, "--out", tmp_path / "f" / "sub",
                               "--no-pictures"), "is not a directory")
    assert tree(tmp_path) == ["f"] and (tmp_path / "f").read_text() == "mine\n"


# ------------------------------------------------------------- names read from results


@pytest.mark.parametrize("name,stem", [
    ("../escape", "escape"), ("/var/abs", "var_abs"), ("..", "case"), ("", "case"),
    ("a/../../b", "a_b"), ("\x1b[2Jx", "2Jx"), ("x" * 600, "x" * STEM_BYTES),
])
def test_uff_export_never_leaves_the_out_directory(name, stem, rod, tmp_path, capsys,
                                                    monkeypatch):
    """The UFF file is named from the case name stored in the result: a name with separators,
    ``..``, an absolute path, control characters or 600 bytes still gives one file inside
    ``--out`` (exit 0), named by ``safe_stem``; nothing anywhere else."""
    monkeypatch.chdir(tmp_path)
    src = doctored(rod, tmp_path / "in", case_name=name)
    out = tmp_path / "deep" / "out"
    outside = Path(name + ".uff")  # where the name itself points (the cwd is tmp_path)
    existed = outside.is_absolute() and outside.exists()
    code, printed, err = run(capsys, "export", src, "--format", "uff", "--out", out)
    assert (code, err) == (0, ""), err
    assert tree(tmp_path / "deep") == ["out", f"out/{stem}.uff"]
    assert Path(printed.strip()) == out / f"{stem}.uff"
    assert tree(tmp_path / "in") == ["doctored.h5"]
    assert (outside.is_absolute() and outside.exists()) == existed


@pytest.mark.parametrize("name", ["../x", "/var/x", "a/../../x", "..", "\x00x"])
def test_the_library_export_paths_stay_in_their_directory(name, rod, tmp_path):
    """The same policy without the command line: every path the export functions derive from
    the stored case name is a direct child of the directory given."""
    from substruct.io import export, hdf5, transient_export, uff

    res = hdf5.load(rod)
    res.case_name = name
    res.variants = {"../v": res.variants["without_eq52"]}  # a variant name read from a file
    out = tmp_path / "o"
    paths = [uff.uff_path(res, out), *export.export_paths(res, out, "vtu"),
             *export.export_paths(res, out, "xdmf", variant="../v")]
    for p in paths:
        assert p.parent == out and plain_name(p.name) and not p.name.startswith("."), p
    with pytest.raises(ValueError, match="holds no transient response"):
        transient_export.transient_export_paths(res, out)


def test_xdmf_export_of_a_hostile_name_stays_in_its_directory(rod, tmp_path, capsys):
    src = doctored(rod, tmp_path / "in", case_name="../../up")
    code, _, err = run(capsys, "export", src, "--format", "xdmf", "--out", tmp_path / "o")
    assert (code, err) == (0, "")
    assert tree(tmp_path / "o") == ["up_modes.h5", "up_modes.xdmf"]


# ------------------------------------------------------------------ never an input


def test_compare_never_draws_over_its_inputs(result, tmp_path, capsys):
    a = doctored(result, tmp_path, "a.png")  # a result file whose name ends in .png
    before = a.read_bytes()
    for extra in ([], ["--force"]):
        assert_one_line_error(*run(capsys, "compare", a, result, "--image", a, *extra),
                              f"{a} is a file this command reads")
        assert a.read_bytes() == before
    link = tmp_path / "link.png"
    link.symlink_to(a)
    assert_one_line_error(*run(capsys, "compare", a, result, "--image", link, "--force"),
                          f"{link} (the same file as {a}) is a file this command reads")
    assert a.read_bytes() == before and tree(tmp_path) == ["a.png", "link.png"]


def test_compare_image_exists_needs_force_and_a_picture_ending(result, tmp_path, capsys):
    image = tmp_path / "mac.png"
    assert run(capsys, "compare", result, result, "--image", image)[0] == 0
    first = image.read_bytes()
    assert first[:8] == b"\x89PNG\r\n\x1a\n"
    assert_one_line_error(*run(capsys, "compare", result, result, "--image", image),
                          f"{image} exists; use --force")
    code, out, err = run(capsys, "compare", result, result, "--image", image, "--force")
    assert code == 0 and out.endswith(f"written: {image}\n")
    for bad, fragment in [(tmp_path / "mac.h5", "must end in .png or .svg or .pdf"),
                          (tmp_path, "must end in"), ("", "an empty file name"),
                          (str(tmp_path) + "/", "a directory, not a file name")]:
        assert_one_line_error(*run(capsys, "compare", result, result, "--image", bad),
                              fragment)
    assert tree(tmp_path) == ["mac.png"]


def test_compare_image_in_a_missing_folder_is_created(result, tmp_path, capsys):
    image = tmp_path / "new" / "deeper" / "mac.svg"
    code, out, err = run(capsys, "compare", result, result, "--image", image)
    assert (code, err) == (0, "")
    assert tree(tmp_path) == ["new", "new/deeper", "new/deeper/mac.svg"]
    assert image.read_text().lstrip().startswith("<?xml")


def test_export_never_overwrites_the_result_it_reads(rod, tmp_path, capsys):
    src = doctored(rod, tmp_path, "tapered_rod.h5")
    before = src.read_bytes()
    for fmt, out in [("uff", tmp_path / "tapered_rod.uff"),
                     ("xdmf", tmp_path / "tapered_rod.xdmf")]:  # its .h5 is the result
        if fmt == "uff":  # a UFF target that is a hard link to the result
            os.link(src, out)
        code, _, err = run(capsys, "export", src, "--format", fmt, "--out", out, "--force")
        assert code == 2 and "is a file this command reads" in err and err.count("\n") == 1, err
        assert src.read_bytes() == before
        out.unlink(missing_ok=True)


# ------------------------------------------------------------ the file system refuses


@pytest.mark.parametrize("reason", [errno.ENOSPC, errno.EROFS, errno.EACCES])
def test_a_failed_picture_write_leaves_nothing(reason, result, tmp_path, capsys, monkeypatch):
    """The picture's write fails after some bytes (a full disk, a folder made read-only):
    one line naming the file and the reason, exit 2, no picture, no temporary file."""
    import matplotlib.figure

    def partly(self, fname, *args, **kwargs):
        Path(fname).write_bytes(b"\x89PNG half")
        raise OSError(reason, os.strerror(reason), str(fname))

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", partly)
    image = tmp_path / "out" / "mac.png"
    code, out, err = run(capsys, "compare", result, result, "--image", image)
    assert code == 2 and out == "" and err.count("\n") == 1, err
    assert err.startswith("substruct: error: cannot write ") and os.strerror(reason) in err
    assert "Traceback" not in err
    assert tree(tmp_path) == []  # the folder it created is gone again


def test_a_full_disk_while_writing_the_result_leaves_the_previous_set(tmp_path, capsys,
                                                                      monkeypatch):
    from substruct.io import hdf5

    out = tmp_path / "out"
    assert cli.main(["run", str(FRF), "--out", str(out), "--quiet", "--no-pictures"]) == 0
    before = (out / f"{NAME}.h5").read_bytes()
    real = hdf5._write_model

    def full(group, model):
        real(group, model)
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(hdf5, "_write_model", full)
    code, _, err = run(capsys, "run", FRF, "--out", out, "--quiet", "--no-pictures", "--force",
                       "--set", "parameters.k3=40")
    assert code == 2 and err.count("\n") == 1 and "No space left on device" in err, err
    assert tree(out) == [f"{NAME}.h5"] and (out / f"{NAME}.h5").read_bytes() == before


def test_a_full_disk_at_the_commit_moves_nothing(rod, tmp_path, capsys, monkeypatch):
    """The rename that starts the commit fails (ENOSPC): nothing moved, the staging folder
    removed, one line."""
    real = os.rename

    def rename(src, dst, *args, **kwargs):
        if str(dst).endswith(".commit"):
            enospc()
        return real(src, dst, *args, **kwargs)

    monkeypatch.setattr(os, "rename", rename)
    out = tmp_path / "o"
    code, _, err = run(capsys, "export", rod, "--format", "uff", "--out", out)
    assert code == 2 and err.count("\n") == 1 and "No space left on device" in err, err
    assert tree(tmp_path) == []


def test_a_full_disk_in_the_uff_writer_leaves_nothing(rod, tmp_path, capsys, monkeypatch):
    from substruct.io import uff

    def partly(path, sets, text=""):
        Path(path).write_bytes(b"    -1\n    58b")
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))

    monkeypatch.setattr(uff, "write_uff", partly)
    (tmp_path / "o").mkdir()
    code, _, err = run(capsys, "export", rod, "--format", "uff", "--out", tmp_path / "o")
    assert code == 2 and "No space left on device" in err and err.count("\n") == 1, err
    assert f"cannot write {tmp_path / 'o' / 'tapered_rod.uff'}: " in err  # its final name
    assert tree(tmp_path) == ["o"]


def test_a_folder_that_refuses_the_staging_folder_is_one_line(tmp_path, capsys,
                                                              monkeypatch):
    """The staging folder cannot be made (EROFS: the file system went read-only during the
    run): one line, exit 2, and the output folder the run created is gone again."""
    from substruct.io import file_set

    monkeypatch.setattr(file_set.tempfile, "mkdtemp", lambda *a, **k: (_ for _ in ()).throw(
        OSError(errno.EROFS, os.strerror(errno.EROFS))))
    code, _, err = run(capsys, "run", FRF, "--out", tmp_path / "o", "--quiet", "--no-pictures")
    assert code == 2 and "Read-only file system" in err and err.count("\n") == 1, err
    assert tree(tmp_path) == []


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into a read-only folder")
def test_a_read_only_folder_is_refused_before_running(tmp_path, capsys):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        assert_one_line_error(*run(capsys, "compare", FRF, FRF, "--image", ro / "m.png"),
                              "is not writable")
    finally:
        ro.chmod(0o755)


# ------------------------------------------------------- nothing after a late failure


def test_an_internal_error_after_the_result_was_written_leaves_no_result(tmp_path, capsys,
                                                                       monkeypatch):
    """The report fails after the result file was written into the staging folder: exit 1
    (an internal error), and no result, because the set is committed only after the report
    is ready."""
    from substruct.cli import summary   # run_command imports it when the report is made

    def broken(*args, **kwargs):
        raise ZeroDivisionError("a bug in the table")

    monkeypatch.setattr(summary, "print_summary", broken)
    code, out, err = run(capsys, "run", FRF, "--out", tmp_path / "o", "--no-pictures")
    assert code == 1 and "internal error: ZeroDivisionError: a bug in the table" in err
    assert tree(tmp_path) == []


def test_an_internal_error_in_the_study_report_leaves_no_study(tmp_path, capsys,
                                                              monkeypatch):
    from substruct.cli import study_command

    monkeypatch.setattr(study_command, "_summary", lambda *a: 1 / 0)
    code, _, err = run(capsys, "study", TUNING, "--out", tmp_path / "o", "--no-pictures",
                       *STUDY)
    assert code == 1 and "internal error: ZeroDivisionError" in err
    assert tree(tmp_path) == []


# ------------------------------------------------------------------ the lock, everywhere


@pytest.mark.parametrize("args", [
    ["run", FRF, "--no-pictures"],
    ["converge", ROD, "--levels", TINY, "--variants", "constrained"],
    ["study", TUNING, "--no-pictures", *STUDY],
], ids=["run", "converge", "study"])
def test_a_second_writer_is_refused_while_the_first_holds_the_directory(args, tmp_path,
                                                                        capsys):
    out = tmp_path / "o"
    with OutputDir(out):  # another writer holds it (flock on the directory)
        assert_one_line_error(*run(capsys, *args, "--out", out, "--quiet"),
                              f"another run is writing {out}")
    assert tree(tmp_path) == ["o"]


def test_two_studies_into_one_directory_do_not_replace_each_other(tmp_path, capsys):
    """The second study of the same case into the same --out is refused (as a second run):
    its file is the first one's until --force; then the set is replaced whole."""
    out = tmp_path / "o"
    args = ["study", TUNING, "--out", out, "--quiet", *STUDY]
    assert run(capsys, *args)[0] == 0
    first = {n: (out / n).read_bytes() for n in tree(out)}
    assert f"{TUNING.stem}_study.h5" in first and len(first) >= 2  # the file and pictures
    assert_one_line_error(*run(capsys, *args, "--set", "study.grid.parameters[1].values="
                               "[3.0, 5.0]"), "exists; use --force to overwrite it")
    assert {n: (out / n).read_bytes() for n in tree(out)} == first
    assert run(capsys, *args, "--force", "--no-pictures")[0] == 0
    assert tree(out) == [f"{TUNING.stem}_study.h5"]  # the old pictures went with the old set


def test_converge_checks_its_targets_under_the_lock(tmp_path, capsys):
    out = tmp_path / "o"
    args = ["converge", ROD, "--levels", TINY, "--variants", "constrained", "--out", out,
            "--quiet"]
    assert run(capsys, *args)[0] == 0
    names = tree(out)
    assert names == ["tapered_rod_convergence.h5", "tapered_rod_convergence.png"]
    assert_one_line_error(*run(capsys, *args), "exists; use --force")
    (out / ".substruct-tapered_rod.x1y2.part").mkdir()  # left by a killed writer
    assert run(capsys, *args, "--force")[0] == 0
    assert tree(out) == names


# ---------------------------------------------------------------------- compare, docs


def test_compare_refuses_a_result_with_a_nan_frequency(result, tmp_path, capsys):
    bad = doctored(result, tmp_path)
    with h5py.File(bad, "r+") as f:
        f["modes/omega"][0] = np.nan
    for args in ([bad, result], [result, bad], [result, bad, "--json"]):
        code, out, err = run(capsys, "compare", *args)
        assert_one_line_error(code, out, err, f"{bad}: not a substruct result: /modes/omega "
                              "holds values that are not finite: nan at index 0")
        assert "nan" not in out


def test_compare_is_in_the_usage_line_the_readme_and_the_docs(capsys):
    assert cli.main(["--help"]) == 0
    usage = capsys.readouterr().out.split("\n\n")[0]  # the usage paragraph
    assert usage.startswith("usage: substruct")
    assert "compare" in usage and "study" in usage, usage
    readme = (ROOT / "README.md").read_text()
    assert "substruct compare" in readme
    assert "substruct compare" in (ROOT / "docs" / "results.md").read_text()
