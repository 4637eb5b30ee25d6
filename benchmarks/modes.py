"""Scale benchmark: lowest 20 coupled modes of a clamped 3D box of two tied halves.

    OMP_NUM_THREADS=1 python benchmarks/modes.py [--sizes 10000 30000 100000 300000] [--quick]

The model: a box ``4 x 1 x 1`` (Q1 hexahedra, steel) clamped at ``x = 0``, built from two
halves meshed separately and tied node to node at ``x = 2``; two tuned absorbers (free-free
spring-masses, massless boundary DOFs) at the tip and at three quarters of the span; one
multi-point constraint ``2 u_z(1, .5, 1) - 5 u_z(2, .5, 1) - 4 u_z(3, .5, 1) + 3 u_z(3.9, .5,
1) = 0`` (the last point inside an element: an interpolated row).

For each size, each in a fresh subprocess (peak memory is the process's high-water mark
``VmHWM`` during the solve, reset before it through ``/proc/self/clear_refs``):

(a) substruct: ``assemble`` (stacking, compatibility rows) + ``null_space_modes``
    (master-slave elimination, ``T^T K T``, factorization, shift-invert ``eigsh``);
(b) baseline: ``eigsh`` shift-invert on the same constrained model eliminated by hand (the
    monolithic mesh, absorbers added to ``K`` and ``M`` directly, the multi-point constraint
    eliminated by one hand-made slave column), with its own best factorization;
(c) the paper's dense formula (``M^1/2`` by ``eigh``, ``pinv``, dense ``eig`` of the
    state-space pencil of eqs 32-34 as ``W^-1 R``), for ``n <= 3000`` only.

Time is the median of 3 runs where a run takes under 20 s, else one run, as wall-clock and as
CPU time of the process (less sensitive to other work on a shared machine).  The table gives
the ratios a/b (time, CPU time, memory), c/a at the dense sizes, and the growth exponent of
(a) (least squares slope of log time against log n).
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
import time

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

E, NU, RHO = 2.1e11, 0.3, 7850.0
LX, LY, LZ = 4.0, 1.0, 1.0
N_MODES = 20


# ------------------------------------------------------------------------------------- model


def divisions(target: int) -> tuple[int, int]:
    """``(nx_half, m)``: elements along x per half and across, for about ``target`` DOFs."""
    best = None
    for m in range(1, 80):
        for nxh in range(max(1, int(1.5 * m)), 3 * m + 2):
            n = 3 * (2 * nxh + 1) * (m + 1) ** 2 + 4
            score = abs(np.log(n / target)) + 0.02 * abs(np.log(2 * nxh / (4 * m)))
            if best is None or score < best[0]:
                best = (score, nxh, m)
    return best[1], best[2]


def absorber_params() -> list[tuple[str, float, float, tuple[float, float, float], str]]:
    """Name, mass, stiffness, attachment point, component of the two absorbers."""
    total = RHO * LX * LY * LZ
    # tuned near the first bending (about 52 Hz) and torsion-ish (about 300 Hz) frequencies
    return [("t1", 0.02 * total, 0.02 * total * (2 * np.pi * 50.0) ** 2, (LX, LY, LZ), "z"),
            ("t2", 0.01 * total, 0.01 * total * (2 * np.pi * 300.0) ** 2,
             (0.75 * LX, LY, LZ), "y")]


MPC = [((1.0, 0.5, 1.0), 2.0), ((2.0, 0.5, 1.0), -5.0), ((3.0, 0.5, 1.0), -4.0),
       ((3.9, 0.5, 1.0), 3.0)]


def substruct_model(target: int):
    """The two halves, the absorbers, and the connections and constraint (substruct API)."""
    from substruct.assembly.interfaces import tie_nodes
    from substruct.assembly.stack import Connection, LinearConstraint, PointRef
    from substruct.models.discrete import free_free
    from substruct.models.solid import BoxGrid, solid_box
    nxh, m = divisions(target)
    left = solid_box("left", BoxGrid((LX / 2, LY, LZ), (nxh, m, m)), E, NU, RHO,
                     fixed=[{"box": [[0, 0, 0], [0, LY, LZ]]}])
    right = solid_box("right", BoxGrid((LX / 2, LY, LZ), (nxh, m, m), origin=(LX / 2, 0, 0)), E,
                      NU, RHO)
    subs = [left, right]
    cons = tie_nodes(left, right, {"box": [[LX / 2, 0, 0], [LX / 2, LY, LZ]]})
    for name, mass, k, xyz, comp in absorber_params():
        subs.append(free_free(name, mass, k))
        cons.append(Connection(PointRef("right", {"at": list(xyz), "component": comp}),
                               PointRef(name, "boundary")))

    def ref(xyz):
        return PointRef("left" if xyz[0] < LX / 2 else "right",
                        {"at": list(xyz), "component": "z"})
    mpc = LinearConstraint(tuple((ref(x), c) for x, c in MPC), name="mpc")
    return subs, cons, [mpc]


def monolithic_system(target: int) -> dict:
    """The same constrained model over the monolithic mesh and the two absorber masses, with
    the constraint eliminated by hand, ``q = T x``: ``{"box", "n", "K", "M", "T"}``."""
    from substruct.models.solid import BoxGrid, solid_box
    nxh, m = divisions(target)
    box = solid_box("box", BoxGrid((LX, LY, LZ), (2 * nxh, m, m)), E, NU, RHO,
                    fixed=[{"box": [[0, 0, 0], [0, LY, LZ]]}])
    n = box.n_dof
    # each absorber's massless boundary DOF is the structure's displacement r q there (a
    # node or an interpolated point): the spring adds k [r, -e_a]^T [r, -e_a] to K
    K = sp.csr_array(sp.block_diag([box.K, sp.csr_array((2, 2))]))
    M = sp.lil_array(sp.block_diag([box.M, sp.csr_array((2, 2))]))
    for j, (_, mass, k, xyz, comp) in enumerate(absorber_params()):
        g = sp.csr_array(sp.hstack([box.row((xyz, comp)), sp.csr_array((1, 2))])).tolil()
        g[0, n + j] = -1.0
        g = sp.csr_array(g)
        K = sp.csr_array(K + k * (g.T @ g))
        M[n + j, n + j] = mass
    M = sp.csr_array(M)
    row = sum(c * box.row((x, "z")) for x, c in MPC)
    row = sp.csr_array(sp.hstack([row, sp.csr_array((1, 2))])).tocoo()
    s = int(row.col[np.argmax(abs(row.data))])  # the slave: the largest coefficient
    a_s = row.toarray()[0, s]
    keep = np.setdiff1d(np.arange(n + 2), [s])
    col = np.full(n + 2, -1)
    col[keep] = np.arange(keep.size)
    others = row.col != s
    T = sp.csr_array((np.concatenate([np.ones(keep.size), -row.data[others] / a_s]),
                      (np.concatenate([keep, np.full(others.sum(), s)]),
                       np.concatenate([col[keep], col[row.col[others]]]))),
                     shape=(n + 2, keep.size))
    return {"box": box, "n": n, "K": K, "M": M, "T": T}


def monolithic_model(target: int) -> tuple[sp.csr_array, sp.csr_array]:
    """The same constrained model eliminated by hand: ``(T^T K T, T^T M T)``."""
    s = monolithic_system(target)
    T = s["T"]
    return sp.csr_array(T.T @ s["K"] @ T), sp.csr_array(T.T @ s["M"] @ T)


# ------------------------------------------------------------------------------- measurement


def _status(key: str) -> int:
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(key):
                return int(line.split()[1]) * 1024
    return 0


def _reset_peak() -> bool:
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
        return True
    except OSError:
        return False


def timed_runs(run, repeat: int, once_above: float = 20.0
               ) -> tuple[list[float], list[float], object]:
    """Wall-clock and CPU (process) times of up to ``repeat`` runs (one if the first takes
    over ``once_above`` seconds), and the last output."""
    times, cpu, out = [], [], None
    for i in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        out = run()
        times.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
        if i == 0 and times[0] > once_above:
            break
    return times, cpu, out


def best_factorization() -> str:
    from substruct.linalg.factorize import has_cholmod
    return "cholmod" if has_cholmod() else "superlu"


def worker(kind: str, size: int, factorization: str, repeat: int) -> dict:
    """One measurement, in this (fresh) process."""
    t0 = time.perf_counter()
    if kind == "a":
        from substruct.analysis.modes.sparse import null_space_modes
        from substruct.assembly.stack import assemble
        subs, cons, mpcs = substruct_model(size)
        build = time.perf_counter() - t0

        def run():
            asm = assemble(subs, cons, mpcs)
            modes = null_space_modes(asm.M, asm.K, asm.A, N_MODES, factorization=factorization)
            return asm.n_dof, modes.omega, float(modes.residual.max())
    elif kind == "b":
        from substruct.linalg.factorize import factorizer
        Kt, Mt = monolithic_model(size)
        build = time.perf_counter() - t0

        def run():
            sigma = -1e-9 * Kt.diagonal().sum() / Mt.diagonal().sum()
            solve = factorizer(factorization)(sp.csc_array(Kt - sigma * Mt))
            op = spla.LinearOperator(Kt.shape, matvec=solve, dtype=float)
            v0 = np.random.default_rng(0).standard_normal(Kt.shape[0])
            lam = spla.eigsh(Kt, k=N_MODES, M=Mt, sigma=sigma, OPinv=op, v0=v0,
                             return_eigenvectors=False)
            return Kt.shape[0], np.sqrt(np.sort(lam)), 0.0
    elif kind == "c":
        from substruct.assembly.stack import assemble
        subs, cons, mpcs = substruct_model(size)
        asm = assemble(subs, cons, mpcs)
        build = time.perf_counter() - t0

        def run():
            return asm.n_dof, paper_dense_modes(asm.M, asm.K, asm.A), 0.0
    else:
        raise ValueError(kind)
    gc.collect()
    rss_before = _status("VmRSS")
    reset = _reset_peak()
    times, cpu, (n, omega, residual) = timed_runs(run, repeat)
    return {"kind": kind, "size": size, "n": int(n), "times": times,
            "time": statistics.median(times), "cpu": statistics.median(cpu),
            "peak": _status("VmHWM"),
            "rss_before": rss_before, "peak_reset": reset, "build": build,
            "freq_hz": (np.asarray(omega)[:N_MODES] / (2 * np.pi)).tolist(),
            "residual": residual, "factorization": factorization if kind != "c" else "dense"}


def paper_dense_modes(M: sp.sparray, K: sp.sparray, A: sp.sparray) -> np.ndarray:
    r"""The paper's eqs (7)-(10), (28)-(34) with dense matrices, literally.

    ``M_d^{1/2}`` by ``eigh``; ``M^* = M_d^{-1/2} [I - (A M_d^{-1/2})^+ A M_d^{-1/2}]
    M_d^{-1/2}``; the pencil ``R eta = lambda W eta`` (undamped: ``C = 0``) by a dense ``eig``
    of ``W^{-1} R``; physical roots are the finite nonzero ones whose vector satisfies
    ``A u = 0``.
    """
    Md = M.toarray()
    massless = np.abs(Md).sum(axis=1) == 0
    Md[massless, massless] = 1.0
    Kd, Ad = K.toarray(), A.toarray()
    n = Md.shape[0]
    w, V = np.linalg.eigh(Md)
    Mih = (V / np.sqrt(w)) @ V.T  # M_d^{-1/2}
    B = Ad @ Mih
    Mstar = Mih @ (np.eye(n) - np.linalg.pinv(B) @ B) @ Mih
    Tm = np.eye(n) - Mstar * massless[None, :]  # I - M* M_o
    W = np.block([[np.zeros((n, n)), np.eye(n)], [Tm, np.zeros((n, n))]])
    R = np.block([[np.eye(n), np.zeros((n, n))], [np.zeros((n, n)), -Mstar @ Kd]])
    lam, V2 = sla.eig(np.linalg.solve(W, R))
    U = V2[n:]
    res = np.linalg.norm(Ad @ U, axis=0) / np.linalg.norm(U, axis=0) / np.linalg.norm(Ad, 2)
    scale = np.sqrt(np.abs(np.diag(Kd)).max() / Md.diagonal().min())
    ok = (res < 1e-6) & (np.abs(lam) > 1e-6 * scale) & (lam.imag > 0)
    return np.sort(np.abs(lam[ok]))


def measure(kind: str, size: int, factorization: str, repeat: int) -> dict:
    env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
           "MKL_NUM_THREADS": "1"}
    cmd = [sys.executable, __file__, "--worker", kind, "--size", str(size),
           "--factorization", factorization, "--repeat", str(repeat)]
    out = subprocess.run(cmd, env=env, capture_output=True, text=True)
    if out.returncode != 0:
        raise RuntimeError(f"worker {kind} {size} failed:\n{out.stderr[-3000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def machine() -> str:
    cpu = "?"
    with open("/proc/cpuinfo") as f:
        for line in f:
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    mem = _meminfo()
    import scipy
    return (f"{os.cpu_count()} cores ({cpu}), {mem / 2**30:.1f} GiB, Python "
            f"{platform.python_version()}, numpy {np.__version__}, scipy {scipy.__version__}, "
            f"OMP_NUM_THREADS=1")


def _meminfo() -> int:
    with open("/proc/meminfo") as f:
        for line in f:
            if line.startswith("MemTotal"):
                return int(line.split()[1]) * 1024
    return 0


def _fmt_mb(b: float) -> str:
    return f"{b / 2**20:,.0f}"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[10000, 30000, 100000, 300000])
    parser.add_argument("--dense-sizes", type=int, nargs="*", default=[500, 1000, 2000, 3000],
                        help="sizes for (c); none to skip")
    parser.add_argument("--quick", action="store_true",
                        help="sizes 10000 30000, dense sizes 500 1000")
    parser.add_argument("--factorization", default=None,
                        help="for (a) and (b): superlu | cholmod (default: the best available)")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--json", default=None, help="also write the raw measurements here")
    parser.add_argument("--worker", choices=["a", "b", "c"], help=argparse.SUPPRESS)
    parser.add_argument("--size", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    fact = args.factorization or best_factorization()
    if args.worker:
        print(json.dumps(worker(args.worker, args.size, fact, args.repeat)))
        return
    sizes = [10000, 30000] if args.quick else args.sizes
    dense_sizes = [500, 1000] if args.quick else args.dense_sizes
    print(f"machine: {machine()}")
    print(f"factorization for (a) and (b): {fact}")
    rows = []
    print(f"\n{'n':>8} {'a: s':>9} {'a: cpu s':>9} {'a: MB':>7} {'b: s':>9} {'b: cpu s':>9} "
          f"{'b: MB':>7} {'a/b t':>6} {'a/b cpu':>7} {'a/b mem':>7} {'max |fa/fb-1|':>13}")
    for size in sizes:
        a = measure("a", size, fact, args.repeat)
        b = measure("b", size, fact, args.repeat)
        diff = float(np.max(np.abs(np.array(a["freq_hz"]) / np.array(b["freq_hz"]) - 1)))
        rows.append({"a": a, "b": b, "freq_diff": diff})
        print(f"{a['n']:>8} {a['time']:>9.2f} {a['cpu']:>9.2f} {_fmt_mb(a['peak']):>7} "
              f"{b['time']:>9.2f} {b['cpu']:>9.2f} {_fmt_mb(b['peak']):>7} "
              f"{a['time'] / b['time']:>6.2f} {a['cpu'] / b['cpu']:>7.2f} "
              f"{a['peak'] / b['peak']:>7.2f} {diff:>13.1e}", flush=True)
    if len(rows) >= 2:
        n = np.array([r["a"]["n"] for r in rows], dtype=float)
        for key in ("time", "cpu"):
            t = np.array([r["a"][key] for r in rows])
            slope = np.polyfit(np.log(n), np.log(t), 1)[0]
            print(f"growth exponent of (a): {key} ~ n^{slope:.2f} (least squares, {len(n)} "
                  "sizes)")
    dense = []
    if dense_sizes:
        print(f"\n{'n':>8} {'c: s':>9} {'c: MB':>7} {'a: s':>9} {'a: MB':>7} {'c/a t':>8} "
              f"{'max |fa/fc-1|':>13}")
    for size in dense_sizes:
        a = measure("a", size, fact, args.repeat)
        c = measure("c", size, fact, 1)
        diff = float(np.max(np.abs(np.array(a["freq_hz"]) / np.array(c["freq_hz"][:N_MODES])
                                   - 1)))
        dense.append({"a": a, "c": c, "freq_diff": diff})
        print(f"{c['n']:>8} {c['time']:>9.2f} {_fmt_mb(c['peak']):>7} {a['time']:>9.3f} "
              f"{_fmt_mb(a['peak']):>7} {c['time'] / a['time']:>8.0f} {diff:>13.1e}", flush=True)
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"machine": machine(), "factorization": fact, "sparse": rows,
                       "dense": dense}, f, indent=1)


if __name__ == "__main__":
    main()
