"""Transient benchmark: 1,000 Newmark steps of a meshed solid assembly, substruct's constrained
forms against the same model integrated monolithically.

    OMP_NUM_THREADS=1 python benchmarks/transient.py [--sizes 10000 30000] [--large] [--steps N]

The model is that of ``benchmarks/modes.py``: a clamped steel box ``4 x 1 x 1`` of Q1
hexahedra made of two halves tied node to node at ``x = 2``, two tuned absorbers (free-free
spring-masses with massless boundary coordinates), one four-term multi-point constraint (one
term interpolated inside an element).  Load: a 1 kN step in z at the tip corner ``(4, 1, 1)``
from rest; outputs: the tip and the first absorber's mass; ``dt = 1e-4`` s (about 200 steps per
period of the first bending mode).

For each size, in one process:

(gi) substruct, ``method="generalized-inverse"`` (eq 5 with the effective matrix, one
     factorization of ``S`` and the gain ``S^-1 A^T (A S^-1 A^T)^+``, projection every step);
(ns) substruct, ``method="null-space"`` (master-slave elimination, ``T^T S T`` factorized
     once);
(b)  baseline: the monolithic mesh with the absorbers stamped into ``K`` and ``M`` and the
     constraint eliminated by one hand-made slave column (as ``benchmarks/modes.py``), the
     effective matrix factorized once by the same factorization, and the same Newmark loop
     (average acceleration) written here, recording the same outputs.

substruct's runs record what a case records by default (outputs, the constraint residual and
the energies every step) but no constraint forces.  Times are medians of 3 runs (one when a run
takes more than 60 s), wall-clock and CPU; the assembly is not timed.  The table gives the
ratios to (b) and the largest difference of the tip history from (b), relative to its peak:
the three integrate the same discrete equations in different coordinates.
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path

import numpy as np
import scipy.sparse as sp

sys.path.insert(0, str(Path(__file__).resolve().parent))
from modes import (  # noqa: E402  (the model and timer of the modal benchmark)
    LX,
    LY,
    LZ,
    best_factorization,
    machine,
    monolithic_system,
    substruct_model,
    timed_runs,
)

DT = 1e-4
FORCE = 1000.0
TIP = (LX, LY, LZ)


def monolithic(target: int) -> dict:
    """The constrained model eliminated by hand: ``q = T x`` over the monolithic mesh and the
    two absorber masses; ``K_t, M_t = T^T K T, T^T M T``; load and output rows."""
    s = monolithic_system(target)
    box, n, K, M, T = s["box"], s["n"], s["K"], s["M"], s["T"]
    tip = sp.csr_array(sp.hstack([box.row((TIP, "z")), sp.csr_array((1, 2))]))
    mass = sp.csr_array(([1.0], ([0], [n])), shape=(1, n + 2))
    O = sp.csr_array(sp.vstack([tip, mass]))
    return {"K": sp.csr_array(T.T @ sp.csr_array(K) @ T),
            "M": sp.csr_array(T.T @ sp.csr_array(M) @ T),
            "load": np.asarray((T.T @ tip.T).todense()).ravel(), "O": sp.csr_array(O @ T)}


def baseline_run(mono: dict, steps: int, factorization: str) -> np.ndarray:
    """Newmark's average acceleration on the eliminated model, from rest under the step:
    ``S = M + h^2/4 K`` factorized once; returns the output histories."""
    from substruct.linalg.factorize import factorizer
    K, M, O, p = mono["K"], mono["M"], mono["O"], FORCE * mono["load"]
    h = DT
    solve = factorizer(factorization)(sp.csc_array(M + 0.25 * h * h * K))
    d = np.zeros(K.shape[0])
    v = np.zeros_like(d)
    a = factorizer(factorization)(sp.csc_array(M))(p)
    out = np.empty((steps + 1, O.shape[0]))
    out[0] = O @ d
    for k in range(steps):
        d_star = d + h * v + 0.25 * h * h * a
        v_star = v + 0.5 * h * a
        a = solve(p - K @ d_star)
        d = d_star + 0.25 * h * h * a
        v = v_star + 0.5 * h * a
        out[k + 1] = O @ d
    return out


def substruct_run(asm, method: str, steps: int, factorization: str) -> tuple[np.ndarray, float]:
    """substruct's transient on the assembled model; the output histories and the drift."""
    from substruct.analysis.transient import (LoadHistory, TransientOptions, TransientOutputs,
                                               transient)
    from substruct.assembly.stack import PointRef
    tip = asm.rows([PointRef("right", {"at": list(TIP), "component": "z"})])
    O = sp.csr_array(sp.vstack([tip, asm.rows([PointRef("t1", "mass")])]))
    f = np.full((steps + 1, 1), FORCE)
    r = transient(asm.M, None, asm.K, asm.A, asm.b,
                  LoadHistory(sp.csc_array(tip.T), f, DT, steps), TransientOutputs(O),
                  options=TransientOptions(method=method, forces=False,
                                           factorization=factorization))
    return r.displacement, r.drift


