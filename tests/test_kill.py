"""A run killed mid-way leaves no result, no partial file, and an earlier result untouched.

``substruct run`` writes its result to a temporary file in the output directory and renames it
over the target only when complete (:func:`substruct.io.hdf5.atomic_path`).  Here a real process
sweeps 20000 frequencies and is killed while it does so (SIGTERM, which it turns into a clean
exit 143, and SIGKILL, which nothing can catch); the output directory must hold exactly what it
held before.  A SIGTERM that arrives while the file is being written removes the temporary file.
"""

import os
import pty
import select
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from substruct import cli

ROOT = Path(__file__).resolve().parent.parent
CASE = ROOT / "cases" / "tapered_rod_fe.yaml"
TARGET = "tapered_rod_fe.h5"
FRF = ("analysis.frf={{omega: {{start: 1, stop: 500, num: {num}}}, inputs: [rod@200], "
       "outputs: [rod@200, rod@100]}}")
SETS = ["--set", "analysis.modes=null", "--set", "output.pictures=false"]


def earlier_result(out: Path, capsys) -> bytes:
    """A good result of the case in ``out`` (a 5-point sweep), and a file beside it."""
    code = cli.main(["run", str(CASE), "--out", str(out), "--quiet", *SETS,
                     "--set", FRF.format(num=5)])
    assert code == 0, capsys.readouterr().err
    (out / "notes.txt").write_text("mine\n")
    return (out / TARGET).read_bytes()


def start_long_sweep(out: Path) -> tuple[subprocess.Popen, int]:
    """``substruct run --force`` of a 20000-frequency sweep, its stderr on a terminal so that
    the progress bar shows when the sweep is under way."""
    master, slave = pty.openpty()
    env = {**os.environ, "MPLBACKEND": "Agg", "OMP_NUM_THREADS": "1",
           "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen([sys.executable, "-m", "substruct.cli", "run", str(CASE), "--out",
                             str(out), "--force", *SETS, "--set", FRF.format(num=20000)],
                            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=slave,
                            env=env, cwd=ROOT)
    os.close(slave)
    return proc, master


def read_until(master: int, marker: bytes, timeout: float) -> bytes:
    """What the process writes to its terminal, up to ``marker`` (or its exit, or timeout)."""
    seen = b""
    deadline = time.monotonic() + timeout
    while marker not in seen and time.monotonic() < deadline:
        ready, _, _ = select.select([master], [], [], 0.2)
        if ready:
            try:
                chunk = os.read(master, 4096)
            except OSError:  # the process exited and closed the terminal
                break
            if not chunk:
                break
            seen += chunk
    return seen


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGKILL], ids=["SIGTERM", "SIGKILL"])
def test_killed_run_leaves_no_result_and_keeps_the_earlier_one(sig, tmp_path, capsys):
    out = tmp_path / "out"
    before = earlier_result(out, capsys)
    proc, master = start_long_sweep(out)
    try:
        seen = read_until(master, b"/20000", timeout=60)
        assert b"/20000" in seen, seen.decode(errors="replace")
        time.sleep(0.3)  # well inside the sweep (which takes half a minute)
        assert proc.poll() is None, "the sweep ended before it could be killed"
        proc.send_signal(sig)
        code = proc.wait(timeout=20)
        tail = read_until(master, b"terminated", timeout=2)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        os.close(master)
    if sig == signal.SIGTERM:
        assert code == 143 and b"substruct: terminated" in tail, (code, tail)
        assert b"Traceback" not in tail
    else:
        assert code == -signal.SIGKILL
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt", TARGET]
    assert (out / TARGET).read_bytes() == before
    assert (out / "notes.txt").read_text() == "mine\n"


def test_sigterm_while_writing_removes_the_partial_file(tmp_path, capsys, monkeypatch):
    """SIGTERM in the middle of the HDF5 write: the ``.part`` file goes, the old result stays."""
    from substruct.io import hdf5 as results

    out = tmp_path / "out"
    before = earlier_result(out, capsys)
    parts = []
    write_model = results._write_model

    def interrupted(group, model):
        parts.extend(p.name for p in out.iterdir() if p.name.endswith(".part"))
        write_model(group, model)
        os.kill(os.getpid(), signal.SIGTERM)  # delivered here, in the middle of save()
        time.sleep(1)  # not reached: the handler raises first

    monkeypatch.setattr(results, "_write_model", interrupted)
    handler = signal.getsignal(signal.SIGTERM)
    code = cli.main(["run", str(CASE), "--out", str(out), "--force", "--quiet", *SETS,
                     "--set", FRF.format(num=5)])
    assert code == 143 and capsys.readouterr().err == "substruct: terminated\n"
    assert len(parts) == 1  # the temporary file existed while writing ...
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt", TARGET]  # ... and is gone
    assert (out / TARGET).read_bytes() == before
    assert signal.getsignal(signal.SIGTERM) == handler  # cli.main restored the handler
