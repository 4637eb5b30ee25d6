"""A run killed at any point leaves the previous set of outputs whole: the result file and the
pictures that belong to it, never the new result beside old pictures or the reverse.

A real ``substruct run --force`` (through ``tests/kill_driver.py``, which pauses it at one
point) replaces an earlier set of ``cases/three_dof_frf.yaml`` (result and two pictures) and
is killed there: in the analysis (inside a 40-second LAPACK call), in the middle of the
result file, after the pictures are drawn, and in the middle of the commit.  SIGTERM and
Ctrl-C must act within 2 s and leave exactly the earlier files; SIGKILL (which nothing can
catch) may leave hidden ``.substruct-*`` leftovers, which the next writer removes (or, for a
commit under way, completes).
"""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import pytest

from cli_helpers import default_ctrl_c
from substruct import cli

ROOT = Path(__file__).resolve().parent.parent
CASE = ROOT / "cases" / "three_dof_frf.yaml"
NAME = "three_dof_frf"
DRIVER = ROOT / "tests" / "kill_driver.py"
NEW = ["--set", "parameters.k3=40"]


def snapshot(out: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(out.iterdir()) if p.is_file()}


def consistent(out: Path) -> list[str]:
    """The set in ``out``: its result lists exactly the pictures beside it; their names."""
    with h5py.File(out / f"{NAME}.h5", "r") as f:
        listed = sorted(str(f.attrs["pictures"]).split("\n"))
    pngs = sorted(p.name for p in out.iterdir() if p.suffix == ".png")
    assert listed == pngs, (listed, pngs)
    return pngs


@pytest.fixture(scope="module")
def earlier(tmp_path_factory):
    """An earlier set (result and pictures of the case as shipped) and a file of the user."""
    out = tmp_path_factory.mktemp("earlier") / "out"
    assert cli.main(["run", str(CASE), "--out", str(out), "--quiet"]) == 0
    (out / "notes.txt").write_text("mine\n")
    assert consistent(out) == [f"{NAME}_frf.png", f"{NAME}_modes.png"]
    return snapshot(out)


def fresh(tmp_path: Path, files: dict[str, bytes]) -> Path:
    out = tmp_path / "out"
    out.mkdir()
    for name, data in files.items():
        (out / name).write_bytes(data)
    return out


def start(point: str, out: Path, *extra: str) -> tuple[subprocess.Popen, int]:
    """The driver paused at ``point``; the pid of the process that paused."""
    env = {**os.environ, "MPLBACKEND": "Agg", "OMP_NUM_THREADS": "1", "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen([sys.executable, str(DRIVER), point, "run", str(CASE), "--out",
                             str(out), "--force", "--quiet", *NEW, *extra],
                            stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, env=env, cwd=ROOT,
                            preexec_fn=default_ctrl_c)
    line = proc.stderr.readline().decode()
    assert line.startswith(f"PAUSED {point} "), line + proc.stderr.read().decode()
    return proc, int(line.split()[-1])


def stop(proc: subprocess.Popen, sig: int) -> tuple[int, str, float]:
    """Send ``sig``; the exit code, the rest of stderr and the seconds until the exit."""
    t0 = time.monotonic()
    proc.send_signal(sig)
    try:
        code = proc.wait(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    took = time.monotonic() - t0
    return code, proc.stderr.read().decode(), took


def gone(pid: int, timeout: float = 5) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return True
        time.sleep(0.05)
    return False


@pytest.mark.parametrize("point", ["compute", "write", "pictures"])
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "SIGINT"])
def test_sigterm_and_ctrl_c_act_within_2_s_and_keep_the_earlier_set(point, sig, tmp_path,
                                                                     earlier):
    out = fresh(tmp_path, earlier)
    proc, _ = start(point, out)
    code, err, took = stop(proc, sig)
    expected = {signal.SIGTERM: (143, "substruct: terminated"),
                signal.SIGINT: (130, "substruct: interrupted")}[sig]
    assert (code, err.strip()) == expected, err
    assert took < 2.0, f"{took:.1f} s to act"
    assert snapshot(out) == earlier  # the same files, byte for byte, and nothing else
    assert sorted(p.name for p in out.iterdir()) == sorted(earlier)


@pytest.mark.parametrize("point", ["compute", "write", "pictures"])
def test_sigkill_keeps_the_earlier_set_and_the_next_run_cleans_up(point, tmp_path, earlier,
                                                                 capsys):
    out = fresh(tmp_path, earlier)
    proc, paused = start(point, out)
    code, _, _ = stop(proc, signal.SIGKILL)
    assert code == -signal.SIGKILL
    assert gone(paused), "the computing child outlived its killed parent"
    assert snapshot(out) == earlier
    leftovers = [p.name for p in out.iterdir() if p.name not in earlier]
    assert all(n.startswith(".substruct-") for n in leftovers), leftovers
    if point != "compute":
        assert leftovers  # the staging folder of the killed run ...
    assert cli.main(["run", str(CASE), "--out", str(out), "--force", "--quiet", *NEW]) == 0
    assert sorted(p.name for p in out.iterdir()) == sorted(earlier)  # ... is gone
    consistent(out)
    with h5py.File(out / f"{NAME}.h5", "r") as f:
        assert "k3=40" in f.attrs["overrides"]


