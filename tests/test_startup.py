"""Start-up and exit of the ``substruct`` process: a command imports only what it uses, and
the program ends without the interpreter's teardown once its exit handlers have run (its
output whole, its exit code kept)."""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

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


def _modules_of_whole_run(argv: list[str]) -> set[str]:
    """The modules loaded by ``main(argv)`` with the computation in this process (not in the
    forked child of :func:`substruct.cli.isolated.call_isolated`), so that what the child
    would load is counted too."""
    code = ("import sys, json, importlib\n"
            "rc = importlib.import_module('substruct.cli.run_command')\n"
            "rc.call_isolated = lambda fn: fn()\n"
            "from substruct.cli.main import main\n"
            f"code = main({argv!r})\n"
            "print(json.dumps([code, sorted(sys.modules)]))\n")
    proc = _python(code)
    assert proc.returncode == 0, proc.stderr
    code_, modules = json.loads(proc.stdout.strip().splitlines()[-1])
    assert code_ == 0, proc.stderr
    return set(modules)


def test_a_modes_run_loads_no_picture_jit_or_other_analysis_route(tmp_path):
    """The constrained rod's modes (and the variant without its constraint), without
    pictures: no plotting, no Numba (the receptance kernels), none of the routes of the
    analyses the case does not ask for."""
    case = ROOT / "cases" / "tapered_rod_fe.yaml"
    mods = _modules_of_whole_run(["run", str(case), "--out", str(tmp_path), "--quiet",
                                  "--no-pictures"])
    assert (tmp_path / "tapered_rod_fe.h5").is_file()
    assert "substruct.run.runner" in mods and "substruct.analysis.modes.production" in mods
    for unused in ("matplotlib", "numba", "substruct.viz.plotting", "substruct.run.frf_route",
                   "substruct.run.vp_route", "substruct.run.spec_route",
                   "substruct.run.base_frf_route", "substruct.run.transient_run",
                   "substruct.run.testlab_route", "scipy.signal", "scipy.spatial"):
        assert unused not in mods, unused


def test_pardiso_is_loaded_without_a_search_for_its_library():
    """With the mkl wheel installed, PARDISO's library is the wheel's own, and neither
    ``ctypes.util.find_library`` (which runs ldconfig and the compiler) nor a walk of the
    environment (``glob``) runs to find it."""
    if importlib.util.find_spec("pypardiso") is None:
        pytest.skip("pypardiso is not installed")
    code = ("import ctypes.util, glob, json\n"
            "calls = []\n"
            "ctypes.util.find_library = lambda *a: calls.append(('find_library', a))\n"
            "glob.glob = lambda *a, **k: calls.append(('glob', a)) or []\n"
            "from substruct.linalg.pardiso import load_mkl_pardiso, mkl_wheel_library\n"
            "path = mkl_wheel_library()\n"
            "loaded = None\n"
            "if path is not None:\n"
            "    load_mkl_pardiso()\n"
            "    import pypardiso\n"
            "    loaded = pypardiso.ps.libmkl._name\n"
            "print(json.dumps([path, calls, loaded]))\n")
    proc = _python(code)
    assert proc.returncode == 0, proc.stderr
    path, calls, loaded = json.loads(proc.stdout.strip().splitlines()[-1])
    if path is None:
        pytest.skip("PARDISO's library is not from the mkl wheel")
    assert calls == [] and loaded == path and os.path.isfile(path)


def test_what_loading_made_is_not_left_to_the_next_young_collection():
    """Objects made while the collector is paused (the case read, the layers loaded) go to the
    oldest generation, so the first collection after the pause does not walk them all; they
    stay collectable (a cycle made in the pause and dropped is freed by a full collection)."""
    import gc
    import weakref

    from substruct.cli.files import collector_paused

    class Node:
        pass

    assert gc.isenabled()
    with collector_paused():
        kept = [Node() for _ in range(1000)]
        cycle = Node()
        cycle.self = cycle  # type: ignore[attr-defined]
        gone = weakref.ref(cycle)
        del cycle
    assert gc.isenabled()
    assert all(gc.is_tracked(k) for k in kept)
    young = {id(o) for o in gc.get_objects(generation=0)}
    assert not any(id(k) in young for k in kept)
    assert any(o is kept[0] for o in gc.get_objects(generation=2))
    assert gone() is not None  # not collected yet: the pause made no collection
    gc.collect()
    assert gone() is None
