"""AMLS for thousands of modes of a plate-like solid of millions of coordinates, alone.

    OMP_NUM_THREADS=1 python benchmarks/amls_slab.py [--size 2000000] [--modes 2000]
        [--omega-guess 3e5] [--cutoff 1.6] [--leaf-size 1000] [--workers N] [--reduce-only]

The model: a steel slab ``2 x 1 x 0.05`` m of Q1 hexahedra, two through the thickness, clamped
on its edge ``x = 0`` (:func:`substruct.models.solid.solid_box`); ``--size`` coordinates about.
A plate-like solid is what AMLS is made for (vehicle bodies of shells): its separators are
lines of nodes through the thickness, not the planes of a compact solid (benchmarks/amls.py).

One reduction (:func:`substruct.linalg.amls_reduce.amls_reduce`) with every block's modes up to
``cutoff * omega_guess``; the reduced eigenpairs below ``omega_guess``; the lowest ``--modes``
of them expanded (:func:`substruct.linalg.amls.expand_modes`: on disk when larger than the
memory allows) and their relative residuals ``||K u - w^2 M u|| / ||K u||`` computed.  With
no reference at this size (Lanczos would need its factorization and the modes in memory), the
count below the guess shows that the wanted modes are all there, and the effective cut-off
against the last wanted frequency is printed.  Peak memory: ``VmHWM`` (with the pages of the
mode file mapped while they are written and read) and the largest anonymous memory sampled
every second (``RssAnon``: what the process itself holds).

``--workers N``: the blocks of the reduction and the subdomains' expansions run as tasks on a
Dask LocalCluster of N worker processes (``substruct run --workers N``), one thread each.
``--reduce-only``: the dissection and the reduction alone (their wall seconds and the reduced
size); run once with ``--workers 0`` and once with ``--workers 2`` for the parallel speed-up
of the reduction (the peak memory is then the command's process only, not the workers').
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import threading
import time

import numpy as np
import scipy.sparse as sp

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from modes import _reset_peak, _status, machine  # noqa: E402


def slab(size: int) -> tuple[sp.csr_array, sp.csr_array]:
    """The clamped slab's ``K`` and ``M`` for about ``size`` coordinates."""
    from substruct.models.solid import BoxGrid, solid_box
    ny = max(2, int(round(np.sqrt(size / 18.0))))
    b = solid_box("slab", BoxGrid((2.0, 1.0, 0.05), (2 * ny, ny, 2)), 2.1e11, 0.3, 7850.0,
                  fixed=[{"box": [[0, 0, 0], [0, 1, 0.05]]}])
    return sp.csr_array(b.K), sp.csr_array(b.M)


