"""Factorization backends side by side on the benchmark box's matrices.

    OMP_NUM_THREADS=1 python benchmarks/factorization.py [--sizes 10000 30000] [--full]

The matrices, from the clamped box of benchmarks/modes.py (Q1 hexahedra, two tied halves, two
absorbers, one multi-point constraint) at about ``size`` coordinates:

- ``spd``: ``K - sigma M`` of the constrained model eliminated by hand (the shift-invert
  matrix of the modes, ``sigma = -1e-9 tr K / tr M``);
- ``symmetric``: the saddle-point (KKT) matrix ``[K - sigma M, s A^T; s A, 0]`` of the two
  halves and their tie and constraint rows (unit rows, ``s`` the mean stiffness diagonal), as
  the Lagrange-form eigensolves factorize it;
- ``complex-symmetric``: the impedance ``K - w^2 M + i w b K`` of the eliminated model at
  ``w = 2 pi 100 rad/s`` with stiffness-proportional damping ``b = 2 (0.01) / w`` (1 % at 100 Hz),
  as a frequency sweep factorizes it.

Each backend of substruct.linalg.backends that is installed and takes the matrix (whether or
not ``auto`` would choose it) is measured
in a fresh process (the matrix read from a file; peak memory is the process's high-water mark
``VmHWM`` during the factorization and solve, reset just before, less the resident memory
before): factorization time (median of 3 runs under 20 s, else one; wall clock and CPU), the
solve of a 20-column block, the relative residual ``||A X - B|| / (||A||_1 ||X||)``, and the
factor's stored entries where the backend tells them.  Ratios are to the fastest backend of the
same matrix in the same run, on CPU time (wall-clock time on a shared machine includes
waiting).  ``--full`` adds the 100k size (SuperLU without METIS is left out there unless
``--all``: minutes and 7 GB for the SPD matrix, more for the others).
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np
import scipy.sparse as sp

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from modes import _reset_peak, _status, machine, monolithic_model, substruct_model  # noqa: E402

KINDS = ("spd", "symmetric", "complex-symmetric")
RHS = 20
HZ = 100.0


def build(kind: str, size: int) -> sp.csr_array:
    """The benchmark matrix ``kind`` at about ``size`` coordinates (module docstring)."""
    if kind == "symmetric":
        from substruct.analysis.modes.krylov import check_inputs, default_shift, eliminate
        from substruct.assembly.stack import assemble
        asm = assemble(*substruct_model(size))
        M, K, A, _ = check_inputs(asm.M, asm.K, asm.A, 1)
        Ak = sp.csr_array(A[eliminate(M, A).kept_rows])
        s = float(np.mean(abs(K.diagonal())))
        B = sp.csr_array(K - default_shift(K, M) * M)
        return sp.csr_array(sp.block_array([[B, s * Ak.T], [s * Ak, None]], format="csr"))
    Kt, Mt = monolithic_model(size)
    if kind == "spd":
        sigma = -1e-9 * Kt.diagonal().sum() / Mt.diagonal().sum()
        return sp.csr_array(Kt - sigma * Mt)
    w = 2 * np.pi * HZ
    beta = 2 * 0.01 / w
    return sp.csr_array(Kt.astype(complex) * (1 + 1j * w * beta) - w**2 * Mt)


def factor_entries(solve, backend: str) -> int | None:
    """The factor's stored entries, where the backend reports them."""
    if backend == "pardiso":
        from substruct.linalg.pardiso import pardiso_factor_entries
        return pardiso_factor_entries(solve)
    return None


def worker(path: str, kind: str, backend: str, repeat: int) -> dict:
    """One backend on one matrix, in this fresh process."""
    from substruct.linalg.backends import backend_factorizer
    A = sp.csr_array(sp.load_npz(path))
    factorize = backend_factorizer(backend, kind)
    rng = np.random.default_rng(1)
    B = rng.standard_normal((A.shape[0], RHS))
    if kind == "complex-symmetric":
        B = B + 1j * rng.standard_normal(B.shape)
    gc.collect()
    before = _status("VmRSS")
    reset = _reset_peak()
    times, cpu = [], []
    for i in range(repeat):
        solve = None
        gc.collect()
        t0, c0 = time.perf_counter(), time.process_time()
        solve = factorize(A)
        times.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
        if times[0] > 20.0:
            break
    t0 = time.perf_counter()
    X = solve(B)
    tsolve = time.perf_counter() - t0
    peak = _status("VmHWM")
    norm1 = float(abs(A).sum(axis=0).max())
    residual = float(np.linalg.norm(A @ X - B) / (norm1 * np.linalg.norm(X)))
    return {"kind": kind, "backend": backend, "n": A.shape[0], "nnz": int(A.nnz),
            "time": statistics.median(times), "cpu": statistics.median(cpu), "times": times,
            "solve": tsolve, "peak": peak - before, "peak_total": peak, "peak_reset": reset,
            "residual": residual, "factor_entries": factor_entries(solve, backend)}


