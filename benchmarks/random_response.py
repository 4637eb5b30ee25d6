"""Benchmark: a random response of 1,000 frequencies, 20 correlated force inputs and 100
outputs, by substruct against the same computation written by hand with NumPy from the same
receptances, in the same process.

    OMP_NUM_THREADS=1 python benchmarks/random_response.py [--frequencies 1000] [--inputs 20]
        [--outputs 100] [--dof 400] [--repeat 3]

The receptances: a damped chain of ``--dof`` unit masses (springs 1e4 between neighbours and to
ground at its first end, dashpots 1e-4 K + 0.1 M), its receptances from ``--inputs`` force
points to ``--outputs`` output points at ``--frequencies`` frequencies, 0.1 to 40 Hz, by
:func:`substruct.analysis.api.receptance_sweep` (not timed: both sides start from them).  The
input cross-spectral matrix: every input a log-log table (1 to 0.1 N^2/Hz over the band),
neighbouring inputs correlated with coherence 0.2 and phase 30 degrees
(:func:`substruct.case.random_cross.cross_matrix`).

* substruct: :func:`substruct.analysis.frf.random.check_spectral_matrix` (Hermitian positive
  semidefinite at every frequency), :func:`~substruct.analysis.frf.random.response_psd`
  (:math:`S_y = H S_f H^H`, batched) and :func:`~substruct.analysis.frf.random.rms`;
* by hand: a Python loop over the frequencies, ``H[k] @ S[k] @ H[k].conj().T``, its diagonal
  integrated by ``np.trapezoid``, and ``np.linalg.eigvalsh`` of each ``S[k]`` for the same check.

Times are medians of ``--repeat`` runs; the table gives both, their ratio, and the largest
difference of the response matrices (relative to their largest term) and of the RMS values.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
import scipy.sparse as sp


def receptances(n: int, n_in: int, n_out: int, f: np.ndarray) -> np.ndarray:
    """``H`` ``(n_f, n_out, n_in)`` of the chain (module docstring)."""
    from substruct.analysis.api import receptance_sweep

    k = 1.0e4
    main = np.full(n, 2 * k)
    main[-1] = k
    K = sp.diags_array([main, np.full(n - 1, -k), np.full(n - 1, -k)], offsets=[0, 1, -1],
                       format="csc")
    M = sp.identity(n, format="csc")
    C = 1e-4 * K + 0.1 * M
    inputs = sp.csc_array(sp.identity(n, format="csc")[:, np.linspace(0, n - 1, n_in)
                                                          .astype(int)])
    outputs = sp.csr_array(sp.identity(n, format="csr")[np.linspace(0, n - 1, n_out)
                                                         .astype(int)])
    return receptance_sweep(K, M, C, None, 2 * np.pi * f, inputs, outputs).H


def inputs_csd(f: np.ndarray, p: int) -> np.ndarray:
    """The input cross-spectral matrix ``(n_f, p, p)`` (module docstring)."""
    from substruct.analysis.frf.random import interpolate_psd
    from substruct.case.random_cross import CrossPsd, cross_matrix

    names = [f"P@{i + 1}" for i in range(p)]
    auto = np.column_stack([interpolate_psd([f[0], f[-1]], [1.0, 0.1], f)] * p)
    pairs = [CrossPsd(between=[names[i], names[i + 1]], coherence=0.2, phase=30.0)
             for i in range(p - 1)]
    return cross_matrix(names, pairs, auto)


def by_substruct(f: np.ndarray, H: np.ndarray, S: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    from substruct.analysis.frf.random import check_spectral_matrix, response_psd, rms

    check_spectral_matrix(S, f=f)
    Sy = response_psd(H, S)
    return Sy, rms(f, np.real(np.einsum("kii->ki", Sy)))


def by_hand(f: np.ndarray, H: np.ndarray, S: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    nf, q, _ = H.shape
    Sy = np.empty((nf, q, q), dtype=complex)
    for k in range(nf):
        if np.linalg.eigvalsh(S[k]).min() < -1e-10 * np.abs(S[k]).max():
            raise ValueError(f"not semidefinite at {f[k]} Hz")
        Sy[k] = H[k] @ S[k] @ H[k].conj().T
    auto = np.real(np.array([np.diag(Sy[k]) for k in range(nf)]))
    return Sy, np.sqrt(np.trapezoid(auto, f, axis=0))


def timed(fn, repeat: int, *args) -> tuple[float, tuple]:
    times, out = [], None
    for _ in range(repeat):
        start = time.perf_counter()
        out = fn(*args)
        times.append(time.perf_counter() - start)
    return statistics.median(times), out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--frequencies", type=int, default=1000)
    ap.add_argument("--inputs", type=int, default=20)
    ap.add_argument("--outputs", type=int, default=100)
    ap.add_argument("--dof", type=int, default=400)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    f = np.linspace(0.1, 40.0, args.frequencies)
    start = time.perf_counter()
    H = receptances(args.dof, args.inputs, args.outputs, f)
    sweep = time.perf_counter() - start
    S = inputs_csd(f, args.inputs)
    t_sub, (Sy, r_sub) = timed(by_substruct, args.repeat, f, H, S)
    t_np, (Sy_np, r_np) = timed(by_hand, args.repeat, f, H, S)
    scale = np.abs(Sy_np).max()
    print(f"random response: {args.frequencies} frequencies, {args.inputs} correlated inputs, "
          f"{args.outputs} outputs (receptances of a {args.dof}-DOF chain, {sweep:.2f} s, "
          f"not timed)")
    print(f"  substruct (check, H S H^H batched, rms)   {t_sub:8.3f} s")
    print(f"  by hand (loop over frequencies, NumPy)    {t_np:8.3f} s")
    print(f"  ratio by hand / substruct                 {t_np / t_sub:8.2f}")
    print(f"  largest |S_y - S_y by hand| / max|S_y|    {np.abs(Sy - Sy_np).max() / scale:8.2e}")
    print(f"  largest relative RMS difference           "
          f"{np.max(np.abs(r_sub / r_np - 1)):8.2e}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