class AnonymousPeak:
    """The largest ``RssAnon`` of this process, sampled every second in a thread."""

    def __init__(self) -> None:
        self.mb = 0
        threading.Thread(target=self._watch, daemon=True).start()

    def _watch(self) -> None:
        while True:
            with open("/proc/self/status") as f:
                for line in f:
                    if line.startswith("RssAnon"):
                        self.mb = max(self.mb, int(line.split()[1]) // 1024)
            time.sleep(1.0)


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--size", type=int, default=2_000_000)
    p.add_argument("--modes", type=int, default=2000)
    p.add_argument("--omega-guess", type=float, default=3e5,
                   help="rad/s, above the wanted modes' highest frequency")
    p.add_argument("--cutoff", type=float, default=1.6)
    p.add_argument("--leaf-size", type=int, default=1000)
    p.add_argument("--workers", type=int, default=0,
                   help="Dask LocalCluster worker processes for the tasks (0: this process)")
    p.add_argument("--reduce-only", action="store_true",
                   help="stop after the reduction (its time against --workers)")
    args = p.parse_args(argv)
    if args.workers:
        from substruct.studies.study_backend import Backend, Session
        with Session(Backend(workers=args.workers)) as session:
            run(args, session)
    else:
        run(args, None)


def run(args: argparse.Namespace, tasks: object) -> None:
    """The measurement of ``main`` (``tasks``: the Dask session, or ``None``)."""
    from substruct.linalg.amls import (AUTO, expand_modes, free_shift, reduced_eigenpairs,
                                       relative_residuals)
    from substruct.linalg.amls_reduce import amls_reduce
    from substruct.linalg.amls_tree import dissection_tree
    from substruct.linalg.scratch_arrays import ScratchArrays

    anon = AnonymousPeak()

    def say(line: str) -> None:
        print(f"{time.strftime('%H:%M:%S')} {line} [anonymous peak {anon.mb} MB]", flush=True)

    print(f"machine: {machine()}")
    t0 = time.perf_counter()
    K, M = slab(args.size)
    say(f"slab: {K.shape[0]} coordinates, {K.nnz} stiffness entries, "
        f"{time.perf_counter() - t0:.1f} s")
    _reset_peak()
    t0, c0 = time.perf_counter(), time.process_time()
    times = {}
    tree = dissection_tree(K, args.leaf_size, M=M)
    times["tree"] = time.perf_counter() - t0
    lam_w = args.omega_guess ** 2
    t = time.perf_counter()
    red = amls_reduce(K, M, tree, (args.cutoff * args.omega_guess) ** 2, AUTO, say, tasks,
                      free_shift(K, M, lam_w))
    times["reduce"] = time.perf_counter() - t
    n_reduced = red.size
    if args.reduce_only:
        out = {"n": K.shape[0], "workers": args.workers, "n_reduced": n_reduced,
               "times": times, "vmhwm_mb": _status("VmHWM") // 2**20,
               "anonymous_peak_mb": anon.mb}
        print(json.dumps(out))
        print(f"{out['n']} coordinates, reduced size {n_reduced}, workers {args.workers}: "
              f"tree {times['tree']:.1f} s, reduction {times['reduce']:.1f} s wall")
        return
    t = time.perf_counter()
    lam, Y = reduced_eigenpairs(red, lam_w)
    times["reduced"] = time.perf_counter() - t
    below = int(lam.size)
    if below < args.modes:
        raise SystemExit(f"only {below} modes below {args.omega_guess:g} rad/s: raise "
                         f"--omega-guess")
    lam, Y = lam[:args.modes], Y[:, :args.modes]
    say(f"reduced eigenpairs: {below} below the guess, the lowest {args.modes} kept")
    t = time.perf_counter()
    U = expand_modes(red, Y, tasks, ScratchArrays("substruct-modes-"))
    times["expand"] = time.perf_counter() - t
    del red, Y
    t = time.perf_counter()
    res = relative_residuals(K, M, lam, U)
    times["residual"] = time.perf_counter() - t
    omega = np.sqrt(lam)
    out = {"n": K.shape[0], "modes": args.modes, "below_guess": below,
           "n_reduced": n_reduced, "omega_first": float(omega[0]),
           "omega_last": float(omega[-1]),
           "cutoff_against_last": args.cutoff * args.omega_guess / float(omega[-1]),
           "on_disk": isinstance(U, np.memmap), "times": times,
           "wall": time.perf_counter() - t0, "cpu": time.process_time() - c0,
           "vmhwm_mb": _status("VmHWM") // 2**20, "anonymous_peak_mb": anon.mb,
           "residual_max": float(res.max()), "residual_median": float(np.median(res))}
    print(json.dumps(out))
    print(f"{out['n']} coordinates, {args.modes} modes ({omega[0]:.4g} to {omega[-1]:.4g} "
          f"rad/s; {below} below {args.omega_guess:g}), reduced size {n_reduced}: "
          f"{out['wall']:.0f} s wall ({', '.join(f'{k} {v:.0f}' for k, v in times.items())}), "
          f"peak {out['vmhwm_mb']} MB (anonymous {anon.mb} MB), modes on disk: "
          f"{out['on_disk']}, residuals max {out['residual_max']:.2e} median "
          f"{out['residual_median']:.2e}")


if __name__ == "__main__":
    main()