def measure(path: str, kind: str, backend: str, repeat: int) -> dict:
    env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
           "MKL_NUM_THREADS": "1"}
    cmd = [sys.executable, __file__, "--worker", path, "--kind", kind, "--backend", backend,
           "--repeat", str(repeat)]
    out = subprocess.run(cmd, env=env, capture_output=True, text=True)
    if out.returncode != 0:
        return {"kind": kind, "backend": backend, "error": out.stderr.strip().splitlines()[-1]}
    return json.loads(out.stdout.strip().splitlines()[-1])


def versions() -> str:
    from importlib.metadata import PackageNotFoundError, version
    parts = []
    for dist in ("pypardiso", "mkl", "scikit-sparse", "pymetis"):
        try:
            parts.append(f"{dist} {version(dist)}")
        except PackageNotFoundError:
            parts.append(f"{dist} absent")
    try:
        import sksparse.cholmod  # noqa: F401
        from threadpoolctl import threadpool_info
        blas = sorted({f"{i['internal_api']} {i.get('version') or ''}".strip()
                       for i in threadpool_info() if i["user_api"] == "blas"
                       and "numpy" not in i["filepath"] and "scipy" not in i["filepath"]})
        parts.append(f"CHOLMOD's BLAS: {', '.join(blas) or 'reference (no optimised BLAS)'}")
    except ImportError:
        pass
    return ", ".join(parts)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[10000, 30000])
    parser.add_argument("--full", action="store_true", help="add the 100k size")
    parser.add_argument("--all", action="store_true",
                        help="at 100k, also SuperLU without METIS")
    parser.add_argument("--kinds", nargs="+", default=list(KINDS), choices=KINDS)
    parser.add_argument("--backends", nargs="+", default=None)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--json", default=None, help="also write the raw measurements here")
    parser.add_argument("--worker", help=argparse.SUPPRESS)
    parser.add_argument("--kind", help=argparse.SUPPRESS)
    parser.add_argument("--backend", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker:
        print(json.dumps(worker(args.worker, args.kind, args.backend, args.repeat)))
        return
    from substruct.linalg.backends import BACKENDS, backend_status
    sizes = args.sizes + ([100000] if args.full and 100000 not in args.sizes else [])
    print(f"machine: {machine()}")
    print(f"libraries: {versions()}")
    print(f"python {platform.python_version()}; factorization of the matrix, solve of "
          f"{RHS} columns; ratios to the best backend of the same matrix (time: CPU time)\n")
    head = (f"{'matrix':<18} {'n':>7} {'backend':<16} {'factor s':>9} {'cpu s':>8} "
            f"{'x best':>7} {'solve s':>8} {'peak MB':>8} {'x best':>7} {'residual':>9} "
            f"{'nnz(L)':>10}")
    print(head)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for size in sizes:
            for kind in args.kinds:
                path = os.path.join(tmp, f"{kind}-{size}.npz")
                sp.save_npz(path, sp.csr_matrix(build(kind, size)))
                names = [b for b, backend in BACKENDS.items() if kind in backend.kinds and
                         backend_status(b) is None and
                         (args.backends is None or b in args.backends)]
                if size >= 100000 and not args.all:
                    names = [b for b in names if b != "superlu"]
                found = [measure(path, kind, b, args.repeat) for b in names]
                ok = [r for r in found if "error" not in r]
                best_t = min((r["cpu"] for r in ok), default=1.0)
                best_m = min((r["peak"] for r in ok), default=1.0)
                for r in found:
                    label = BACKENDS[r["backend"]].label
                    if "error" in r:
                        print(f"{kind:<18} {'':>7} {label:<16} failed: {r['error']}")
                        continue
                    fe = "" if r["factor_entries"] is None else f"{r['factor_entries']:,}"
                    print(f"{kind:<18} {r['n']:>7} {label:<16} {r['time']:>9.2f} "
                          f"{r['cpu']:>8.2f} {r['cpu'] / best_t:>7.2f} {r['solve']:>8.2f} "
                          f"{r['peak'] / 2**20:>8,.0f} {r['peak'] / best_m:>7.2f} "
                          f"{r['residual']:>9.1e} {fe:>10}", flush=True)
                    rows.append({**r, "size": size})
                os.remove(path)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1)


if __name__ == "__main__":
    main()
