"""Overhead of running a study on Dask against running it in this process.

Two studies of the shipped absorber-tuning case (``cases/tapered_rod_tuning.yaml``):

* ``long``: a grid whose samples solve the receptance directly (``method: kkt``, 1801
  frequencies, about 1.5-3 s each), at least 30 s in-process;
* ``short``: many quick samples (``method: modal``, 181 frequencies, tens of ms each), where
  the per-task cost of Dask shows.

Each runs in-process (serial, the baseline), then on a LocalCluster of 1 and of 2 worker
processes (one thread each) started beforehand and reached through its scheduler's address, so
that the cluster's start-up is timed on its own.  The tables are checked to be identical
(bitwise) to the baseline.  The per-task overhead is
``(t_dask_1_worker - t_in_process) / samples`` (one worker does the same work as the serial
run, plus the scheduling, serialization and transfer of every task).

A third study, ``shared``, is the box beam of ``cases/box_beam_tmd.yaml`` (two Craig-Bampton
halves) on a grid of absorber stiffnesses: the halves do not depend on it, so they are reduced
once and shared; it runs in-process reducing them in every sample (the baseline), in-process
shared, and shared on 2 workers.  ``chunks`` is one run of that case with a 400-frequency
direct sweep, serial (baseline) against ``run_distributed`` on 2 workers (the two reductions as
tasks, the sweep in 2 and 8 chunks).

    OMP_NUM_THREADS=1 python benchmarks/study_dask.py [--repeat 3] [--long 20] [--short 200]
        [--shared 6] [--only long,short,shared,chunks]
"""

from __future__ import annotations

import argparse
import logging
import statistics
import time
from pathlib import Path

import numpy as np

from substruct.case.loader import load_case
from substruct.studies.study_backend import Backend
from substruct.studies.study_run import run_study

CASE = Path(__file__).resolve().parent.parent / "cases" / "tapered_rod_tuning.yaml"
BOX = CASE.parent / "box_beam_tmd.yaml"


def box_study(samples: int) -> list[str]:
    """The box beam with absorber tmd1's stiffness on a grid of ``samples`` values."""
    return ["parameters={k1: 2.035e+5}", "substructures[2].stiffness=k1",
            "analysis.frf.omega={start: 300, stop: 4500, num: 100, spacing: log}",
            f"study={{grid: {{parameters: [{{parameter: k1, start: 1.8e+5, stop: 2.2e+5, "
            f"num: {samples}}}]}}, collect: {{frequencies: 4, frf_peaks: "
            f"['right@1,0.05,0.1:z']}}}}"]


def study(samples: int, slow: bool) -> list[str]:
    """Overrides of a grid of ``samples`` stiffnesses at one damping."""
    sweep = ("{start: 30, stop: 39, num: 1801, spacing: linear}" if slow else
             "{start: 30, stop: 39, num: 181, spacing: linear}")
    return [f"study.grid.parameters[0]={{parameter: kc, start: 1100, stop: 1200, "
            f"num: {samples}}}",
            "study.grid.parameters[1]={parameter: cc, values: [3.7]}",
            f"analysis.frf.omega={sweep}",
            f"analysis.frf.method={'kkt' if slow else 'modal'}",
            "study.collect={frequencies: 4, frf_peaks: [rod@200]}"]


def timed(overrides: list[str], backend: Backend, repeat: int, case_file: Path = CASE,
          share: bool = True):
    """Median seconds of ``repeat`` runs, and the last result."""
    times, result = [], None
    for _ in range(repeat):
        case = load_case(case_file, overrides)
        start = time.perf_counter()
        result = run_study(case, backend, share=share)
        times.append(time.perf_counter() - start)
    return statistics.median(times), result


def same(a, b) -> bool:
    return (np.array_equal(a.table, b.table) and a.errors == b.errors and
            all(np.array_equal(a.values[k], b.values[k], equal_nan=True) for k in a.values))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeat", type=int, default=3, help="runs of the short study")
    parser.add_argument("--long", type=int, default=20, help="samples of the long study")
    parser.add_argument("--short", type=int, default=200, help="samples of the short study")
    parser.add_argument("--shared", type=int, default=6, help="samples of the shared study")
    parser.add_argument("--only", default="long,short,shared,chunks",
                        help="which studies to run (comma-separated)")
    args = parser.parse_args()
    only = set(args.only.split(","))
    from distributed import Client, LocalCluster

    print(f"{'study':6s} {'samples':>7s} {'backend':18s} {'seconds':>9s} {'ratio':>7s} "
          f"{'overhead/task':>14s} identical", flush=True)

    def row(name: str, samples: int, backend: str, t: float, ratio: float, overhead: float,
            ok: bool) -> None:
        extra = f"{1e3 * overhead:11.1f} ms" if np.isfinite(overhead) and overhead else ""
        print(f"{name:6s} {samples:7d} {backend:18s} {t:9.2f} {ratio:7.2f} {extra:>14s} {ok}",
              flush=True)

    clusters = {}
    for n in (1, 2):
        start = time.perf_counter()
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                               host="127.0.0.1", dashboard_address=":0",
                               silence_logs=logging.ERROR, env={"OMP_NUM_THREADS": "1"})
        Client(cluster).close()
        clusters[n] = (cluster, time.perf_counter() - start)
        print(f"LocalCluster start-up, {n} worker{'s' * (n > 1)}: {clusters[n][1]:.2f} s",
              flush=True)
    try:
        for name, samples, slow, repeat in (("long", args.long, True, 1),
                                            ("short", args.short, False, args.repeat)):
            if name not in only:
                continue
            overrides = study(samples, slow)
            base, reference = timed(overrides, Backend(), repeat)
            row(name, samples, "in-process", base, 1.0, 0.0, True)
            for n, (cluster, _) in clusters.items():
                t, result = timed(overrides, Backend(scheduler=cluster.scheduler_address),
                                  repeat)
                overhead = (t - base) / samples if n == 1 else float("nan")
                row(name, samples, f"dask {n} worker{'s' * (n > 1)}", t, t / base, overhead,
                    same(reference, result))
        if "shared" in only:
            overrides = box_study(args.shared)
            base, reference = timed(overrides, Backend(), 1, BOX, share=False)
            row("shared", args.shared, "in-process, each", base, 1.0, 0.0, True)
            t, result = timed(overrides, Backend(), 1, BOX)
            row("shared", args.shared, "in-process, once", t, t / base, 0.0,
                same(reference, result))
            t, result = timed(overrides, Backend(scheduler=clusters[2][0].scheduler_address),
                              1, BOX)
            row("shared", args.shared, "dask 2, once", t, t / base, 0.0,
                same(reference, result))
        if "chunks" in only:
            from substruct.run.runner import run_case
            from substruct.studies.distributed_run import run_distributed

            case = load_case(BOX, ["analysis.frf.omega={start: 300, stop: 4500, num: 400, "
                                   "spacing: log}"])
            start = time.perf_counter()
            serial = run_case(case)
            base = time.perf_counter() - start
            row("chunks", 400, "serial run_case", base, 1.0, 0.0, True)
            address = clusters[2][0].scheduler_address
            for chunks in (2, 8):
                start = time.perf_counter()
                got = run_distributed(case, Backend(scheduler=address), chunks=chunks)
                t = time.perf_counter() - start
                assert got.frf is not None and serial.frf is not None
                row("chunks", 400, f"dask 2, {chunks} chunks", t, t / base, 0.0,
                    bool(np.array_equal(got.frf.H, serial.frf.H)))
    finally:
        for cluster, _ in clusters.values():
            cluster.close()


if __name__ == "__main__":
    main()