def test_sigkill_during_the_commit_is_completed_by_the_next_writer(tmp_path, earlier):
    from substruct.io.file_set import OutputDir

    out = fresh(tmp_path, earlier)
    proc, _ = start("commit", out)
    code, _, _ = stop(proc, signal.SIGKILL)
    assert code == -signal.SIGKILL
    commits = [p for p in out.iterdir() if p.name.endswith(".commit")]
    assert len(commits) == 1  # killed past the point of no return, one picture moved
    assert snapshot(out) != earlier
    with OutputDir(out) as target:  # any writer finishes the commit first
        assert target.stale == [commits[0].name]
    assert sorted(p.name for p in out.iterdir()) == sorted(earlier)
    assert consistent(out) == [f"{NAME}_frf.png", f"{NAME}_modes.png"]
    now = snapshot(out)
    with h5py.File(out / f"{NAME}.h5", "r") as f:
        assert "k3=40" in f.attrs["overrides"]  # the new set, whole
    assert all(now[n] != earlier[n] for n in now if n != "notes.txt")


def test_sigterm_while_writing_removes_the_partial_file(tmp_path, capsys, monkeypatch):
    """SIGTERM in the middle of the HDF5 write (in the process that writes it, the run's
    child): the staging folder goes, the old result stays, the handler is restored."""
    from substruct.io import hdf5 as results

    out = tmp_path / "out"
    args = ["run", str(CASE), "--out", str(out), "--quiet", "--no-pictures"]
    assert cli.main(args) == 0
    before = (out / f"{NAME}.h5").read_bytes()
    seen = tmp_path / "parts.txt"  # written by the writing process, read here
    write_model = results._write_model

    def interrupted(group, model):
        seen.write_text("".join(f"{p.name}\n" for p in out.iterdir()
                                if p.name.endswith(".part")))
        write_model(group, model)
        os.kill(os.getpid(), signal.SIGTERM)  # delivered here, in the middle of save()
        time.sleep(1)  # not reached: the handler raises first

    monkeypatch.setattr(results, "_write_model", interrupted)
    capsys.readouterr()
    handler = signal.getsignal(signal.SIGTERM)
    code = cli.main([*args, "--force", *NEW])
    assert code == 143 and capsys.readouterr().err == "substruct: terminated\n"
    assert len(seen.read_text().split()) == 1  # the staging folder existed while writing ...
    assert sorted(p.name for p in out.iterdir()) == [f"{NAME}.h5"]  # ... and is gone
    assert (out / f"{NAME}.h5").read_bytes() == before
    assert signal.getsignal(signal.SIGTERM) == handler  # cli.main restored the handler


@pytest.mark.parametrize("point", ["commit", "exit"])
def test_sigterm_after_the_commit_began_exits_143_with_its_line(point, tmp_path, earlier):
    """SIGTERM once the commit is under way (held until it is done) or once the command has
    returned (the interpreter shutting down): the new set stands whole, and the process still
    says why it ends: ``substruct: terminated``, exit code 143 (never a silent death by the
    default action)."""
    out = fresh(tmp_path, earlier)
    proc, _ = start(point, out)
    code, err, _ = stop(proc, signal.SIGTERM)
    assert (code, err) == (143, "substruct: terminated\n"), (code, err)
    assert sorted(p.name for p in out.iterdir()) == sorted(earlier)  # no leftovers
    assert consistent(out) == [f"{NAME}_frf.png", f"{NAME}_modes.png"]
    with h5py.File(out / f"{NAME}.h5", "r") as f:
        assert "k3=40" in f.attrs["overrides"]  # the new set, committed before the exit


STUDY_CASE = ROOT / "cases" / "tapered_rod_tuning.yaml"
STUDY_SMALL = ["--set", "study.grid.parameters[0]={parameter: kc, values: [1140.0, 1160.0]}",
               "--set", "study.grid.parameters[1]={parameter: cc, values: [3.5, 4.0]}",
               "--set", "analysis.frf.omega={start: 30, stop: 39, num: 61, spacing: linear}"]


def test_a_killed_study_leaves_no_file_and_the_next_writer_removes_its_part(tmp_path):
    """A study SIGKILLed after its file was written (into the staging folder, not yet
    committed) leaves no study file, only hidden ``.substruct-*`` leftovers; the next study
    into the directory removes them under the lock and writes its set."""
    out = tmp_path / "out"
    env = {**os.environ, "MPLBACKEND": "Agg", "OMP_NUM_THREADS": "1", "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen([sys.executable, str(DRIVER), "study-write", "study",
                             str(STUDY_CASE), "--out", str(out), "--quiet", *STUDY_SMALL],
                            stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, env=env, cwd=ROOT)
    line = proc.stderr.readline().decode()
    assert line.startswith("PAUSED study-write "), line + proc.stderr.read().decode()
    code, _, _ = stop(proc, signal.SIGKILL)
    assert code == -signal.SIGKILL
    leftovers = sorted(p.name for p in out.iterdir())
    assert leftovers and all(n.startswith(".substruct-") for n in leftovers), leftovers
    parts = [p for p in out.iterdir() if p.name.endswith(".part")]
    assert any(f.name == "tapered_rod_tuning_study.h5" for p in parts for f in p.iterdir())
    assert cli.main(["study", str(STUDY_CASE), "--out", str(out), "--quiet", "--no-pictures",
                     *STUDY_SMALL]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["tapered_rod_tuning_study.h5"]
