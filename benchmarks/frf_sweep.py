"""FRF sweep benchmark: every receptance of two coupled chains, three routes, one process.

    OMP_NUM_THREADS=1 python benchmarks/frf_sweep.py [--frequencies 1000] [--repeat 3] [--quick]

The model: two fixed-free chains of 200 masses (``m = 1``, ``k = 1e4``, Rayleigh damping
``C = 1e-4 K + 0.5 M``), tied tip to tip (one constraint row): 400 coordinates.  All
400 x 400 receptances at ``--frequencies`` frequencies from 1 to 150 rad/s (the first 60 or so
coupled resonances), by

(a) substruct: ``analysis.api.receptance_sweep`` (the production path: the null-space sweep on
    the master-slave basis, one factorization of ``T^T Z(w) T`` a frequency, every input in
    one solve; its checks at three frequencies included);
(b) direct LU: ``scipy.sparse.linalg.splu`` (default options) of the same reduced impedance
    ``T^T Z(w) T`` at each frequency, solved for all inputs, ``H = T X`` gathered densely;
(c) LM-FBS, as pyFBS computes it: at each frequency the uncoupled receptances
    ``Y = blockdiag(Z_1^-1, Z_2^-1)`` by dense inversion, then
    ``Y_c = Y - Y B^T (B Y B^T)^+ B Y`` with the signed Boolean ``B`` (dense).

Each route writes all its receptances into its own array (the page faults of 2.6 GB of output
at 1,000 frequencies are part of every route).  Time: median of ``--repeat`` runs (one run for
a route that takes over 60 s), wall clock and CPU of the process.  The answers of (a) and (b)
are compared with (c): ``max |H - H_c| / max |H_c|``.
"""

from __future__ import annotations

import argparse
import platform
import statistics
import time

import numpy as np
import scipy
import scipy.sparse as sp
import scipy.sparse.linalg as spla

N_CHAIN, K_SPRING, MASS = 200, 1e4, 1.0


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


def route_lmfbs(K, M, C, B, w):
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


def timed(route, args, repeat: int):
    times, cpu, out = [], [], None
    for i in range(repeat):
        out = None  # free the previous answer before the next run
        t0, c0 = time.perf_counter(), time.process_time()
        out = route(*args)
        times.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
        if times[0] > 60.0:
            break
    return statistics.median(times), statistics.median(cpu), len(times), out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frequencies", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--quick", action="store_true", help="200 frequencies (about 1 min)")
    opts = parser.parse_args()
    nw = 200 if opts.quick else opts.frequencies
    K, M, C, B = chains()
    w = np.linspace(1.0, 150.0, nw)
    args = (K, M, C, B, w)
    print(f"# {platform.processor() or platform.machine()}, Python {platform.python_version()},"
          f" NumPy {np.__version__}, SciPy {scipy.__version__}")
    print(f"# two tied chains, {K.shape[0]} coordinates, {nw} frequencies x "
          f"{K.shape[0]} x {K.shape[0]} receptances")
    t_c, cpu_c, runs_c, (H_c, _) = timed(route_lmfbs, args, opts.repeat)
    rows = [("c LM-FBS (dense inverses)", t_c, cpu_c, runs_c, 0.0)]
    scale = max(float(np.abs(Hk).max()) for Hk in H_c)
    notes = ""
    for name, route in (("a substruct receptance_sweep", route_substruct),
                        ("b direct LU per frequency", route_direct_lu)):
        t, cpu, runs, (H, res) = timed(route, args, opts.repeat)
        diff = max(float(np.abs(Hk - Hc).max()) for Hk, Hc in zip(H, H_c)) / scale
        rows.append((name, t, cpu, runs, diff))
        if res is not None:
            notes = f"# (a) method {res.method}, checks {res.agreement}"
        del H
    print(f"{'route':32s} {'time (s)':>9s} {'CPU (s)':>9s} {'runs':>5s} "
          f"{'|H - H_c| / |H_c|':>18s} {'c / route':>10s}")
    for name, t, cpu, runs, diff in rows:
        print(f"{name:32s} {t:9.2f} {cpu:9.2f} {runs:5d} {diff:18.1e} {t_c / t:10.1f}")
    print(notes)
    a, b = rows[1][1], rows[2][1]
    print(f"# ratios: LM-FBS / substruct = {t_c / a:.1f}x, direct LU / substruct = "
          f"{b / a:.2f}x")


if __name__ == "__main__":
    main()
