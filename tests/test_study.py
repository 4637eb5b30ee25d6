"""Studies: parameters wherever a number is read, the ``study:`` block, the study on every
backend (in-process, a LocalCluster, a scheduler and a worker in separate processes), failed
samples, the study file and a sample checked against ``substruct run --set``."""

from __future__ import annotations

import itertools
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

from substruct import cli
from substruct.case.loader import CaseError, load_case, parse_case
from substruct.io.study_file import load_study, save_study
from substruct.run.runner import run_case
from substruct.studies.study_backend import BackendError
from substruct.studies.study_plan import number_text, samples
from substruct.studies.study_run import run_study
from substruct.studies.study_tuning import den_hartog, grid_optimum

CASES = Path(__file__).resolve().parent.parent / "cases"
ROD = CASES / "tapered_rod.yaml"
QUICK = ["analysis.frf.omega={start: 1, stop: 200, num: 40, spacing: linear}"]


def rod_case(overrides=()):
    return parse_case(ROD.read_text(), str(ROD), CASES, list(overrides))


# ----------------------------------------------------------------- step 1: parameters


def test_a_parameter_feeds_stiffness_mass_damping_and_counts():
    literal = run_case(rod_case(QUICK + [
        "substructures.c.stiffness=8000", "substructures.c.mass=1.5",
        "substructures.c.damping=20", "substructures.rod.discretization.n=10"]))
    named = run_case(rod_case(QUICK + [
        "parameters.k=4000", "parameters.n=5", "substructures.c.stiffness=2*k",
        "substructures.c.mass=k/8000*3", "substructures.c.damping=k/200",
        "substructures.rod.discretization.n=2*n"]))
    assert named.modes is not None and literal.modes is not None
    assert np.array_equal(named.modes.omega, literal.modes.omega)
    assert np.array_equal(named.modes.damping_ratio, literal.modes.damping_ratio)
    assert named.modes.damping_ratio.max() > 0  # the damper is there
    # and they differ from the shipped stiffness 7000
    shipped = run_case(rod_case(QUICK))
    assert shipped.modes is not None
    assert not np.allclose(shipped.modes.omega, named.modes.omega)


def test_parameters_may_be_expressions_of_earlier_ones():
    case = rod_case(["parameters.k0=7000", "parameters.kc=1.5*k0",
                     "substructures.c.stiffness=kc", "parameters.z=0.01",
                     "substructures.rod.reduce.damping={ratio: z}"])
    assert case.substructure("c").stiffness == 10500.0
    assert case.substructure("rod").reduce.damping.as_argument() == 0.01


@pytest.mark.parametrize("overrides, fragment", [
    (["substructures.c.stiffness=kk"], "substructures.c.stiffness: must be a number"),
    (["substructures.c.stiffness=2*kk"], "substructures.c.stiffness: unknown name 'kk'"),
    (["substructures.c.stiffness=-EA0"], "substructures.c.stiffness: must be > 0"),
    (["substructures.c.stiffness=EA0*1e30"],
     "substructures.c.stiffness: 'EA0*1e30' = 6e+36: out of range: too large"),
    (["substructures.c.stiffness=__import__('os')"], "substructures.c.stiffness: call of"),
    (["parameters.n=8.5", "substructures.rod.discretization.n=n"],
     "substructures.rod.discretization.n: must be an integer: 'n' = 8.5"),
    (["parameters.n=0", "substructures.rod.discretization.n=n"],
     "substructures.rod.discretization.n: must be >= 1"),
])
def test_bad_parameter_values_are_one_line_naming_the_field(overrides, fragment):
    with pytest.raises(CaseError) as info:
        rod_case(overrides)
    message = str(info.value)
    assert fragment in message and "\n" not in message


# ----------------------------------------------------------------- the plan of samples

TUNING = CASES / "tapered_rod_tuning.yaml"
#: A 2 x 2 grid of the shipped study with a short sweep (quick on any backend).
SMALL = ["study.grid.parameters[0]={parameter: kc, values: [1140.0, 1160.0]}",
         "study.grid.parameters[1]={parameter: cc, values: [3.5, 4.0]}",
         "analysis.frf.omega={start: 30, stop: 39, num: 181, spacing: linear}"]