def timed(run, repeat: int) -> tuple[float, float, object]:
    """Median wall-clock and CPU times of up to ``repeat`` runs, and the last output."""
    times, cpu, out = timed_runs(run, repeat, once_above=60.0)
    return statistics.median(times), statistics.median(cpu), out


def progress(size: int, form: str, wall: float, cpu: float) -> None:
    """One line on standard error as each form finishes (a large size takes many minutes)."""
    print(f"  [{size}] {form}: {wall:.2f} s wall, {cpu:.2f} s CPU", file=sys.stderr, flush=True)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[10000, 30000])
    parser.add_argument("--large", action="store_true", help="add the 100k-DOF size")
    parser.add_argument("--steps", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--factorization", default=None,
                        help="superlu | cholmod (default: the best available)")
    args = parser.parse_args(argv)
    from substruct.assembly.stack import assemble
    fact = args.factorization or best_factorization()
    sizes = args.sizes + ([100000] if args.large else [])
    print(f"machine: {machine()}")
    print(f"{args.steps} Newmark steps of {DT:g} s; factorization: {fact}; medians of "
          f"{args.repeat} runs")
    print(f"\n{'n':>8} {'m':>5} {'gi: s':>8} {'ns: s':>8} {'b: s':>8} {'gi cpu':>8} "
          f"{'ns cpu':>8} {'b cpu':>8} {'gi/b':>6} {'ns/b':>6} {'gi/b cpu':>8} "
          f"{'ns/b cpu':>8} {'|gi-b|':>8} {'|ns-b|':>8} {'drift gi':>9}")
    for size in sizes:
        subs, cons, mpcs = substruct_model(size)
        asm = assemble(subs, cons, mpcs)
        mono = monolithic(size)
        tb, cb, yb = timed(lambda: baseline_run(mono, args.steps, fact), args.repeat)
        progress(size, "b", tb, cb)
        tg, cg, (yg, drift) = timed(lambda: substruct_run(asm, "generalized-inverse",
                                                          args.steps, fact), args.repeat)
        progress(size, "gi", tg, cg)
        tn, cn, (yn, _) = timed(lambda: substruct_run(asm, "null-space", args.steps, fact),
                                args.repeat)
        progress(size, "ns", tn, cn)
        peak = float(np.abs(yb[:, 0]).max())
        eg = float(np.abs(yg[:, 0] - yb[:, 0]).max()) / peak
        en = float(np.abs(yn[:, 0] - yb[:, 0]).max()) / peak
        print(f"{asm.n_dof:>8} {asm.A.shape[0]:>5} {tg:>8.2f} {tn:>8.2f} {tb:>8.2f} "
              f"{cg:>8.2f} {cn:>8.2f} {cb:>8.2f} {tg / tb:>6.2f} {tn / tb:>6.2f} "
              f"{cg / cb:>8.2f} {cn / cb:>8.2f} {eg:>8.1e} {en:>8.1e} {drift:>9.1e}",
              flush=True)


if __name__ == "__main__":
    main()
