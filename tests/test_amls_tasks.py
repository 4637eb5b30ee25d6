"""The AMLS reduction's blocks as tasks: the same eigenpairs bit for bit whether each tree
level runs in this process or on a 2-worker Dask LocalCluster (127.0.0.1); ``substruct run
--workers 2`` with ``solver: amls`` prints each level and writes the same modes as the
in-process run; ``--workers`` on a case without AMLS is refused (exit 2, nothing written).

The Dask runs are in a subprocess of their own (Dask's threads stay out of pytest), with one
BLAS thread in the subprocess and in the workers."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from counting_tasks import COUNTING
from two_boxes import two_boxes_case

ROOT = Path(__file__).resolve().parent.parent
ENV = {**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1",
       "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "MPLBACKEND": "Agg"}

SCRIPT = """
import sys
import numpy as np
import scipy.sparse as sp
from substruct.linalg.amls import amls_modes
from substruct.linalg.amls_tree import dissection_tree
from substruct.models.solid import BoxGrid, solid_box
from substruct.studies.study_backend import Backend, Session
b = solid_box("b", BoxGrid((4.0, 1.0, 1.0), (16, 4, 4)), 2.1e11, 0.3, 7850.0,
              fixed=[{"box": [[0, 0, 0], [0, 1, 1]]}])
K, M = sp.csr_array(b.K), sp.csr_array(b.M)
kw = dict(cutoff=3.0, leaf_size=100, iterations=1, ritz_ratio=2.0)
serial = amls_modes(K, M, 3000.0, **kw)
tree = dissection_tree(K, 100).postorder()
""" + COUNTING + """
with Session(Backend(workers=2)) as s:
    where = Counting(s)
    dask = amls_modes(K, M, 3000.0, tasks=where, **kw)
np.savez(sys.argv[1], lam_s=serial.lam, U_s=serial.U, res_s=serial.residual,
         lam_d=dask.lam, U_d=dask.U, res_d=dask.residual,
         calls=np.array(where.counts()),
         blocks=np.array([len(tree), sum(not b.is_leaf for b in tree)]))
"""


def test_dask_local_cluster_gives_the_same_bits(tmp_path):
    out = tmp_path / "amls.npz"
    done = subprocess.run([sys.executable, "-c", SCRIPT, str(out)], capture_output=True,
                          text=True, env=ENV, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    r = np.load(out)
    assert r["lam_s"].size >= 6
    assert np.array_equal(r["lam_s"], r["lam_d"])
    assert np.array_equal(r["U_s"], r["U_d"])
    assert np.array_equal(r["res_s"], r["res_d"])
    # every block a submitted task, split into its kept part and (but the root's) its
    # condensation, both tasks given the block's future; every separator's task given its
    # children's condensations as futures; one map for the subdomains' expansion
    maps, submits, chained = r["calls"]
    blocks, separators = r["blocks"]
    assert separators >= 3
    assert maps == 1 and submits == 3 * blocks - 1
    assert chained == separators + 2 * blocks - 1


CAPPED = """
import sys
import numpy as np
import scipy.sparse as sp
from substruct.linalg.amls_reduce import amls_reduce
from substruct.linalg.amls_tree import dissection_tree
from substruct.linalg.task_runner import IN_PROCESS
from substruct.models.solid import BoxGrid, solid_box
from substruct.studies.study_backend import Backend, Session
b = solid_box("b", BoxGrid((4.0, 1.0, 1.0), (16, 4, 4)), 2.1e11, 0.3, 7850.0,
              fixed=[{"box": [[0, 0, 0], [0, 1, 1]]}])
K, M = sp.csr_array(b.K), sp.csr_array(b.M)
tree = dissection_tree(K, 100)
blocks = len(tree.postorder())
lam_cut = (3 * 3000.0) ** 2
""" + COUNTING + """
class Capped(Counting):
    def __init__(self, s, cap):
        super().__init__(s)
        self.cap = cap
    def task_memory(self):
        return self.cap
serial = amls_reduce(K, M, tree, lam_cut)
for cap in 2.0 ** np.arange(10, 34):  # a worker's limit that keeps a few blocks here
    here = amls_reduce(K, M, tree, lam_cut, tasks=Capped(IN_PROCESS, int(cap))).blocks_here
    if 0 < here < blocks // 2:
        break