def test_grid_product_is_in_itertools_order_and_zip_pairs_rows():
    case = load_case(TUNING, SMALL)
    names, table = samples(case.study)
    assert names == ["kc", "cc"]
    assert table.tolist() == [list(r) for r in itertools.product([1140.0, 1160.0], [3.5, 4.0])]
    zipped = load_case(TUNING, SMALL + ["study.grid.combine=zip"])
    assert samples(zipped.study)[1].tolist() == [[1140.0, 3.5], [1160.0, 4.0]]
    ranged = load_case(TUNING)
    _, table = samples(ranged.study)
    assert table.shape == (99, 2) and np.allclose(np.unique(table[:, 0]),
                                                  np.linspace(1130, 1180, 11))


def test_random_samples_follow_their_distributions_and_the_seed():
    block = ("study={random: {seed: 7, count: 4000, parameters: ["
             "{parameter: kc, distribution: normal, mean: 1150, std: 10}, "
             "{parameter: cc, distribution: lognormal, median: 4.0, sigma: 0.1}, "
             "{parameter: m0, distribution: uniform, low: 0.9, high: 1.1}]}}")
    case = load_case(TUNING, [block])
    _, a = samples(case.study)
    _, b = samples(load_case(TUNING, [block]).study)
    assert np.array_equal(a, b)  # same seed, same table
    n = len(a)
    assert abs(a[:, 0].mean() - 1150) < 4 * 10 / np.sqrt(n)
    assert abs(a[:, 0].std() / 10 - 1) < 0.05
    assert abs(np.median(np.log(a[:, 1])) - np.log(4.0)) < 4 * 0.1 * 1.25 / np.sqrt(n)
    assert 0.9 <= a[:, 2].min() and a[:, 2].max() < 1.1
    assert abs(a[:, 2].mean() - 1.0) < 4 * 0.2 / np.sqrt(12 * n)
    other = load_case(TUNING, [block.replace("seed: 7", "seed: 8")])
    assert not np.array_equal(samples(other.study)[1], a)


@pytest.mark.parametrize("value", [1e-05, 1150.0, 0.1 + 0.2, 1.2345678901234567e22, 3e-7])
def test_override_text_reads_back_to_the_same_float(value):
    case = load_case(TUNING, [f"parameters.cc={number_text(value)}"])
    assert case.parameters["cc"] == value


@pytest.mark.parametrize("block, fragment", [
    ("{grid: {parameters: [{parameter: k9, values: [1]}]}}",
     "study.grid.parameters[0].parameter: not a parameter of the case"),
    ("{grid: {combine: zip, parameters: [{parameter: kc, values: [1, 2]}, "
     "{parameter: cc, values: [1]}]}}", "study.grid.combine: zip needs as many values"),
    ("{random: {seed: 1, count: 3, parameters: [{parameter: kc, distribution: normal, "
     "mean: 1}]}}", "study.random.parameters[0].std: a normal distribution needs mean and std"),
    ("{grid: {parameters: [{parameter: kc, values: [1]}]}, collect: {frf_peaks: [rod@50]}}",
     "study.collect.frf_peaks[0]: not an output of analysis.frf"),
    ("{grid: {parameters: [{parameter: kc, values: [1]}]}, collect: {frequencies: 9}}",
     "study.collect.frequencies: more than the 4 modes"),
])
def test_bad_study_blocks_are_one_line(block, fragment):
    with pytest.raises(CaseError) as info:
        load_case(TUNING, [f"study={block}"])
    assert fragment in str(info.value) and "\n" not in str(info.value)


# ----------------------------------------------------------------- backends


def assert_same(a, b):
    assert np.array_equal(a.table, b.table)
    assert a.errors == b.errors
    assert sorted(a.values) == sorted(b.values)
    for name in a.values:  # bitwise: NaN where a sample failed, in both
        assert np.array_equal(a.values[name], b.values[name], equal_nan=True), name


