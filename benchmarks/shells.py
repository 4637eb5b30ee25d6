"""Shell benchmark: lowest 20 modes of a cantilever plate of DKQ shells in two tied halves.

    OMP_NUM_THREADS=1 python benchmarks/shells.py [--sizes 10000 100000] [--quick] [--repeat 1]

The model: a steel plate ``2 x 1`` m, 10 mm thick, in the ``x-y`` plane, clamped along
``x = 0`` (all six components of its nodes), made of two frames of one shell each
(``1 x 1`` m, ``n x n`` DKQ/QM6 quadrilaterals, consistent mass), tied at ``x = 1`` node to
node in all six components (``6 (n + 1)`` connection rows).  About ``12 (n + 1)^2``
coordinates: ``n = 28`` gives 10k, ``n = 90`` 99k (16,200 shell elements).

First, in this process, the element matrices' rate on 1,000 distorted quadrilaterals:
``shell_matrices`` one element at a time against ``shell_matrices_batch`` (elements/second).

Then for each size, each side in a fresh subprocess (peak memory is the process's high-water
mark ``VmHWM`` during the solve, reset before it through ``/proc/self/clear_refs``, as in
``modes.py``):

(a) substruct: ``assemble`` (stacking, the tie rows) + ``null_space_modes`` (master-slave
    elimination, ``T^T K T``, factorization, shift-invert ``eigsh``), the model (the two
    frames, their element matrices) built outside the timing;
(b) baseline: one frame of the whole plate (``2n x n`` elements: the tie eliminated by hand,
    the seam nodes shared), ``eigsh`` in shift-invert mode with ``OPinv`` from the same
    factorization and shift;
(r) ``substruct run plate.yaml --out <tmp> --force --quiet --no-pictures --json`` in a
    subprocess: the same two frames and the tie as a case file (``type: frame`` with
    ``shells:`` and ``divisions``, the tie as ``connections``), start-up, meshing, assembly,
    the production solve and its checks, the results file (as ``run_command.py``).

Time: wall clock (median of ``--repeat`` runs, one run when a run takes over 20 s) and CPU
time.  The frequencies of (a) and (r) are compared with (b).
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

sys.path.insert(0, str(Path(__file__).resolve().parent))
from modes import best_factorization, machine, timed_runs  # noqa: E402
from run_command import child  # noqa: E402

E, G, RHO, T = 2.1e11, 8.1e10, 7850.0, 0.01
N_MODES = 20


def panels(target: int) -> int:
    """``n``: elements along each side of a half for about ``target`` coordinates."""
    return max(2, int(round(np.sqrt(target / 12.0))) - 1)


def edge_ids(n: int) -> tuple[list[int], list[int]]:
    """Node ids of a half's edges ``x = x0`` and ``x = x0 + 1``, ``y = 0 .. 1``: the corners
    1, 4 and 2, 3, and between them nodes given at the places the shell's division makes
    (ids ``10 + j`` and ``10 + n + j``), so that supports and ties can name them (a node made by
    ``divisions`` that falls on a given node is that node: docs/structures.md)."""
    inner = list(range(1, n))
    return [1] + [10 + j for j in inner] + [4], [2] + [10 + n + j for j in inner] + [3]


def _nodes(x0: float, width: float, n: int) -> dict[int, list[float]]:
    """Corners and edge nodes of a ``width x 1`` rectangle from ``x = x0`` (``n`` elements
    along ``y``)."""
    out = {1: [x0, 0.0, 0.0], 2: [x0 + width, 0.0, 0.0], 3: [x0 + width, 1.0, 0.0],
           4: [x0, 1.0, 0.0]}
    a, b = edge_ids(n)
    for j in range(1, n):
        out[a[j]] = [x0, j / n, 0.0]
        out[b[j]] = [x0 + width, j / n, 0.0]
    return out


def _frame(name: str, x0: float, width: float, nx: int, ny: int, clamped: list[int]):
    from substruct.models.beam import Material
    from substruct.models.frame import frame
    from substruct.models.shell_mesh import Shell
    steel = Material(E=E, G=G, rho=RHO)
    return frame(name, _nodes(x0, width, ny), [], supports={i: "123456" for i in clamped},
                 shells=[Shell((1, 2, 3, 4), T, steel, (nx, ny))])


def halves(n: int):
    """The two frames and the tie rows (substruct API)."""
    from substruct.assembly.stack import Connection, PointRef
    edge0, edge1 = edge_ids(n)
    left = _frame("left", 0.0, 1.0, n, n, edge0)
    right = _frame("right", 1.0, 1.0, n, n, [])
    cons = []
    for a, b in zip(edge1, edge0):  # left's x = 1 edge is right's x = 1 edge
        for c in ("ux", "uy", "uz", "rx", "ry", "rz"):
            cons.append(Connection(PointRef("left", f"{a}:{c}"), PointRef("right", f"{b}:{c}")))
    return [left, right], cons


def monolithic(n: int):
    """The whole plate as one frame: ``(K, M)`` with the seam nodes shared."""
    whole = _frame("plate", 0.0, 2.0, 2 * n, n, edge_ids(n)[0])
    assert whole.meta["n_nodes"] == (2 * n + 1) * (n + 1)
    return whole.K, whole.M


def case_text(n: int) -> str:
    """The two halves and the tie as a case file."""
    edge0, edge1 = edge_ids(n)
    mat = f"{{steel: {{E: {E!r}, G: {G!r}, rho: {RHO!r}}}}}"

    def half(name: str, x0: float, clamped: list[int]) -> str:
        nodes = ", ".join(f"{i}: {xyz}" for i, xyz in _nodes(x0, 1.0, n).items())
        sup = ", ".join(f'{i}: "123456"' for i in clamped)
        return (f"  - name: {name}\n    type: frame\n    nodes: {{{nodes}}}\n"
                f"    materials: {mat}\n"
                f"    shells: [{{nodes: [1, 2, 3, 4], thickness: {T}, material: steel, "
                f"divisions: [{n}, {n}]}}]\n"
                + (f"    supports: {{{sup}}}\n" if clamped else ""))
    ties = "\n".join(f"  - [left@{a}:{c}, right@{b}:{c}]" for a, b in zip(edge1, edge0)
                     for c in ("ux", "uy", "uz", "rx", "ry", "rz"))
    return (f"name: plate\nsubstructures:\n{half('left', 0.0, edge0)}{half('right', 1.0, [])}"
            f"connections:\n{ties}\nanalysis:\n  modes: {{count: {N_MODES}}}\n"
            f"output: {{pictures: false}}\n")


def _status(key: str) -> int:
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(key):
                return int(line.split()[1]) * 1024
    return 0


def _reset_peak() -> None:
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
    except OSError:
        pass


def worker(kind: str, size: int, factorization: str, repeat: int) -> dict:
    """One measurement in this (fresh) process."""
    n = panels(size)
    t0 = time.perf_counter()
    if kind == "a":
        from substruct.analysis.modes.sparse import null_space_modes
        from substruct.assembly.stack import assemble
        subs, cons = halves(n)
        build = time.perf_counter() - t0

        def run():
            asm = assemble(subs, cons)
            modes = null_space_modes(asm.M, asm.K, asm.A, N_MODES, factorization=factorization)
            return asm.n_dof, modes.omega
    else:
        from substruct.linalg.factorize import factorizer
        K, M = monolithic(n)
        build = time.perf_counter() - t0

        def run():
            sigma = -1e-9 * K.diagonal().sum() / M.diagonal().sum()
            solve = factorizer(factorization)(sp.csc_array(K - sigma * M))
            op = spla.LinearOperator(K.shape, matvec=solve, dtype=float)
            v0 = np.random.default_rng(0).standard_normal(K.shape[0])
            lam = spla.eigsh(K, k=N_MODES, M=M, sigma=sigma, OPinv=op, v0=v0,
                             return_eigenvectors=False)
            return K.shape[0], np.sqrt(np.sort(lam))
    gc.collect()
    _reset_peak()
    times, cpu, (n_dof, omega) = timed_runs(run, repeat)
    return {"n": int(n_dof), "time": statistics.median(times), "cpu": statistics.median(cpu),
            "peak": _status("VmHWM"), "build": build, "panels": n,
            "omega": np.asarray(omega)[:N_MODES].tolist()}


def measure(kind: str, size: int, factorization: str, repeat: int, env: dict) -> dict:
    """A worker's measurement, with its whole process's wall and CPU time and peak."""
    cmd = [sys.executable, __file__, "--worker", kind, "--size", str(size),
           "--factorization", factorization, "--repeat", str(repeat)]
    wall, peak, out, cpu = child(cmd, env)
    data = json.loads(out.strip().splitlines()[-1])
    return {**data, "proc_time": wall, "proc_cpu": cpu, "proc_peak": peak}


def run_case(size: int, env: dict, work: Path) -> dict:
    case = work / f"plate_{size}.yaml"
    case.write_text(case_text(panels(size)))
    exe = str(Path(sys.executable).parent / "substruct")
    wall, peak, out, cpu = child([exe, "run", str(case), "--out", str(work / f"out_{size}"),
                                  "--force", "--quiet", "--no-pictures", "--json"], env)
    data = json.loads(out)
    return {"time": wall, "cpu": cpu, "peak": peak, "n": data["model"]["n_dof"],
            "omega": data["modes"]["omega"], "method": data["modes"]["method"],
            "agreement": data["modes"]["agreement"]}


def element_rates(m: int = 1000) -> tuple[float, float, float]:
    """Quadrilaterals a second, one at a time and batched, and the largest difference over
    the element's norm."""
    from substruct.models.shell import shell_matrices
    from substruct.models.shell_batch import shell_matrices_batch
    rng = np.random.default_rng(0)
    base = np.array([[0, 0, 0], [1, 0, 0], [1.1, 0.9, 0], [0.1, 1, 0]], float)
    X = base[None] + 0.1 * rng.standard_normal((m, 4, 3)) * np.array([1, 1, 0.05])
    t0 = time.process_time()
    ref = [shell_matrices(x, E, E / (2 * G) - 1, T, RHO)[0] for x in X]
    t1 = time.process_time()
    K, _ = shell_matrices_batch(X, E, E / (2 * G) - 1, T, RHO)
    t2 = time.process_time()
    diff = max(float(np.abs(K[e] - ref[e]).max() / np.linalg.norm(ref[e])) for e in range(m))
    return m / (t1 - t0), m / (t2 - t1), diff


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[10000, 100000])
    parser.add_argument("--quick", action="store_true", help="10k only, one run")
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--no-case", action="store_true", help="skip (r)")
    parser.add_argument("--worker", choices=["a", "b"], help=argparse.SUPPRESS)
    parser.add_argument("--size", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--factorization", default=None, help=argparse.SUPPRESS)
    opts = parser.parse_args()
    fact = opts.factorization or best_factorization()
    if opts.worker:
        print(json.dumps(worker(opts.worker, opts.size, fact, opts.repeat)))
        return
    env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
           "MKL_NUM_THREADS": "1", "MPLBACKEND": "Agg"}
    print(f"machine: {machine()}")
    print(f"factorization: {fact} (the baseline's and substruct's)")
    one, batch, diff = element_rates()
    print(f"element matrices (CPU): {one:,.0f} quads/s one at a time, {batch:,.0f} quads/s "
          f"batched ({batch / one:.1f}x), largest difference {diff:.1e} of the element norm")
    sizes = [10000] if opts.quick else opts.sizes
    print(f"\n{'n':>8} {'quads':>6} {'a: s':>7} {'a: cpu':>7} {'a: MB':>6} {'b: s':>7} "
          f"{'b: cpu':>7} {'b: MB':>6} {'a/b t':>6} {'a/b cpu':>7} {'a/b mem':>7} "
          f"{'|wa/wb-1|':>9} {'build s':>7} {'r: s':>7} {'r: cpu':>7} {'r: MB':>6} "
          f"{'r/b pcpu':>8} {'|wr/wb-1|':>9}")
    with tempfile.TemporaryDirectory() as tmp:
        for size in sizes:
            a = measure("a", size, fact, opts.repeat, env)
            b = measure("b", size, fact, opts.repeat, env)
            wb = np.asarray(b["omega"])
            da = float(np.max(np.abs(np.asarray(a["omega"]) / wb - 1)))
            line = (f"{a['n']:>8} {2 * a['panels'] ** 2:>6} {a['time']:>7.2f} {a['cpu']:>7.2f} "
                    f"{a['peak'] / 2**20:>6,.0f} {b['time']:>7.2f} {b['cpu']:>7.2f} "
                    f"{b['peak'] / 2**20:>6,.0f} {a['time'] / b['time']:>6.2f} "
                    f"{a['cpu'] / b['cpu']:>7.2f} {a['peak'] / b['peak']:>7.2f} {da:>9.1e} "
                    f"{a['build']:>7.1f}")
            if not opts.no_case:
                r = run_case(size, env, Path(tmp))
                dr = float(np.max(np.abs(np.asarray(r["omega"][:N_MODES]) / wb - 1)))
                line += (f" {r['time']:>7.2f} {r['cpu']:>7.2f} {r['peak'] / 2**20:>6,.0f} "
                         f"{r['cpu'] / b['proc_cpu']:>8.2f} {dr:>9.1e}")
                print(line, flush=True)
                print(f"         (r) {r['method']}, checks "
                      f"{', '.join(f'{k} {v:.1e}' for k, v in r['agreement'].items())}",
                      flush=True)
            else:
                print(line, flush=True)
            print(f"         b: whole process {b['proc_time']:.1f} s, CPU {b['proc_cpu']:.1f} s, "
                  f"peak {b['proc_peak'] / 2**20:,.0f} MB; f1 = {wb[0] / 2 / np.pi:.4f} Hz ... "
                  f"f20 = {wb[-1] / 2 / np.pi:.4f} Hz", flush=True)


if __name__ == "__main__":
    main()
