"""The dense eigen solve against the estimate that ``substruct run`` warns with.

:data:`substruct.cli.progress.DENSE_SECONDS_PER_N3` (``1.7e-7 s x n^3``) is what the slow-solve
warning assumes for the generalized-inverse formulation (eqs 28-34, all roots of the balanced
pencil).  This script measures that solve on the tapered rod by P2 elements at a few sizes
(median of ``--repeat`` runs, one BLAS thread recommended) and prints the measured time, the
estimate and their ratio: a ratio far from 1 on a machine means the constant should change.

    OMP_NUM_THREADS=1 python benchmarks/dense_estimate.py [--elements 50 100 200] [--repeat 3]
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

__all__ = ["measure", "main"]

CASE = Path(__file__).resolve().parent.parent / "cases" / "tapered_rod_fe.yaml"


def measure(elements: int, repeat: int) -> tuple[int, float]:
    """Coordinates of the model and the median seconds of one dense eigen solve."""
    import substruct
    from substruct.analysis.api import modes

    case = substruct.load_case(CASE, [f"substructures.rod.discretization.elements={elements}"])
    asm = substruct.build_model(case).assembly
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        modes(asm.M, asm.C, asm.K, asm.A, 6, method="generalized-inverse", solver="dense")
        times.append(time.perf_counter() - start)
    return asm.n_dof, statistics.median(times)


def main() -> None:
    """Print the table."""
    from substruct.cli.progress import DENSE_SECONDS_PER_N3, dense_seconds

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--elements", type=int, nargs="+", default=[50, 100, 200])
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    print(f"estimate: {DENSE_SECONDS_PER_N3:.2e} s x n^3 (generalized-inverse, dense)")
    print(f"{'n':>6} {'measured s':>11} {'estimate s':>11} {'ratio':>7} {'s / n^3':>10}")
    for e in args.elements:
        n, t = measure(e, args.repeat)
        est = dense_seconds(n)
        print(f"{n:6d} {t:11.3f} {est:11.3f} {t / est:7.2f} {t / n ** 3:10.2e}")


if __name__ == "__main__":
    main()