#: Runs a study in a fresh interpreter and writes its file: Dask leaves threads in the process
#: that uses it, and a later test that forks (``substruct run`` analyses in a forked child)
#: could inherit one of their locks held and hang, so no test starts Dask in pytest itself.
DASK_SCRIPT = """
import sys, json
from substruct.case.loader import load_case
from substruct.io.study_file import save_study
from substruct.studies.study_backend import Backend, BackendError
from substruct.studies.study_run import run_study
args = json.loads(sys.argv[1])
try:
    result = run_study(load_case(args["case"], args["overrides"]), Backend(**args["backend"]))
except BackendError as err:
    print(err)
    sys.exit(3)
save_study(result, args["out"])
"""


def dask_study(tmp_path, overrides, **backend):
    """The study run on ``Backend(**backend)`` in a subprocess, read back from its file."""
    import json

    out = tmp_path / f"dask_{len(list(tmp_path.iterdir()))}.h5"
    done = subprocess.run([sys.executable, "-c", DASK_SCRIPT, json.dumps(
        {"case": str(TUNING), "overrides": overrides, "backend": backend, "out": str(out)})],
        capture_output=True, text=True, env={**os.environ, "OMP_NUM_THREADS": "1"},
        timeout=600)
    if done.returncode == 3:
        raise BackendError(done.stdout.strip())
    assert done.returncode == 0, done.stderr[-2000:]
    return load_study(out)


@pytest.fixture(scope="module")
def serial():
    return run_study(load_case(TUNING, SMALL))


def test_a_grid_sample_equals_a_direct_run_with_set(serial, tmp_path, capsys):
    k = 2  # kc = 1160, cc = 3.5
    assert serial.table[k].tolist() == [1160.0, 3.5]
    code = cli.main(["run", str(TUNING), "--out", str(tmp_path), "--quiet", "--no-pictures",
                     *sum((["--set", s] for s in SMALL), []),
                     "--set", "parameters.kc=1160", "--set", "parameters.cc=3.5"])
    assert code == 0
    with h5py.File(tmp_path / "tapered_rod_tuning.h5") as f:
        omega = f["modes/omega"][()]
        zeta = f["modes/damping_ratio"][()]
        H = f["frf/H"][()]
        w = f["frf/omega"][()]
        shapes = f["modes/shapes"][()]
    assert np.array_equal(serial.values["frequency"][k], omega[:4])
    assert np.array_equal(serial.values["damping_ratio"][k], zeta[:4])
    peak = np.abs(H[:, 0, 0])
    assert serial.values["frf_peak"][k, 0] == peak.max()
    assert serial.values["frf_peak_omega"][k, 0] == w[np.argmax(peak)]
    # the MAC to the modes of the case as written (kc = 1155, cc = 3.7), computed here
    written = run_case(load_case(TUNING, SMALL)).modes
    assert written is not None
    for i in range(4):
        r, s = written.shapes[:, i], shapes[:, i]
        mac = abs(np.vdot(r, s)) ** 2 / (np.vdot(r, r).real * np.vdot(s, s).real)
        assert serial.values["mac"][k, i] == pytest.approx(mac, abs=1e-12)
    assert np.allclose(serial.reference["mac"], 1.0, atol=1e-12)
    assert serial.values["mac"][k, 0] < 1 - 1e-4  # the absorber's mode changed with kc


def test_same_table_on_a_two_worker_local_cluster(serial, tmp_path):
    result = dask_study(tmp_path, SMALL, workers=2)
    assert result.backend == "LocalCluster (2 workers)"
    assert_same(serial, result)


def _spawn(args, log):
    return subprocess.Popen(args, stdout=log, stderr=subprocess.STDOUT,
                            env={**os.environ, "OMP_NUM_THREADS": "1"})


def _scheduler(tmp_path):
    dask = str(Path(sys.executable).parent / "dask")
    file = tmp_path / "scheduler.json"
    log = open(tmp_path / "dask.log", "w")
    sched = _spawn([dask, "scheduler", "--host", "127.0.0.1", "--port", "0",
                    "--no-dashboard", "--scheduler-file", str(file)], log)
    for _ in range(300):
        if file.exists() and file.stat().st_size:
            break
        time.sleep(0.1)
    import json
    address = json.loads(file.read_text())["address"]
    return dask, file, log, sched, address


