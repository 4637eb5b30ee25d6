"""Ctrl-C while the ``substruct`` command starts (its modules load for a second or two, and
``main`` imports the layers it needs before a command runs): exit 130 and the one line
``substruct: interrupted``, no traceback.

Each run pauses inside one import (``tests/interrupt_driver.py``) and is sent SIGINT there, so
the interrupt lands in that window every time; the last case lets the pause end and shows the
command then runs to its normal end.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from cli_helpers import default_ctrl_c

ROOT = Path(__file__).resolve().parents[1]
DRIVER = ROOT / "tests" / "interrupt_driver.py"
CASE = ROOT / "cases" / "three_dof_frf.yaml"

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")


def _start(module: str, *args: str, pause: float = 60.0) -> tuple[subprocess.Popen, str]:
    env = dict(os.environ, PYTHONPATH=str(ROOT), OMP_NUM_THREADS="1", MPLBACKEND="Agg",
               PAUSE_SECONDS=str(pause))
    proc = subprocess.Popen([sys.executable, str(DRIVER), module, *args], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=default_ctrl_c)
    assert proc.stderr is not None
    first = proc.stderr.readline()
    return proc, first


@pytest.mark.parametrize("module", [
    "substruct.cli.arguments",  # while `from substruct.cli import main` loads the command
    "substruct.cli.summary",  # inside main(): the command module loading, before its own try
])
def test_ctrl_c_while_the_command_starts_is_one_line_and_130(tmp_path, module):
    proc, first = _start(module, "info", str(tmp_path / "missing.h5"))
    assert first.startswith(f"PAUSED {module} "), first
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert err == "substruct: interrupted\n"
    assert out == ""


def test_without_the_interrupt_the_paused_start_runs_to_its_end(tmp_path):
    """The same start, left alone: the command runs (here: bad input, exit 2, one line)."""
    proc, first = _start("substruct.cli.summary", "info", str(tmp_path / "missing.h5"),
                         pause=0.5)
    assert first.startswith("PAUSED substruct.cli.summary "), first
    out, err = proc.communicate(timeout=180)
    assert proc.returncode == 2, err
    assert err.startswith("substruct: error: ") and err.count("\n") == 1, err
