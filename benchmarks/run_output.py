"""``substruct run`` on a big output against its library call, and its start-up against bare imports.

    OMP_NUM_THREADS=1 python benchmarks/run_output.py [--frequencies 1000] [--repeat 3]
                                                      [--startup-repeat 9] [--quick]
                                                      [--skip-startup | --startup-only]

Big output: the two tied 200-mass chains of ``benchmarks/frf_sweep.py``, all 400 x 400
receptances at ``--frequencies`` frequencies (1,000: a 2.56 GB result), each side a fresh
process (imports, Numba's compilation and the first touch of the output's pages counted):

(a) the library: a process that imports substruct, builds the chains' matrices, calls
    ``substruct.analysis.api.receptance_sweep`` (timed: the library time) and writes the
    array to a raw file with ``ndarray.tofile`` (timed: the time to write the output);
(b) the command: ``python -m substruct.cli run two_chains.yaml --quiet --no-pictures`` (the
    case of ``frf_sweep.py``: two ``matrices`` substructures from Matrix Market files, the
    tie, ``frf`` with the 400 inputs and outputs), writing the HDF5 result file.

Printed: (a) the sweep and the write, (b) the whole command, (c) the ratio of (b) to (a)'s
sweep + write (target 1.3) and to (a)'s whole process, (d) the peak resident set of (b)'s
largest process against the size of the result file (target: at most the size + 1 GB).  The
files are compared in a process of their own: Linux carries a process's peak resident set
over into the processes it starts, so the benchmark's own process must stay small for (d) to
be the command's (comparing in it, through a mapping of the 2.56 GB raw file, made every
later (b) read 2.6 GB whatever the command used).  The
two run in turn, ``--repeat`` times; medians.  Times are CPU seconds (user + system, of the
process and the children it waited for: ``wait4``), which a machine shared with other jobs
disturbs far less than the wall clock (printed too).  (b)'s receptances are compared with
(a)'s: they must be equal bit for bit.

Start-up (e): the tapered rod of ``cases/tapered_rod_fe.yaml`` with 4,000 P2 elements (8,006
coordinates, 6 modes and the variant without the constraint, each checked), ``substruct run
--quiet --no-pictures``, against ``python -c "import numpy, scipy.sparse.linalg, h5py"``,
in turn, ``--startup-repeat`` times; medians; target: the run at most 2x the bare imports.
``--startup-only`` runs (e) alone.  The load average of the machine before and after (e) is
printed: on a shared machine the ratio is steady only while the load is.
Both with Python's bytecode cache on, as an installed package has it (without it, the
``substruct`` process compiles its 100-odd modules at every start: 0.15-0.3 s more).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
from frf_sweep import N_CHAIN, case_text, chains  # noqa: E402
from fbs_common import child  # noqa: E402

BARE = "import numpy, scipy.sparse.linalg, h5py"
ROD = ["--set", "substructures[0].discretization.elements=4000"]


def worker_library(frequencies: int, raw: str) -> None:
    """(a), in its own process: the sweep and the raw write, timed; one JSON line."""
    from substruct.analysis.api import receptance_sweep
    import scipy.sparse as sp

    K, M, C, B = chains()
    n = K.shape[0]
    w = np.linspace(1.0, 150.0, frequencies)
    c0, t0 = time.process_time(), time.perf_counter()
    res = receptance_sweep(K, M, C, B, w, sp.eye_array(n, format="csc"),
                           sp.eye_array(n, format="csr"))
    c1, t1 = time.process_time(), time.perf_counter()
    res.H.tofile(raw)
    c2, t2 = time.process_time(), time.perf_counter()
    print(json.dumps({"sweep_cpu": c1 - c0, "sweep_wall": t1 - t0, "write_cpu": c2 - c1,
                      "write_wall": t2 - t1, "bytes": res.H.nbytes, "shape": res.H.shape}))


def write_case(work: Path, frequencies: int) -> Path:
    import scipy.io
    import scipy.sparse as sp

    K, M, C, _ = chains()
    n = N_CHAIN
    files = {}
    for name, X in (("K", K), ("M", M), ("C", C)):
        path = work / f"chain_{name}.mtx"
        scipy.io.mmwrite(path, sp.coo_matrix(X[:n, :n]), symmetry="symmetric")
        files[name] = path.name
    case = work / "two_chains.yaml"
    case.write_text(case_text(n, np.linspace(1.0, 150.0, frequencies), files))
    return case


def same_receptances(h5: Path, raw: Path, shape: tuple[int, ...]) -> bool:
    """Whether the result file holds (a)'s array, compared a block of frequencies at a time."""
    import h5py

    ref = np.memmap(raw, dtype=complex, mode="r", shape=shape)
    with h5py.File(h5, "r") as f:
        ds = f["frf/H"]
        if ds.shape != shape:
            return False
        step = max(1, (64 << 20) // (shape[1] * shape[2] * 16))
        return all(np.array_equal(ds[k:k + step], ref[k:k + step])
                   for k in range(0, shape[0], step))


def worker_compare(h5: str, raw: str, shape: str) -> None:
    """In its own process (:func:`same_receptances`): one JSON line."""
    dims = tuple(int(d) for d in shape.split(","))
    print(json.dumps({"equal": same_receptances(Path(h5), Path(raw), dims)}))


def big_output(opts: argparse.Namespace, env: dict, work: Path) -> None:
    case = write_case(work, opts.frequencies)
    raw = work / "H.raw"
    lib_cmd = [sys.executable, __file__, "--worker", "library", "--frequencies",
               str(opts.frequencies), "--raw", str(raw)]
    run_cmd = [sys.executable, "-m", "substruct.cli", "run", str(case), "--out",
               str(work / "out"), "--force", "--quiet", "--no-pictures"]
    a_rows, b_rows, equal = [], [], True
    for _ in range(opts.repeat):
        a = child(lib_cmd, env, ROOT)
        a.update(json.loads(a["out"].strip().splitlines()[-1]))
        b = child(run_cmd, env, ROOT)
        h5 = work / "out" / "two_chains.h5"
        b["size"] = h5.stat().st_size
        compare = child([sys.executable, __file__, "--worker", "compare", "--raw", str(raw),
                         "--h5", str(h5), "--shape", ",".join(str(d) for d in a["shape"])],
                        env, ROOT)
        equal = equal and json.loads(compare["out"].strip().splitlines()[-1])["equal"]
        raw.unlink()
        a_rows.append(a)
        b_rows.append(b)

    def med(rows: list[dict], key: str) -> float:
        return statistics.median(r[key] for r in rows)

    lib = med(a_rows, "sweep_cpu") + med(a_rows, "write_cpu")
    lib_wall = med(a_rows, "sweep_wall") + med(a_rows, "write_wall")
    size, peak = med(b_rows, "size"), max(r["peak"] for r in b_rows)
    print(f"\nBig output: two tied 200-mass chains, {opts.frequencies} frequencies x 400 x 400 "
          f"receptances ({size / 1e9:.2f} GB result file), {opts.repeat} alternate runs, "
          f"medians")
    print(f"{'row':58s} {'CPU s':>8s} {'wall s':>8s} {'peak GB':>8s}")
    print(f"{'(a) library: receptance_sweep (fresh process, 1st call)':58s} "
          f"{med(a_rows, 'sweep_cpu'):8.2f} {med(a_rows, 'sweep_wall'):8.2f}")
    print(f"{'(a) library: write the output (ndarray.tofile)':58s} "
          f"{med(a_rows, 'write_cpu'):8.2f} {med(a_rows, 'write_wall'):8.2f}")
    print(f"{'(a) library: sweep + write':58s} {lib:8.2f} {lib_wall:8.2f}")
    print(f"{'(a) library: whole process (imports, model, sweep, write)':58s} "
          f"{med(a_rows, 'cpu'):8.2f} {med(a_rows, 'wall'):8.2f} "
          f"{max(r['peak'] for r in a_rows) / 1e9:8.2f}")
    print(f"{'(b) substruct run --quiet --no-pictures (whole process)':58s} "
          f"{med(b_rows, 'cpu'):8.2f} {med(b_rows, 'wall'):8.2f} {peak / 1e9:8.2f}")
    print(f"{'(c) ratio (b) / (a) sweep + write (target <= 1.3)':58s} "
          f"{med(b_rows, 'cpu') / lib:8.2f} {med(b_rows, 'wall') / lib_wall:8.2f}")
    print(f"{'(c) ratio (b) / (a) sweep alone':58s} "
          f"{med(b_rows, 'cpu') / med(a_rows, 'sweep_cpu'):8.2f} "
          f"{med(b_rows, 'wall') / med(a_rows, 'sweep_wall'):8.2f}")
    print(f"{'(c) ratio (b) / (a) whole process':58s} "
          f"{med(b_rows, 'cpu') / med(a_rows, 'cpu'):8.2f} "
          f"{med(b_rows, 'wall') / med(a_rows, 'wall'):8.2f}")
    print(f"{'(d) peak of (b) - result file size (target <= 1 GB)':58s} {'':8s} {'':8s} "
          f"{(peak - size) / 1e9:8.2f}")
    print(f"(b)'s receptances equal to (a)'s, bit for bit: {'yes' if equal else 'NO'}")
    print("each run, CPU s (a sweep + write | b): " + ", ".join(
        f"{a['sweep_cpu'] + a['write_cpu']:.2f} | {b['cpu']:.2f}" for a, b in zip(a_rows, b_rows)))


def startup(opts: argparse.Namespace, env: dict, work: Path) -> None:
    rod = [sys.executable, "-m", "substruct.cli", "run", "cases/tapered_rod_fe.yaml", *ROD,
           "--out", str(work / "rod"), "--force", "--quiet", "--no-pictures"]
    bare = [sys.executable, "-c", BARE]
    child(rod, env, ROOT)  # a first run: the files of both in the page cache
    load_before = os.getloadavg()[0]
    runs = [(child(rod, env, ROOT), child(bare, env, ROOT)) for _ in range(opts.startup_repeat)]
    load_after = os.getloadavg()[0]
    cpu_r = statistics.median(r["cpu"] for r, _ in runs)
    cpu_b = statistics.median(b["cpu"] for _, b in runs)
    wall_r = statistics.median(r["wall"] for r, _ in runs)
    wall_b = statistics.median(b["wall"] for _, b in runs)
    print(f"\nStart-up: 8k-DOF rod (cases/tapered_rod_fe.yaml, 4,000 P2 elements), "
          f"{opts.startup_repeat} alternate runs, medians; load average {load_before:.1f} "
          f"before, {load_after:.1f} after")
    print(f"{'row':58s} {'CPU s':>8s} {'wall s':>8s}")
    print(f"{'(e) substruct run --quiet --no-pictures, 8,006 coordinates':58s} "
          f"{cpu_r:8.2f} {wall_r:8.2f}")
    label = f'(e) python -c "{BARE}"'
    print(f"{label:58s} {cpu_b:8.2f} {wall_b:8.2f}")
    print(f"{'(e) ratio (target <= 2)':58s} {cpu_r / cpu_b:8.2f} {wall_r / wall_b:8.2f}")
    print("each pair, CPU s (run | bare): " + ", ".join(
        f"{r['cpu']:.2f} | {b['cpu']:.2f}" for r, b in runs))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frequencies", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--startup-repeat", type=int, default=9)
    parser.add_argument("--quick", action="store_true",
                        help="200 frequencies, one run, three start-up runs")
    parser.add_argument("--skip-startup", action="store_true", help="the big output only")
    parser.add_argument("--startup-only", action="store_true", help="the start-up (e) only")
    parser.add_argument("--worker", choices=["library", "compare"], help=argparse.SUPPRESS)
    parser.add_argument("--raw", help=argparse.SUPPRESS)
    parser.add_argument("--h5", help=argparse.SUPPRESS)
    parser.add_argument("--shape", help=argparse.SUPPRESS)
    opts = parser.parse_args()
    if opts.skip_startup and opts.startup_only:
        parser.error("--skip-startup and --startup-only exclude each other")
    if opts.worker == "library":
        worker_library(opts.frequencies, opts.raw)
        return
    if opts.worker == "compare":
        worker_compare(opts.h5, opts.raw, opts.shape)
        return
    if opts.quick:
        opts.frequencies, opts.repeat, opts.startup_repeat = 200, 1, 3
    env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
           "MKL_NUM_THREADS": "1", "MPLBACKEND": "Agg",
           "PYTHONPATH": os.pathsep.join([str(ROOT), *filter(None, [os.environ.get(
               "PYTHONPATH")])])}
    env.pop("PYTHONDONTWRITEBYTECODE", None)  # bytecode cached, as an installed package has it
    import h5py
    import scipy

    print(f"# {platform.processor() or platform.machine()}, {os.cpu_count()} cores, Python "
          f"{platform.python_version()}, NumPy {np.__version__}, SciPy {scipy.__version__}, "
          f"h5py {h5py.__version__} (HDF5 {h5py.version.hdf5_version})")
    with tempfile.TemporaryDirectory() as tmp:
        if not opts.skip_startup:
            startup(opts, env, Path(tmp))
        if not opts.startup_only:
            big_output(opts, env, Path(tmp))


if __name__ == "__main__":
    main()