def _worker(dask, file, log):
    return _spawn([dask, "worker", "--scheduler-file", str(file), "--nthreads", "1",
                   "--nworkers", "1", "--no-dashboard", "--host", "127.0.0.1"], log)


def _stop(*procs):
    for p in procs:
        if p.poll() is None:
            p.terminate()
    for p in procs:
        try:
            p.wait(10)
        except subprocess.TimeoutExpired:
            p.kill()


def test_same_table_on_a_scheduler_and_worker_in_separate_processes(serial, tmp_path):
    dask, file, log, sched, address = _scheduler(tmp_path)
    worker = _worker(dask, file, log)
    try:
        assert address.startswith("tcp://127.0.0.1:")
        result = dask_study(tmp_path, SMALL, scheduler=address)
        assert result.backend == f"scheduler {address}"
        assert_same(serial, result)
    finally:
        _stop(worker, sched)


def test_a_failed_sample_is_recorded_and_the_others_complete(serial, tmp_path):
    bad = SMALL[:1] + ["study.grid.parameters[1]={parameter: cc, values: [3.5, -1.0, 4.0]}"] \
        + SMALL[2:]
    result = run_study(load_case(TUNING, bad))
    assert result.failed == [1, 4]  # cc = -1 for both stiffnesses
    for k in result.failed:
        assert "substructures.c.damping: must be >= 0" in result.errors[k]
        assert np.isnan(result.values["frequency"][k]).all()
    good = [0, 2, 3, 5]
    assert np.array_equal(result.values["frequency"][good], serial.values["frequency"])
    on_dask = dask_study(tmp_path, bad, workers=1)
    assert_same(result, on_dask)


def test_the_study_file_holds_the_table_and_the_failures(tmp_path):
    bad = ["study.grid.parameters[0]={parameter: kc, values: [1150.0]}",
           "study.grid.parameters[1]={parameter: cc, values: [4.0, -2.0]}"] + SMALL[2:]
    result = run_study(load_case(TUNING, bad))
    path = save_study(result, tmp_path / "s.h5")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.h5"]  # no temporary left
    back = load_study(path)
    assert_same(result, back)
    assert back.parameters == ["kc", "cc"] and back.peaks == ["rod@200<-rod@200"]
    with h5py.File(path) as f:
        assert f["failures/index"][()].tolist() == [1]
        assert "must be >= 0" in f["failures/message"][0].decode()


def test_the_command_writes_the_file_and_refuses_bad_input(tmp_path, capsys):
    args = ["study", str(TUNING), "--out", str(tmp_path), *sum((["--set", s] for s in SMALL), [])]
    assert cli.main(args + ["--no-pictures"]) == 0
    out = capsys.readouterr().out
    assert "4 samples of kc, cc on in-process" in out and "0 failed" in out
    assert (tmp_path / "tapered_rod_tuning_study.h5").exists()
    assert cli.main(args) == 2  # exists, no --force
    err = capsys.readouterr().err
    assert "exists; use --force" in err and err.count("\n") == 1
    assert cli.main(["study", str(ROD), "--out", str(tmp_path / "x")]) == 2
    assert "study: the case has no study: block" in capsys.readouterr().err
    assert not (tmp_path / "x").exists() or not any((tmp_path / "x").iterdir())
    assert cli.main(args + ["--force", "--scheduler", "127.0.0.1:9"]) == 2
    assert "--scheduler: an address such as tcp://SCHEDULER_HOST:8786" in capsys.readouterr().err
    with pytest.raises(BackendError, match="--scheduler tcp://127.0.0.1:9: nothing listens"):
        dask_study(tmp_path, SMALL, scheduler="tcp://127.0.0.1:9", connect_timeout=2)


def test_a_study_whose_every_sample_failed_is_exit_1_and_writes_nothing(tmp_path, capsys):
    bad = ["study.grid.parameters[0]={parameter: kc, values: [1150.0]}",
           "study.grid.parameters[1]={parameter: cc, values: [-1.0, -2.0]}"] + SMALL[2:]
    args = ["study", str(TUNING), "--out", str(tmp_path / "o"), "--no-pictures",
            *sum((["--set", s] for s in bad), [])]
    assert cli.main(args) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "every sample of the study failed (2 of 2)" in err
    assert "substructures.c.damping: must be >= 0" in err
    assert not (tmp_path / "o").exists() or not any((tmp_path / "o").iterdir())