Y = np.random.default_rng(1).standard_normal((serial.size, 5))
with Session(Backend(workers=2)) as s:
    where = Capped(s, int(cap))
    lines = []
    dask = amls_reduce(K, M, tree, lam_cut, tasks=where, progress=lines.append)
    X = dask.expand(Y, where)
np.savez(sys.argv[1], lam_s=serial.lam, lam_d=dask.lam, X_s=serial.expand(Y), X_d=X,
         M_diff=(serial.M != dask.M).nnz, here=dask.blocks_here, blocks=blocks,
         calls=np.array(where.counts()), said=np.array(lines[:1]))
"""


def test_blocks_too_large_for_a_worker_are_reduced_here_with_the_same_bits(tmp_path):
    """A worker's memory limit (here made small) below what a block's task would hold: that
    block and every one above it are reduced in this process, the rest on the workers; the
    reduced pencil and its expansion are the same bit for bit."""
    out = tmp_path / "capped.npz"
    done = subprocess.run([sys.executable, "-c", CAPPED, str(out)], capture_output=True,
                          text=True, env=ENV, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    r = np.load(out)
    here, blocks = int(r["here"]), int(r["blocks"])
    assert 0 < here < blocks // 2
    assert np.array_equal(r["lam_s"], r["lam_d"]) and int(r["M_diff"]) == 0
    assert np.array_equal(r["X_s"], r["X_d"])
    # only the blocks not reduced here were tasks (three submits each: the block, its kept
    # part, its condensation; the root is among those reduced here)
    maps, submits, chained = r["calls"]
    assert submits == 3 * (blocks - here)
    assert str(r["said"][0]).startswith(f"AMLS: {here} of {blocks} blocks would hold more")


CASE = two_boxes_case("tied", """\
  modes: {count: 8, solver: SOLVER, tolerance: 0.05, amls: AMLS}
""")


def _cli(tmp_path: Path, name: str, extra: list[str], solver: str = "amls"):
    case = tmp_path / f"{name}.yaml"
    amls = "{leaf_size: 100, iterations: 1}" if solver == "amls" else "null"
    case.write_text(CASE.replace("SOLVER", solver).replace("AMLS", amls))
    args = [sys.executable, "-m", "substruct.cli", "run", str(case), "--out",
            str(tmp_path / name), *extra]
    return subprocess.run(args, capture_output=True, text=True, timeout=600,
                          env={**ENV, "SUBSTRUCT_PROGRESS": "1"}, cwd=tmp_path)


def test_run_with_workers_prints_levels_and_writes_the_same_modes(tmp_path):
    h5py = pytest.importorskip("h5py")
    serial = _cli(tmp_path, "serial", [])
    assert serial.returncode == 0, serial.stderr[-3000:]
    dask = _cli(tmp_path, "dask", ["--workers", "2"])
    assert dask.returncode == 0, dask.stderr[-3000:]
    levels = [line for line in dask.stderr.splitlines() if "AMLS level" in line]
    assert levels and levels[-1].split("AMLS level ")[1].startswith("0 (")
    assert "AMLS tasks on LocalCluster (2 workers)" in dask.stderr
    assert [line for line in serial.stderr.splitlines() if "AMLS level" in line]

    def modes(name):
        with h5py.File(tmp_path / name / "tied.h5", "r") as f:
            return {k: f["modes"][k][()] for k in ("omega", "shapes")}
    a, b = modes("serial"), modes("dask")
    assert np.array_equal(a["omega"], b["omega"]) and np.array_equal(a["shapes"], b["shapes"])


def test_workers_without_amls_is_refused(tmp_path):
    done = _cli(tmp_path, "sparse", ["--workers", "2"], solver="sparse")
    assert done.returncode == 2
    assert done.stderr.strip() == ("substruct: error: --workers: runs the blocks of an AMLS "
                                   "reduction or the samples of a virtual-point Monte Carlo "
                                   "study as tasks; the case has no virtual_points.monte_carlo"
                                   " and no solver: amls in analysis.modes or the modal "
                                   "block of analysis.frf, random or transient, got "
                                   "analysis.modes.solver sparse")
    assert not (tmp_path / "sparse").exists()


def test_run_checks_the_scheduler_address_before_anything(tmp_path):
    done = _cli(tmp_path, "bad", ["--scheduler", "http://127.0.0.1:8786"])
    assert done.returncode == 2
    assert done.stderr.startswith("substruct: error: --scheduler: protocol http:// is not "
                                  "supported"), done.stderr
    assert len(done.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "bad").exists()
