"""``substruct study --workers 2``: Dask's scratch space in a directory of the system's
temporary directory (``$TMPDIR``), removed at the end; the workers' output never on the
terminal; an interrupted study (Ctrl-C to the whole process group, as a terminal sends it, or
SIGTERM to the command) prints one line and leaves no worker and no scratch behind.  Each study
runs in its own process (Dask's threads stay out of pytest)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import psutil
import pytest
from cli_helpers import default_ctrl_c

ROOT = Path(__file__).resolve().parent.parent
TUNING = ROOT / "cases" / "tapered_rod_tuning.yaml"
SMALL = ["study.grid.parameters[0]={parameter: kc, values: [1140.0, 1160.0]}",
         "study.grid.parameters[1]={parameter: cc, values: [3.5, 4.0]}",
         "analysis.frf.omega={start: 30, stop: 39, num: 181, spacing: linear}"]
#: 400 x 9 samples: minutes of work, so the study is still running when it is stopped.
LONG = ["study.grid.parameters[0]={parameter: kc, start: 1100, stop: 1200, num: 400}"]


def files(directory: Path) -> list[str]:
    return sorted(str(p.relative_to(directory)) for p in directory.rglob("*"))


def command(tmp_path: Path, overrides: list[str]) -> tuple[list[str], dict[str, str], Path]:
    """The study on 2 workers with ``TMPDIR`` and the working directory of its own."""
    for name in ("tmp", "cwd"):
        (tmp_path / name).mkdir()
    env = {**os.environ, "TMPDIR": str(tmp_path / "tmp"), "PYTHONPATH": str(ROOT),
           "MPLBACKEND": "Agg", "OMP_NUM_THREADS": "1", "PYTHONFAULTHANDLER": "1"}
    args = [sys.executable, "-m", "substruct.cli", "study", str(TUNING), "--workers", "2",
            "--out", str(tmp_path / "out"), "--no-pictures"]
    for s in overrides:
        args += ["--set", s]
    return args, env, tmp_path / "tmp"


def test_a_study_on_two_workers_is_quiet_and_leaves_no_scratch(tmp_path):
    args, env, tmp = command(tmp_path, SMALL)
    done = subprocess.run(args, env=env, cwd=tmp_path / "cwd", capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stderr == ""  # no log line of Dask, no worker output
    assert "4 samples of kc, cc on LocalCluster (2 workers)" in done.stdout
    assert files(tmp) == [] and files(tmp_path / "cwd") == []
    assert files(tmp_path / "out") == ["tapered_rod_tuning_study.h5"]


def _worker_logs(tmp: Path) -> list[Path]:
    return list(tmp.glob("substruct-dask-*/**/worker-*.log"))


@pytest.mark.parametrize("how", ["ctrl-c", pytest.param("sigterm", marks=pytest.mark.slow)])
def test_an_interrupted_study_prints_one_line_and_leaves_nothing(how, tmp_path):
    args, env, tmp = command(tmp_path, LONG)
    proc = subprocess.Popen(args, env=env, cwd=tmp_path / "cwd", stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True,
                            preexec_fn=default_ctrl_c)
    try:
        deadline = time.monotonic() + 300
        while len(_worker_logs(tmp)) < 2 and time.monotonic() < deadline:
            assert proc.poll() is None, proc.communicate()
            time.sleep(0.2)
        # both workers started, each writing into its log in the scratch directory of TMPDIR
        assert len(_worker_logs(tmp)) == 2
        time.sleep(2.0)  # samples under way
        children = psutil.Process(proc.pid).children(recursive=True)
        assert len(children) >= 2
        if how == "ctrl-c":
            os.killpg(proc.pid, signal.SIGINT)  # what the terminal does: the whole group
        else:
            proc.send_signal(signal.SIGTERM)
        try:
            out, err = proc.communicate(timeout=120)
        except subprocess.TimeoutExpired:  # show where it hangs (faulthandler), then fail
            proc.send_signal(signal.SIGABRT)
            out, err = proc.communicate(timeout=60)
            pytest.fail(f"the study did not end after {how}:\n{err[-6000:]}")
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    assert (proc.returncode, err) == ((130, "substruct: interrupted\n") if how == "ctrl-c"
                                      else (143, "substruct: terminated\n"))
    assert out == ""
    _, alive = psutil.wait_procs(children, timeout=30)
    assert alive == []  # no worker left running
    assert files(tmp) == [] and files(tmp_path / "cwd") == []
    assert not (tmp_path / "out").exists() or files(tmp_path / "out") == []