# ----------------------------------------------------------------- the shipped study


def test_tuning_grid_optimum_agrees_with_den_hartog():
    """Absorber c on mode 1 of the rod without c (34.26 rad/s, modal mass 120.4 at x = 3L/4):
    the best point of a fine grid is Den Hartog's tuning within one grid step, and the
    closed-form tuning's peak is within 0.5 % of the grid's smallest."""
    from test_study_tuning_picture import primary_mode

    omega, u = primary_mode()
    dh = den_hartog(omega, 1.0 / u ** 2, 1.0)
    assert dh.mu == pytest.approx(0.0083, abs=1e-4)
    grid = ["study.grid.parameters[0]={parameter: kc, start: 1145, stop: 1165, num: 5}",
            "study.grid.parameters[1]={parameter: cc, start: 3.4, stop: 4.2, num: 5}",
            "study.collect={frf_peaks: [rod@200]}"]
    result = run_study(load_case(TUNING, grid))
    k, best = grid_optimum(result.values["frf_peak"][:, 0])
    assert abs(result.table[k, 0] - dh.k_opt) <= 5.0
    assert abs(result.table[k, 1] - dh.c_opt) <= 0.2
    tuned = run_case(load_case(TUNING, [f"parameters.kc={dh.k_opt!r}",
                                        f"parameters.cc={dh.c_opt!r}"]))
    assert tuned.frf is not None
    peak = float(np.abs(tuned.frf.H[:, 0, 0]).max())
    assert best * 0.995 < peak < best * 1.005
    # a detuned absorber (10 % too stiff) is far worse: the comparison can fail
    off = run_case(load_case(TUNING, [f"parameters.kc={1.1 * dh.k_opt!r}",
                                      f"parameters.cc={dh.c_opt!r}"]))
    assert off.frf is not None and np.abs(off.frf.H[:, 0, 0]).max() > 1.3 * best


@pytest.mark.slow
def test_killing_a_worker_mid_study_still_completes(tmp_path):
    """Two workers; the first is killed (SIGKILL) once 3 samples are done: the scheduler runs
    its tasks again on the other, and the table equals the in-process one."""
    dask, file, log, sched, address = _scheduler(tmp_path)
    workers = [_worker(dask, file, log), _worker(dask, file, log)]
    try:
        more = ["study.grid.parameters[0]={parameter: kc, start: 1140, stop: 1160, num: 15}",
                "study.grid.parameters[1]={parameter: cc, values: [3.5, 4.0]}",
                "analysis.frf.omega={start: 30, stop: 39, num: 181, spacing: linear}"]
        script = ("import sys, os, signal\n"
                  "from distributed import Client\n"
                  "from substruct.case.loader import load_case\n"
                  "from substruct.io.study_file import save_study\n"
                  "from substruct.studies.study_backend import Backend\n"
                  "from substruct.studies.study_run import run_study\n"
                  "address, case, out, pid = sys.argv[1:5]\n"
                  "with Client(address, timeout=30) as c:\n"
                  "    c.wait_for_workers(2, timeout=60)\n"
                  "def tick(done, total):\n"
                  "    if done == 3:\n"
                  "        os.kill(int(pid), signal.SIGKILL)\n"
                  "save_study(run_study(load_case(case, sys.argv[5:]), "
                  "Backend(scheduler=address), tick), out)\n")
        out = tmp_path / "killed.h5"
        done = subprocess.run([sys.executable, "-c", script, address, str(TUNING), str(out),
                               str(workers[0].pid), *more], capture_output=True, text=True,
                              timeout=600)
        assert done.returncode == 0, done.stderr[-2000:]
        result = load_study(out)
        assert workers[0].wait(10) == -signal.SIGKILL
        assert result.failed == [] and len(result.errors) == 30
        assert_same(run_study(load_case(TUNING, more)), result)
    finally:
        _stop(*workers, sched)
