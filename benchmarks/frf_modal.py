"""Benchmark: a 1,000-frequency receptance sweep of a 3D assembly, modal (coupled modes up to a
cut-off plus the second-order residual) against the direct sweep (eq 15, one sparse complex
factorization per frequency).

    OMP_NUM_THREADS=1 python benchmarks/frf_modal.py [--sizes 3000 10000] [--frequencies 1000]
        [--direct-frequencies 25] [--cutoff 3] [--count N] [--chain 200]

The model is the one of ``benchmarks/modes.py``: a clamped steel box ``4 x 1 x 1`` (Q1
hexahedra) of two halves tied node to node, two tuned absorbers (free-free, massless boundary
DOFs, here with dashpots: 5 % of critical, so the damping is not proportional) and one
four-term multi-point constraint.  Input: a unit force at the tip corner in ``z``; outputs: that
point, the three-quarter point and the two absorber masses.  Frequencies: 10 to 500 Hz.

* modal: :func:`substruct.analysis.api.receptance_sweep` with ``method="modal"`` (modes up to
  ``cutoff`` times 500 Hz by the sparse damped solver, the static and second-order residual
  from one factorization, the modal sum at every frequency; its own direct check at
  ``--check-frequencies`` frequencies, 0 by default, since the direct column below is that
  check), all of it timed;
* direct: the Lagrange-multiplier formulation itself,
  :func:`substruct.analysis.formulations.coupling.receptance` with ``method="kkt"`` (one sparse complex LU
  of the bordered impedance a frequency), on ``--direct-frequencies`` frequencies spread over
  the grid (a full 1,000-frequency direct sweep takes too long here: its cost is the same at
  every frequency, so the time is scaled to the whole grid and the table says so).

The peak resident memory of the process after each size is printed (``ru_maxrss``; it only
grows, so a row is the largest of that size and those before it).

``--chain n``: two damped chains of ``n`` coordinates joined end to start, all ``2n x 2n``
receptances at every frequency, by LM-FBS from the two chains' receptances against the inverse
of the coupled impedance (the kind of problem the pyFBS route is used for; pyFBS itself is not
a dependency, so it is not timed here).

Times are medians of ``--repeat`` runs in this process.  The table gives the modal time, the
direct time per frequency and for the whole grid, their ratio, and the largest relative
difference between the two at the directly solved frequencies.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import sys
import time

import numpy as np
import scipy.sparse as sp

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))


def build(target: int):
    """The assembly of ``benchmarks/modes.py`` with damped absorbers; force and output rows."""
    from modes import absorber_params, substruct_model

    from substruct.assembly.stack import PointRef, assemble
    from substruct.models.discrete import free_free

    subs, cons, mpcs = substruct_model(target)
    for k, (name, mass, stiff, _, _) in enumerate(absorber_params()):
        subs[2 + k] = free_free(name, mass, stiff, 2 * 0.05 * np.sqrt(stiff * mass))
    asm = assemble(subs, cons, mpcs)
    tip = PointRef("right", {"at": [4.0, 1.0, 1.0], "component": "z"})
    mid = PointRef("right", {"at": [3.0, 1.0, 1.0], "component": "z"})
    points = [tip, mid, PointRef("t1", "mass"), PointRef("t2", "mass")]
    outputs = asm.rows(points)
    inputs = sp.csc_array(asm.rows([tip]).T)
    return asm, inputs, outputs


def timed(run, repeat: int):
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = run()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def chains_table(n: int, frequencies: int, repeat: int) -> None:
    """Two damped spring-mass chains of ``n`` coordinates each, joined end to start, every
    coordinate an input and an output (``2n x 2n`` receptances at each frequency): LM-FBS from
    the two chains' receptances (:func:`substruct.analysis.frf.coupling.lm_fbs`, batched over
    the frequencies) against the inverse of the coupled impedance at each frequency."""
    from substruct.analysis.frf.coupling import boolean_rows, lm_fbs, stack
    from substruct.builder.frf_parts import FrfPart

    rng = np.random.default_rng(0)

    def chain(grounded: bool):
        k, c, m = rng.uniform(1e3, 3e3, n), rng.uniform(0.5, 2.0, n), rng.uniform(0.5, 2, n)
        K, C = np.zeros((n, n)), np.zeros((n, n))
        for i in range(n):
            if i == 0 and not grounded:
                continue
            for X, v in ((K, k[i]), (C, c[i])):
                X[i, i] += v
                if i:
                    X[i - 1, i - 1] += v
                    X[i, i - 1] -= v
                    X[i - 1, i] -= v
        return np.diag(m), C, K

    w = np.linspace(0.5, 60.0, frequencies)
    parts = []
    for name, grounded in (("a", True), ("b", False)):
        M, C, K = chain(grounded)
        Y = np.linalg.inv(K[None] - w[:, None, None] ** 2 * M[None] + 1j * w[:, None, None] * C)
        parts.append((FrfPart(name, w, [str(i) for i in range(n)], Y), (M, C, K)))
    Y, labels = stack([p for p, _ in parts])
    B = boolean_rows(labels, [(f"a@{n - 1}", "b@0")])
    t_fbs, Yc = timed(lambda: lm_fbs(Y, B), repeat)
    (Ma, Ca, Ka), (Mb, Cb, Kb) = (mats for _, mats in parts)
    big = [np.zeros((2 * n - 1, 2 * n - 1)) for _ in range(3)]
    for X, (xa, xb) in zip(big, ((Ma, Mb), (Ca, Cb), (Ka, Kb))):
        X[:n, :n] += xa
        X[n - 1:, n - 1:] += xb
    Mc, Cc, Kc = big

    def direct():
        return np.linalg.inv(Kc[None] - w[:, None, None] ** 2 * Mc[None]
                             + 1j * w[:, None, None] * Cc)
    t_dir, Hd = timed(direct, repeat)
    keep = list(range(n)) + list(range(n + 1, 2 * n))
    err = np.abs(Yc[:, keep][:, :, keep] - Hd).max() / np.abs(Hd).max()
    print(f"\nTwo chains of {n} coordinates, {frequencies} frequencies, all {2 * n} x {2 * n} "
          f"coupled receptances:")
    print("| LM-FBS from the parts' receptances (s) | inverse of the coupled impedance (s) | "
          "ratio | max rel. difference |")
    print("|---|---|---|---|")
    print(f"| {t_fbs:.2f} | {t_dir:.2f} | {t_dir / t_fbs:.2f} | {err:.1e} |", flush=True)


def main(argv: list[str] | None = None) -> None:
    """Print the tables (one row per size; then the two chains)."""
    from substruct.analysis.api import receptance_sweep
    from substruct.analysis.formulations.coupling import receptance
    from substruct.analysis.frf.modal import ModalOptions

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[3000, 10000])
    ap.add_argument("--frequencies", type=int, default=1000)
    ap.add_argument("--direct-frequencies", type=int, default=25)
    ap.add_argument("--cutoff", type=float, default=3.0)
    ap.add_argument("--count", type=int, default=None,
                    help="roots kept (default: those up to the cut-off, found by asking the "
                         "eigensolver for 20, 40, 80, ... roots: up to three solves)")
    ap.add_argument("--check-frequencies", type=int, default=0,
                    help="the modal sweep's own direct check (timed with it)")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--chain", type=int, default=200, help="coordinates of each chain (0: none)")
    args = ap.parse_args(argv)
    w = 2 * np.pi * np.linspace(10.0, 500.0, args.frequencies)
    pick = np.unique(np.linspace(0, len(w) - 1, args.direct_frequencies).round().astype(int))
    print(f"OMP_NUM_THREADS={os.environ.get('OMP_NUM_THREADS', 'unset')}, "
          f"{args.frequencies} frequencies 10-500 Hz, modes up to {args.cutoff:g} x 500 Hz, "
          f"direct on {len(pick)} frequencies (scaled to the grid)")
    head = ("| DOF | roots kept | modal sweep (s) | direct per frequency (s) | direct, whole "
            "grid (s, scaled) | direct / modal | max rel. difference | peak memory (GB) |")
    print(head)
    print("|" + "---|" * 8, flush=True)
    for size in args.sizes:
        asm, E, O = build(size)
        opts = ModalOptions(count=args.count, cutoff=args.cutoff, solver="sparse",
                            n_check=args.check_frequencies)
        t_modal, modal = timed(lambda: receptance_sweep(
            asm.K, asm.M, asm.C, asm.A, w, E, O, method="modal", modal=opts,
            tolerance=1e-3), args.repeat)
        print(f"  {asm.n_dof} DOF: modal sweep {t_modal:.1f} s ({modal.method})", flush=True)
        t_direct, direct = timed(lambda: receptance(
            asm.K, asm.M, asm.C, asm.A, w[pick], method="kkt", inputs=E, outputs=O),
            args.repeat)
        per = t_direct / len(pick)
        whole = per * len(w)
        err = np.abs(modal.H[pick] - direct).max() / np.abs(direct).max()
        kept = modal.method.split(":")[1].split(" root")[0].strip()
        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20
        print(f"| {asm.n_dof} | {kept} | {t_modal:.2f} | {per:.3f} | {whole:.1f} | "
              f"{whole / t_modal:.1f} | {err:.1e} | {peak:.2f} |", flush=True)
    if args.chain:
        chains_table(args.chain, args.frequencies, args.repeat)


if __name__ == "__main__":
    main()
