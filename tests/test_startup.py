"""Start-up and exit of the ``substruct`` process: a command imports only what it uses, and
the program ends without the interpreter's teardown once its exit handlers have run (its
output whole, its exit code kept)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ENV = {**os.environ, "MPLBACKEND": "Agg", "OMP_NUM_THREADS": "1", "PYTHONPATH": str(ROOT)}
FRF = ROOT / "cases" / "three_dof_frf.yaml"


def _python(code: str, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True,
                          env=ENV, cwd=ROOT, timeout=120)


def _modules_after(argv: list[str]) -> set[str]:
    code = ("import sys, json; from substruct.cli.main import main; "
            f"code = main({argv!r}); "
            "print(json.dumps([code, sorted(sys.modules)]))")
    proc = _python(code)
    code_, modules = json.loads(proc.stdout.strip().splitlines()[-1])
    assert code_ == 0, proc.stderr
    return set(modules)


def test_run_imports_no_other_command_and_no_unused_library(tmp_path):
    mods = _modules_after(["run", str(FRF), "--out", str(tmp_path), "--quiet",
                           "--no-pictures"])
    assert "substruct.cli.run_command" in mods and "substruct.case.loader" in mods
    for unused in ("substruct.cli.study_command", "substruct.cli.compare_command",
                   "substruct.cli.converge_command", "substruct.cli.uff_export",
                   "substruct.studies", "scipy.spatial", "matplotlib", "pyvista", "meshio",
                   "dask"):
        assert unused not in mods, unused


def test_info_loads_no_case_layer(tmp_path):
    assert subprocess.run([sys.executable, "-m", "substruct.cli", "run", str(FRF), "--out",
                           str(tmp_path), "--quiet", "--no-pictures"], env=ENV, cwd=ROOT,
                          timeout=120).returncode == 0
    mods = _modules_after(["info", str(tmp_path / "three_dof_frf.h5")])
    assert "substruct.cli.result_commands" in mods
    for unused in ("substruct.cli.run_command", "substruct.case.loader", "pydantic",
                   "substruct.run.runner", "scipy.sparse.linalg", "skfem"):
        assert unused not in mods, unused


def test_the_program_ends_without_teardown_its_output_and_code_whole(tmp_path):
    """An object whose finalizer would speak at the interpreter's teardown stays silent (the
    teardown is skipped); an exit handler still runs; the JSON report (with ``H`` at 110
    frequencies, about 40 kB) arrives whole through a pipe, with exit code 0; bad input still
    exits 2 with its line."""
    code = ("import atexit, sys; from substruct.cli.main import main\n"
            "class Loud:\n"
            "    def __del__(self): sys.stderr.write('teardown ran\\n')\n"
            "keep = Loud()\n"
            "atexit.register(lambda: sys.stderr.write('exit handler ran\\n'))\n"
            "sys.argv = ['substruct', *sys.argv[1:]]\n"
            "sys.exit(main())\n")
    proc = _python(code, "run", str(FRF), "--out", str(tmp_path), "--json", "--no-pictures",
                   "--set", "analysis.frf.omega={start: 1, stop: 3, num: 110}")
    assert proc.returncode == 0, proc.stderr
    report = json.loads(proc.stdout)
    assert report["frf"]["n_omega"] == 110 and len(report["frf"]["H"]["real"]) == 110
    assert len(proc.stdout) > 30_000
    assert "exit handler ran" in proc.stderr and "teardown ran" not in proc.stderr
    bad = _python(code, "run", str(tmp_path / "missing.yaml"))
    assert bad.returncode == 2
    assert bad.stderr.startswith("substruct: error: ") and "no such case file" in bad.stderr
    assert "exit handler ran" in bad.stderr and "teardown ran" not in bad.stderr


def test_a_program_calling_main_with_arguments_keeps_its_teardown(tmp_path):
    code = ("import sys; from substruct.cli.main import main\n"
            "class Loud:\n"
            "    def __del__(self): sys.stderr.write('teardown ran\\n')\n"
            "keep = Loud()\n"
            f"main(['run', {str(FRF)!r}, '--out', {str(tmp_path)!r}, '--quiet', "
            "'--no-pictures'])\n"
            "sys.exit(7)\n")
    proc = _python(code)
    assert proc.returncode == 7 and "teardown ran" in proc.stderr, proc.stderr
