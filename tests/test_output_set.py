"""Outputs as one set: checked before computing, one writer at a time, old pictures go with
their result.

- Output paths that would fail only once written are refused before anything is computed
  (exit 2, one line, nothing written): ``--out ''``, a component past the file system's
  ``NAME_MAX``, a dangling symbolic link, a directory that cannot be written.
- Two runs into one ``--out``: the second exits 2 with "another run is writing DIR" while the
  first writes, and the directory holds the first run's set, whole.
- A run without pictures replaces a set with pictures: the old pictures go with the old result.
"""

import os
import subprocess
import sys
from pathlib import Path

import h5py
import pytest
from cli_helpers import run

import substruct.run.runner
from substruct.cli.errors import InputError
from substruct.cli.files import check_out_dir

ROOT = Path(__file__).resolve().parent.parent
CASE = ROOT / "cases" / "three_dof_frf.yaml"
NAME = "three_dof_frf"


@pytest.fixture
def never_computes(monkeypatch):
    """A run that reaches the analysis fails the test (exit 1 instead of 2)."""
    def computed(*args, **kwargs):
        raise AssertionError("the analysis ran")
    monkeypatch.setattr(substruct.run.runner, "run_case", computed)


def refused(capsys, *args) -> str:
    code, out, err = run(capsys, *args)
    assert code == 2 and out == "", err
    assert err.startswith("substruct: error: ") and err.count("\n") == 1, err
    assert "Traceback" not in err
    return err


def test_empty_out_is_refused_and_nothing_lands_in_the_working_directory(
        tmp_path, capsys, monkeypatch, never_computes):
    monkeypatch.chdir(tmp_path)
    err = refused(capsys, "run", CASE, "--out", "")
    assert "--out '': an empty directory name" in err
    assert list(tmp_path.iterdir()) == []


def test_over_long_out_component_is_refused(tmp_path, capsys, never_computes):
    long = "d" * 300
    err = refused(capsys, "run", CASE, "--out", tmp_path / long / "x")
    assert "has 300 bytes, more than the 255" in err
    assert list(tmp_path.iterdir()) == []


def test_dangling_symlink_as_out_is_refused(tmp_path, capsys, never_computes):
    link = tmp_path / "results"
    link.symlink_to(tmp_path / "gone")
    err = refused(capsys, "run", CASE, "--out", link)
    assert f"{link} is a symbolic link to {tmp_path / 'gone'}, which does not exist" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results"]


def test_unwritable_out_is_refused(capsys, never_computes):
    err = refused(capsys, "run", CASE, "--out", "/proc/substruct-out")
    assert "--out /proc/substruct-out is not writable" in err


def test_file_names_too_long_for_the_file_system():
    with pytest.raises(InputError, match=r"is too long \(243 bytes; with its temporary name "
                                         r"at most 255 bytes\)"):
        check_out_dir(".", "--out", ["n" * 240 + ".h5"])
    check_out_dir(".", "--out", ["n" * 200 + ".h5"])  # room left for the temporary name


def test_second_run_into_one_out_fails_while_the_first_writes(tmp_path, capsys):
    out = tmp_path / "out"
    env = {**os.environ, "MPLBACKEND": "Agg", "OMP_NUM_THREADS": "1", "PYTHONPATH": str(ROOT)}
    first = subprocess.Popen([sys.executable, str(ROOT / "tests" / "kill_driver.py"),
                              "compute-short", "run", str(CASE), "--out", str(out), "--quiet"],
                             stderr=subprocess.PIPE, env=env, cwd=ROOT)
    try:
        line = first.stderr.readline().decode()
        assert line.startswith("PAUSED compute-short"), line
        code, stdout, err = run(capsys, "run", CASE, "--out", out, "--quiet", "--force",
                                "--set", "parameters.k3=40")
        assert (code, stdout, err) == (2, "", f"substruct: error: another run is writing "
                                              f"{out}\n")
        assert first.wait(timeout=120) == 0, first.stderr.read().decode()
    finally:
        if first.poll() is None:
            first.kill()
            first.wait()
    names = sorted(p.name for p in out.iterdir())
    assert names == [f"{NAME}.h5", f"{NAME}_frf.png", f"{NAME}_modes.png"]
    with h5py.File(out / f"{NAME}.h5", "r") as f:
        assert "overrides" not in f.attrs  # the first run's result ...
        assert sorted(str(f.attrs["pictures"]).split("\n")) == names[1:]  # ... and pictures


def test_a_run_without_pictures_takes_the_old_pictures_away(tmp_path, capsys):
    out = tmp_path / "out"
    assert run(capsys, "run", CASE, "--out", out, "--quiet")[0] == 0
    assert len(list(out.glob("*.png"))) == 2
    (out / "notes.txt").write_text("mine\n")
    code, _, err = run(capsys, "run", CASE, "--out", out, "--quiet", "--force",
                       "--no-pictures")
    assert code == 0, err
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt", f"{NAME}.h5"]
    with h5py.File(out / f"{NAME}.h5", "r") as f:
        assert f.attrs["pictures"] == ""


def test_pictures_false_in_the_case_draws_none_and_loads_no_plotting(tmp_path):
    code = ("import sys; from substruct import cli; "
            f"c = cli.main(['run', {str(CASE)!r}, '--out', {str(tmp_path)!r}, '--quiet', "
            "'--set', 'output.pictures=false']); "
            "print(c, sorted(m for m in sys.modules if m.startswith(('pyvista', 'matplotlib', "
            "'substruct.viz', 'vtk')))[:3])")
    env = {**os.environ, "MPLBACKEND": "Agg", "PYTHONPATH": str(ROOT)}
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=env, cwd=ROOT, timeout=120)
    assert proc.stdout.strip() == "0 []", proc.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == [f"{NAME}.h5"]
