"""FRF sweep benchmark: every receptance of two coupled chains, by substruct and by LM-FBS.

    OMP_NUM_THREADS=1 python benchmarks/frf_sweep.py [--frequencies 1000] [--repeat 3] [--quick]
        [--no-command] [--no-splu] [--pyfbs PYTHON]

The model: two fixed-free chains of 200 masses (``m = 1``, ``k = 1e4``, Rayleigh damping
``C = 1e-4 K + 0.5 M``), tied tip to tip (one constraint row): 400 coordinates.  All
400 x 400 receptances at ``--frequencies`` frequencies from 1 to 150 rad/s (the first 60 or so
coupled resonances), by

(p) pyFBS LM-FBS, as pyFBS's coupling example does it: the uncoupled receptances of the two
    chains stacked over the frequencies, ``Y`` (``F x 400 x 400``, block diagonal), the signed
    Boolean ``B`` (dense), and ``Y_c = Y - Y B^T (B Y B^T)^+ B Y`` evaluated left to right on
    the stacks (NumPy ``@``), the interface inverse by ``pyfbs.tpinv`` when pyFBS is importable
    (pyFBS 1.0.7 ships no coupling function: its LM-FBS is this expression in its examples),
    else ``numpy.linalg.pinv`` (the row then says "pyFBS-style").  The stacks are taken 100
    frequencies at a time (the same products; it bounds the memory).  Two times: the whole
    route (the uncoupled receptances by inversion of the stacked impedances included) and the
    coupling alone (the receptances given, as a pyFBS user's measured FRFs are);
(l) lean LM-FBS in NumPy: the same formula a frequency at a time, with the dense inverses of
    the two 200 x 200 impedances and ``Y B^T`` formed first (no 400 x 400 x 400 product);
(a) substruct: ``analysis.api.receptance_sweep`` (the production path: the null-space sweep on
    the master-slave basis, the band LU of ``T^T Z(w) T`` a frequency, every input in one
    solve by the compiled substitutions; its checks at three frequencies included);
(b) ``scipy.sparse.linalg.splu`` of the same reduced impedance at each frequency, solved for
    all inputs, ``H = T X``;
(r) ``substruct run`` of the same model as a case file (two ``matrices`` substructures from
    Matrix Market files, the tie, ``frf`` with the 400 inputs and outputs) in a subprocess,
    ``--no-pictures``: start-up, case checks, the sweep, the HDF5 file of 2.6 GB;
(w) the floor: writing the 400 x 400 complex outputs of every frequency into a new array (the
    page faults of 2.6 GB of output at 1,000 frequencies, paid by every route);
(f) (a) as a fresh process: start-up, the imports (Numba's included), building the chains, the
    sweep (loading the compiled substitutions from Numba's cache), the answer held in memory;
    and (p) as a fresh process when ``--pyfbs PYTHON`` names the Python of an environment with
    pyFBS (not a dependency): (p) then runs in that process (``pyfbs`` imported there), timed
    inside it and as the whole process, instead of in this one.  A fresh process hands back
    its times and its answer at three frequencies (first, middle, last), compared with (l).

Time: median of ``--repeat`` runs of (a), (w) and (r), one run of the slow routes (l), (p),
(b); wall clock and CPU time (of the process, or of the child for (r) and (f)).  The answers
are compared with (l): ``max |H - H_l| / max |H_l|``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import scipy
import scipy.io
import scipy.sparse as sp
import scipy.sparse.linalg as spla

try:  # optional: pip install pyFBS (not a dependency of substruct)
    import pyfbs
    from importlib.metadata import version
    PYFBS = version("pyFBS")
except ImportError:  # pragma: no cover - depends on the environment
    pyfbs = None
    PYFBS = ""

N_CHAIN, K_SPRING, MASS = 200, 1e4, 1.0
STACK = 100  # frequencies a stack of route (p)


def chains() -> tuple[sp.csr_array, sp.csr_array, sp.csr_array, sp.csr_array]:
    """``K, M, C, B`` of the two chains stacked and the tie of their tips."""
    n = N_CHAIN
    d = np.full(n, 2 * K_SPRING)
    d[-1] = K_SPRING
    Kc = sp.diags_array([-np.full(n - 1, K_SPRING), d, -np.full(n - 1, K_SPRING)],
                        offsets=[-1, 0, 1])
    K = sp.csr_array(sp.block_diag([Kc, Kc]))
    M = sp.csr_array(sp.eye_array(2 * n) * MASS)
    C = sp.csr_array(1e-4 * K + 0.5 * M)
    B = sp.csr_array(([1.0, -1.0], ([0, 0], [n - 1, 2 * n - 1])), shape=(1, 2 * n))
    return K, M, C, B


def route_substruct(K, M, C, B, w):
    from substruct.analysis.api import receptance_sweep
    n = K.shape[0]
    res = receptance_sweep(K, M, C, B, w, sp.eye_array(n, format="csc"),
                           sp.eye_array(n, format="csr"))
    return res.H, res


def route_direct_lu(K, M, C, B, w):
    from substruct.linalg.nullspace import master_slave
    T = sp.csc_array(master_slave(B).T)
    Kt, Mt, Ct = (sp.csc_array(T.T @ X @ T) for X in (K, M, C))
    Tt = T.T.toarray()
    Td = T.toarray()
    H = np.empty((len(w), K.shape[0], K.shape[0]), dtype=complex)
    for k, wk in enumerate(w):
        lu = spla.splu(sp.csc_array(Kt - wk**2 * Mt + 1j * wk * Ct))
        H[k] = Td @ lu.solve(Tt.astype(complex))
    return H, None


def route_lean_lmfbs(K, M, C, B, w):
    n = N_CHAIN
    Kd, Md, Cd, Bd = K.toarray(), M.toarray(), C.toarray(), B.toarray()
    H = np.empty((len(w), 2 * n, 2 * n), dtype=complex)
    Y = np.zeros((2 * n, 2 * n), dtype=complex)
    for k, wk in enumerate(w):
        Z = Kd - wk**2 * Md + 1j * wk * Cd
        Y[:n, :n] = np.linalg.inv(Z[:n, :n])
        Y[n:, n:] = np.linalg.inv(Z[n:, n:])
        YB = Y @ Bd.T
        H[k] = Y - YB @ np.linalg.pinv(Bd @ YB) @ (Bd @ Y)
    return H, None


def route_pyfbs(K, M, C, B, w):
    """Route (p); returns ``H`` and the CPU seconds of the coupling step alone."""
    n = N_CHAIN
    Kd, Md, Cd = K.toarray(), M.toarray(), C.toarray()
    Bu = Bf = B.toarray()
    H = np.empty((len(w), 2 * n, 2 * n), dtype=complex)
    coupling = 0.0
    for s in range(0, len(w), STACK):
        ws = w[s:s + STACK, None, None]
        Z = Kd[None] - ws**2 * Md[None] + 1j * ws * Cd[None]
        Y_A = np.linalg.inv(Z[:, :n, :n])  # the uncoupled receptances (a user's input)
        Y_B = np.linalg.inv(Z[:, n:, n:])
        del Z
        c0 = time.process_time()
        Y = np.zeros((len(ws), 2 * n, 2 * n), dtype=complex)
        Y[:, :n, :n], Y[:, n:, n:] = Y_A, Y_B
        Y_int = Bu @ Y @ Bf.T
        inv = pyfbs.tpinv(Y_int, trunc=0) if pyfbs is not None else np.linalg.pinv(Y_int)
        H[s:s + len(ws)] = Y - Y @ Bf.T @ inv @ Bu @ Y
        coupling += time.process_time() - c0
        del Y, Y_A, Y_B
    return H, coupling


def route_floor(K, M, C, B, w):
    block = np.ones((K.shape[0], K.shape[0]), dtype=complex)
    H = np.empty((len(w), K.shape[0], K.shape[0]), dtype=complex)
    for k in range(len(w)):
        H[k] = block
    return H, None


def case_text(n: int, w: np.ndarray, files: dict[str, str]) -> str:
    points = ", ".join(f"{s}@q{i}" for s in "AB" for i in range(1, n + 1))
    subs = "".join(
        f"  - name: {s}\n    type: matrices\n    K: {{file: {files['K']}}}\n"
        f"    M: {{file: {files['M']}}}\n    C: {{file: {files['C']}}}\n" for s in "AB")
    return (f"name: two_chains\nunits: \"N, m, kg, s\"\nsubstructures:\n{subs}"
            f"constraints:\n  - name: tie\n    terms: {{A@q{n}: 1, B@q{n}: -1}}\n"
            f"analysis:\n  frf:\n    omega: {{start: {w[0]}, stop: {w[-1]}, num: {len(w)}}}\n"
            f"    inputs: [{points}]\n    outputs: [{points}]\n"
            f"output: {{pictures: false}}\n")


def route_command(K, M, C, B, w, work: Path):
    """``substruct run`` in a subprocess: (wall, child CPU, child peak RSS bytes)."""
    n = N_CHAIN
    files = {}
    for name, X in (("K", K), ("M", M), ("C", C)):
        path = work / f"chain_{name}.mtx"
        scipy.io.mmwrite(path, sp.coo_matrix(X[:n, :n]), symmetry="symmetric")
        files[name] = path.name
    case = work / "two_chains.yaml"
    case.write_text(case_text(n, w, files))
    cmd = [sys.executable, "-m", "substruct.cli", "run", str(case), "--out", str(work / "out"),
           "--force", "--quiet", "--no-pictures"]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    out, err = proc.communicate()
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise RuntimeError(f"substruct run failed ({proc.returncode}): {err.decode()[-2000:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    size = sum(f.stat().st_size for f in (work / "out").glob("*.h5"))
    return wall, cpu, after.ru_maxrss * 1024.0, size


def timed(route, args, repeat: int):
    times, cpu, out = [], [], None
    for _ in range(repeat):
        out = None  # free the previous answer before the next run
        t0, c0 = time.perf_counter(), time.process_time()
        out = route(*args)
        times.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)

    return statistics.median(times), statistics.median(cpu), len(times), out


def picked(nw: int) -> np.ndarray:
    """The frequencies a fresh process hands back: first, middle, last."""
    return np.unique([0, nw // 2, nw - 1])


def worker(route: str, nw: int, dst: str) -> None:
    """A fresh process's route: (f) ``substruct`` or (p) ``pyfbs``; writes ``dst`` (``.npz``:
    the answer at :func:`picked`, the times inside the process)."""
    K, M, C, B = chains()
    w = np.linspace(1.0, 150.0, nw)
    c0 = time.process_time()
    if route == "substruct":
        H, res = route_substruct(K, M, C, B, w)
        extra = {"checks": {k: float(v) for k, v in res.agreement.items()}}
    else:
        H, coupling = route_pyfbs(K, M, C, B, w)
        extra = {"coupling": coupling, "pyfbs": PYFBS}
    extra["route_cpu"] = time.process_time() - c0
    with open("/proc/self/status") as status:  # this process's own peak (VmHWM, kB)
        extra["peak"] = next((float(line.split()[1]) * 1024.0 for line in status
                              if line.startswith("VmHWM")), float("nan"))
    np.savez(dst, H=H[picked(nw)], times=json.dumps(extra))


def fresh(python: str, route: str, nw: int, work: Path, env: dict) -> tuple[dict, np.ndarray]:
    """``worker(route)`` in ``python`` as a new process: its wall time and CPU (user + system
    of the whole process, ``wait4``), with the worker's own times and peak resident set
    (``VmHWM``: ``wait4``'s figure holds this process's peak, the child having started in its
    memory); and its answer at :func:`picked`."""
    dst = work / f"{route}.npz"
    cmd = [python, __file__, "--worker", route, "--frequencies", str(nw), str(dst)]
    with tempfile.TemporaryFile() as err:
        t0 = time.perf_counter()
        proc = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=err)
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - t0
        if os.waitstatus_to_exitcode(status) != 0:
            err.seek(0)
            raise RuntimeError(f"{' '.join(cmd)} failed: {err.read().decode()[-2000:]}")
    with np.load(dst) as z:
        inside, H = json.loads(str(z["times"])), z["H"]
    dst.unlink()
    return {"wall": wall, "cpu": usage.ru_utime + usage.ru_stime, **inside}, H


def difference(H, H_ref, scale: float) -> float:
    return max(float(np.abs(Hk - Rk).max()) for Hk, Rk in zip(H, H_ref)) / scale


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frequencies", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--quick", action="store_true", help="200 frequencies")
    parser.add_argument("--no-command", action="store_true", help="leave out (r)")
    parser.add_argument("--no-splu", action="store_true", help="leave out (b)")
    parser.add_argument("--pyfbs", help="the Python of an environment with pyFBS: (p) there")
    parser.add_argument("--worker", choices=["substruct", "pyfbs"], help=argparse.SUPPRESS)
    parser.add_argument("dst", nargs="?", help=argparse.SUPPRESS)
    opts = parser.parse_args()
    nw = 200 if opts.quick else opts.frequencies
    if opts.worker:
        worker(opts.worker, nw, opts.dst)
        return
    K, M, C, B = chains()
    w = np.linspace(1.0, 150.0, nw)
    args = (K, M, C, B, w)
    pyfbs_version = PYFBS
    if opts.pyfbs:
        probe = subprocess.run([opts.pyfbs, "-c", "from importlib.metadata import version; "
                                "import pyfbs; print(version('pyFBS'))"],
                               capture_output=True, text=True, env=dict(os.environ, PYTHONPATH=""))
        pyfbs_version = probe.stdout.strip() if probe.returncode == 0 else ""
    print(f"# {platform.processor() or platform.machine()}, Python {platform.python_version()},"
          f" NumPy {np.__version__}, SciPy {scipy.__version__}, "
          f"pyFBS {pyfbs_version or 'not importable'}, OMP_NUM_THREADS="
          f"{os.environ.get('OMP_NUM_THREADS', 'unset')}, NUMPY_MADVISE_HUGEPAGE="
          f"{os.environ.get('NUMPY_MADVISE_HUGEPAGE', 'unset')}, load average "
          f"{' '.join(f'{x:.1f}' for x in os.getloadavg())}")
    print(f"# two tied chains, {K.shape[0]} coordinates, {nw} frequencies x "
          f"{K.shape[0]} x {K.shape[0]} receptances")
    t_l, cpu_l, runs_l, (H_l, _) = timed(route_lean_lmfbs, args, 1)
    scale = max(float(np.abs(Hk).max()) for Hk in H_l)
    pick = picked(nw)
    rows = [("l LM-FBS lean (NumPy)", t_l, cpu_l, runs_l, 0.0)]
    label_p = (f"p pyFBS {pyfbs_version} LM-FBS" if pyfbs_version
               else "p pyFBS-style LM-FBS (no pyFBS)")
    if not opts.pyfbs:
        t, cpu, runs, (H, coupling) = timed(route_pyfbs, args, 1)
        rows.append((label_p, t, cpu, runs, difference(H, H_l, scale)))
        rows.append(("p  its coupling step alone", float("nan"), coupling, runs,
                     rows[-1][4]))
        del H
    notes = ""
    routes = [("a substruct receptance_sweep", route_substruct),
              ("b splu per frequency", route_direct_lu),
              ("w floor: write the outputs", route_floor)]
    for name, route in routes:
        if route is route_direct_lu and opts.no_splu:
            continue
        once = route is route_direct_lu
        t, cpu, runs, (H, res) = timed(route, args, 1 if once else opts.repeat)
        diff = difference(H, H_l, scale) if route is not route_floor else float("nan")
        rows.append((name, t, cpu, runs, diff))
        if res is not None:
            notes = f"# (a) method {res.method}, checks {res.agreement}"
        del H
    H_pick = H_l[pick].copy()
    del H_l
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parent.parent))
    with tempfile.TemporaryDirectory() as tmp:
        got, H = fresh(sys.executable, "substruct", nw, Path(tmp), env)
        rows.append(("f (a) as a fresh process", got["wall"], got["cpu"], 1,
                     difference(H, H_pick, scale)))
        notes += (f"\n# (f) the sweep inside the process {got['route_cpu']:.2f} s CPU, peak RSS "
                  f"{got['peak'] / 1e9:.2f} GB")
        if opts.pyfbs:
            got, H = fresh(opts.pyfbs, "pyfbs", nw, Path(tmp), dict(os.environ, PYTHONPATH=""))
            d = difference(H, H_pick, scale)
            rows.insert(1, (label_p + ", in its process", float("nan"), got["route_cpu"], 1,
                            d))
            rows.insert(2, ("p  its coupling step alone", float("nan"), got["coupling"], 1, d))
            rows.insert(3, ("p  the whole process", got["wall"], got["cpu"], 1, d))
            notes += f"\n# (p) the whole process's peak RSS {got['peak'] / 1e9:.2f} GB"
    if not opts.no_command:
        with tempfile.TemporaryDirectory() as tmp:
            runs = [route_command(K, M, C, B, w, Path(tmp)) for _ in range(opts.repeat)]
        t, cpu = statistics.median(r[0] for r in runs), statistics.median(r[1] for r in runs)
        rows.append(("r substruct run (command)", t, cpu, len(runs), float("nan")))
        notes += (f"\n# (r) peak RSS {max(r[2] for r in runs) / 1e9:.2f} GB, result file "
                  f"{runs[0][3] / 1e9:.2f} GB")
    cpu_p, cpu_pc = rows[1][2], rows[2][2]
    print(f"{'route':40s} {'wall (s)':>9s} {'CPU (s)':>9s} {'runs':>5s} "
          f"{'|H - H_l|/|H_l|':>16s} {'p/route CPU':>12s} {'p-coupling/route':>17s}")
    for name, t, cpu, runs, diff in rows:
        print(f"{name:40s} {t:9.2f} {cpu:9.2f} {runs:5d} {diff:16.1e} {cpu_p / cpu:12.1f} "
              f"{cpu_pc / cpu:17.1f}")
    print(notes)
    a = next(r for r in rows if r[0].startswith("a "))
    f = next(r for r in rows if r[0].startswith("f "))
    p_whole = next((r for r in rows if r[0].startswith("p  the whole")), None)
    which = "pyFBS" if pyfbs_version else "pyFBS-style, pyFBS not importable"
    print(f"# CPU ratios ({which}): pyFBS route / substruct = {cpu_p / a[2]:.1f}x warm, "
          f"{cpu_p / f[2]:.1f}x against (f) the fresh process"
          + (f", {p_whole[2] / f[2]:.1f}x fresh process against fresh process"
             if p_whole else "")
          + f"; pyFBS coupling step alone / substruct = {cpu_pc / a[2]:.1f}x warm, "
          f"{cpu_pc / f[2]:.1f}x fresh; lean LM-FBS / substruct = {cpu_l / a[2]:.1f}x warm")
    held = cpu_p / f[2] >= 20 and cpu_p / a[2] >= 20
    print(f"# target (a), >= 20x the pyFBS route, fresh process included: "
          f"{'holds' if held else 'does not hold'}")


if __name__ == "__main__":
    main()
