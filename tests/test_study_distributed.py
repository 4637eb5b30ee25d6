"""One analysis on a backend: its reductions as tasks and its direct sweep in frequency
chunks, the same receptances as the serial run (bit for bit), in-process and on a 2-worker
LocalCluster."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from substruct.case.loader import load_case
from substruct.run.runner import run_case
from substruct.studies.distributed_run import chunk_bounds, run_distributed
from substruct.studies.study_backend import Backend

CASES = Path(__file__).resolve().parent.parent / "cases"
BOX = CASES / "box_beam_tmd.yaml"
#: Two Craig-Bampton halves (two reduction tasks), a direct sweep with its kkt check.
QUICK = ["analysis.frf.omega={start: 300, stop: 4500, num: 23, spacing: log}"]


@pytest.mark.parametrize("n, chunks", [(23, 4), (5, 8), (100, 1), (7, 7)])
def test_chunks_cover_the_grid_in_order_and_even(n, chunks):
    bounds = chunk_bounds(n, chunks)
    assert [i for a, b in bounds for i in range(a, b)] == list(range(n))
    sizes = [b - a for a, b in bounds]
    assert len(bounds) == min(n, chunks) and max(sizes) - min(sizes) <= 1


@pytest.fixture(scope="module")
def serial():
    return run_case(load_case(BOX, QUICK))


def test_chunked_sweep_in_process_is_the_serial_sweep(serial):
    chunked = run_distributed(load_case(BOX, QUICK), Backend(), chunks=4)
    assert chunked.frf is not None and serial.frf is not None
    assert np.array_equal(chunked.frf.omega, serial.frf.omega)
    assert np.array_equal(chunked.frf.H, serial.frf.H)
    assert chunked.modes is not None and serial.modes is not None
    assert np.array_equal(chunked.modes.omega, serial.modes.omega)
    # each chunk checked on its own: the largest figure bounds the whole sweep's
    for name, value in serial.frf.agreement.items():
        assert chunked.frf.agreement[name] >= value * (1 - 1e-12)
        assert chunked.frf.agreement[name] < 1e-9


def test_a_modal_sweep_is_not_split():
    case = load_case(CASES / "tapered_rod_tuning.yaml",
                     ["analysis.frf.omega={start: 30, stop: 39, num: 91, spacing: linear}"])
    a, b = run_case(case), run_distributed(case, Backend(), chunks=4)
    assert a.frf is not None and b.frf is not None
    assert np.array_equal(a.frf.H, b.frf.H) and a.frf.agreement == b.frf.agreement


SCRIPT = """
import sys, json
import numpy as np
from substruct.case.loader import load_case
from substruct.studies.distributed_run import run_distributed
from substruct.studies.study_backend import Backend
a = json.loads(sys.argv[1])
r = run_distributed(load_case(a["case"], a["overrides"]), Backend(workers=2), chunks=4)
np.savez(a["out"], H=r.frf.H, omega=r.frf.omega, modes=r.modes.omega)
"""


def test_reductions_and_chunks_on_a_two_worker_local_cluster(serial, tmp_path):
    out = tmp_path / "dask.npz"
    done = subprocess.run([sys.executable, "-c", SCRIPT, json.dumps(
        {"case": str(BOX), "overrides": QUICK, "out": str(out)})], capture_output=True,
        text=True, env={**os.environ, "OMP_NUM_THREADS": "1"}, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    got = np.load(out)
    assert serial.frf is not None and serial.modes is not None
    assert np.array_equal(got["omega"], serial.frf.omega)
    # the reductions ran on workers (one thread each), the serial run here: equal to round-off
    assert np.allclose(got["H"], serial.frf.H, rtol=0, atol=1e-12 * np.abs(serial.frf.H).max())
    assert np.allclose(got["modes"], serial.modes.omega, rtol=1e-12)
