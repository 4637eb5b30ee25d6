"""AMLS against shift-invert Lanczos: the lowest k modes of a clamped solid box.

    OMP_NUM_THREADS=1 python benchmarks/amls.py [--sizes 30000 300000 1000000 2000000]
        [--modes 50 200 500 2000] [--cutoff 2] [--iterations 2] [--ritz-ratio 1.2]
        [--leaf-size 1000]
        [--workers N] [--lanczos-dir DIR] [--amls-only 1000000 ...] [--quick] [--accuracy]

The model: a steel box ``4 x 1 x 1`` of Q1 hexahedra clamped at ``x = 0`` (the monolithic mesh
of benchmarks/modes.py).  For each size and number of modes k, each in a fresh subprocess
(peak memory: the process's ``VmHWM`` during the solve, reset before it):

(a) Lanczos: ``eigsh`` shift-invert (ARPACK) with ``OPinv`` the registry's factorization of
    ``K - sigma M`` (:func:`substruct.linalg.lanczos.shift_invert_lanczos`), k + 1 modes; the
    wanted frequency is then put halfway between modes k and k + 1;
(b) AMLS (:func:`substruct.linalg.amls.amls_modes`) for every mode below that frequency, with
    the cut-off (a multiple of it), leaf size and subspace iterations given.

The table: wall and CPU seconds and peak MB of both, the ratio of times, the number of
reduced coordinates, the count of AMLS modes against k, the largest relative frequency error
against (a) and the largest relative residual ``||K u - w^2 M u|| / ||K u||`` of AMLS.  With
several sizes or numbers of modes, the exponents of the fitted growth ``t ~ n^a`` (for each k)
and ``t ~ k^b`` (for each n) follow.  ``--lanczos-dir DIR``: each Lanczos measurement is
written to ``DIR/lanczos_<size>_<k>.json`` and read from there when present, so that AMLS
settings or versions are compared against one Lanczos run (its seconds and peak are those of
that run, on the same machine).  ``--workers N``: the AMLS side runs its tree's blocks as
tasks on a Dask LocalCluster of N worker processes (``substruct run --workers N``); its
reduction time ("A: red s") against the single-process run's is the parallel speed-up.
``--amls-only SIZE ...``: sizes whose Lanczos reference would not fit in memory (about 28 GB
at 10^6 coordinates), run by AMLS alone up to the wanted frequency of the largest ``--sizes``
row (the same box's frequencies, converged with the mesh): the modes found, the residuals,
the time and memory, and AMLS's own growth ``t ~ n^a`` over every size.

``--accuracy``: the cut-off against accuracy on a small clamped box (24 x 6 x 6 Q1, 3,528
coordinates, the 30 lowest modes, leaves of at most 200 coordinates, no iteration), against a
dense ``eigh``: for each cut-off multiple, the reduced size and the largest relative error of
the frequencies, then the fitted rate ``err ~ r^-p``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np
import scipy.sparse as sp

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from modes import _reset_peak, _status, divisions, machine  # noqa: E402


def box(size: int) -> tuple[sp.csr_array, sp.csr_array]:
    from substruct.models.solid import BoxGrid, solid_box
    nxh, m = divisions(size)
    b = solid_box("box", BoxGrid((4.0, 1.0, 1.0), (2 * nxh, m, m)), 2.1e11, 0.3, 7850.0,
                  fixed=[{"box": [[0, 0, 0], [0, 1, 1]]}])
    return sp.csr_array(b.K), sp.csr_array(b.M)


def worker(args: argparse.Namespace) -> dict:
    K, M = box(args.size)
    _reset_peak()
    t0, c0 = time.perf_counter(), time.process_time()
    if args.worker == "lanczos":
        from substruct.linalg.factorize import factorizer
        from substruct.linalg.lanczos import shift_invert_lanczos
        sigma = -1e-9 * K.diagonal().sum() / M.diagonal().sum()
        solve = factorizer("auto")(sp.csc_array(K - sigma * M))
        v0 = np.random.default_rng(0).standard_normal(K.shape[0])
        lam, _ = shift_invert_lanczos(K, M, args.k + 1, sigma, solve, v0=v0)
        out = {"lam": np.sort(lam).tolist()}
    else:
        from substruct.linalg.amls import amls_modes
        kw = dict(cutoff=args.cutoff, leaf_size=args.leaf_size, iterations=args.iterations,
                  ritz_ratio=args.ritz_ratio)
        if args.workers:
            from substruct.studies.study_backend import Backend, Session
            with Session(Backend(workers=args.workers)) as session:
                _reset_peak()
                t0, c0 = time.perf_counter(), time.process_time()
                r = amls_modes(K, M, args.omega_max, tasks=session, **kw)
        else:
            r = amls_modes(K, M, args.omega_max, **kw)
        out = {"lam": r.lam.tolist(), "residual": float(r.residual.max(initial=0)),
               "n_reduced": r.n_reduced, "times": r.times}
    out.update(n=K.shape[0], time=time.perf_counter() - t0, cpu=time.process_time() - c0,
               peak=_status("VmHWM"))
    return out


def measure(kind: str, size: int, k: int, args: argparse.Namespace,
            omega_max: float = 0.0) -> dict:
    env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
           "MKL_NUM_THREADS": "1"}
    cmd = [sys.executable, __file__, "--worker", kind, "--size", str(size), "--k", str(k),
           "--omega-max", repr(omega_max), "--cutoff", str(args.cutoff), "--iterations",
           str(args.iterations), "--leaf-size", str(args.leaf_size), "--ritz-ratio",
           str(args.ritz_ratio), "--workers", str(args.workers if kind == "amls" else 0)]
    out = subprocess.run(cmd, env=env, capture_output=True, text=True)
    if out.returncode != 0:
        raise RuntimeError(f"worker {kind} {size} {k} failed:\n{out.stderr[-3000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def lanczos(size: int, k: int, args: argparse.Namespace) -> dict:
    """The Lanczos measurement of ``size``, ``k``: from ``--lanczos-dir`` if stored there,
    else measured (and stored there)."""
    if not args.lanczos_dir:
        return measure("lanczos", size, k, args)
    path = os.path.join(args.lanczos_dir, f"lanczos_{size}_{k}.json")
    if os.path.exists(path):
        with open(path) as f:
            return json.load(f)
    a = measure("lanczos", size, k, args)
    os.makedirs(args.lanczos_dir, exist_ok=True)
    with open(path, "w") as f:
        json.dump(a, f)
    return a


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", type=int, nargs="+", default=[30000, 100000])
    p.add_argument("--modes", type=int, nargs="+", default=[50, 200, 500])
    p.add_argument("--cutoff", type=float, default=2.0)
    p.add_argument("--iterations", type=int, default=2)
    p.add_argument("--ritz-ratio", type=float, default=1.2)
    p.add_argument("--leaf-size", type=int, default=1000)
    p.add_argument("--quick", action="store_true", help="30000 coordinates only")
    p.add_argument("--workers", type=int, default=0,
                   help="AMLS: the tree's blocks as tasks on a LocalCluster of N workers")
    p.add_argument("--accuracy", action="store_true",
                   help="the cut-off against accuracy table (small box, dense reference)")
    p.add_argument("--lanczos-dir", default=None,
                   help="reuse (or store) the Lanczos measurements in this directory")
    p.add_argument("--amls-only", type=int, nargs="+", default=[],
                   help="sizes too large for a Lanczos reference on this machine, run by AMLS "
                        "alone up to the wanted frequency of the largest --sizes row (the "
                        "same box, its frequencies converged): modes found, residuals, time")
    p.add_argument("--json", default=None, help="also write the raw measurements here")
    p.add_argument("--worker", choices=["lanczos", "amls"], help=argparse.SUPPRESS)
    p.add_argument("--size", type=int, help=argparse.SUPPRESS)
    p.add_argument("--k", type=int, help=argparse.SUPPRESS)
    p.add_argument("--omega-max", type=float, help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.worker:
        print(json.dumps(worker(args)))
        return
    if args.accuracy:
        accuracy()
        return
    sizes = [30000] if args.quick else args.sizes
    print(f"machine: {machine()}")
    print(f"AMLS: cut-off {args.cutoff} x the wanted frequency, {args.iterations} subspace "
          f"iteration(s) on the Ritz vectors up to {args.ritz_ratio} x, leaves <= "
          f"{args.leaf_size} coordinates; Lanczos: eigsh shift-invert, registry factorization")
    if args.workers:
        print(f"AMLS on a Dask LocalCluster of {args.workers} workers")
    head = (f"{'n':>7} {'k':>4} {'L: s':>7} {'L: cpu':>7} {'L: MB':>6} {'A: s':>7} "
            f"{'A: cpu':>7} {'A: MB':>6} {'A/L t':>6} {'A: red s':>8} {'n_red':>6} "
            f"{'found':>5} {'max df/f':>9} {'max res':>8}")
    print(head)
    rows = []
    for size in sizes:
        for k in args.modes:
            a = lanczos(size, k, args)
            lam = np.array(a["lam"])
            wmax = float(np.sqrt(0.5 * (lam[k - 1] + lam[k])))
            b = measure("amls", size, k, args, wmax)
            lb = np.array(b["lam"])
            m = min(lb.size, k)
            err = float(np.max(np.abs(np.sqrt(lb[:m] / lam[:m]) - 1))) if m else float("nan")
            rows.append({"lanczos": a, "amls": b, "k": k, "freq_err": err})
            print(f"{a['n']:>7} {k:>4} {a['time']:>7.1f} {a['cpu']:>7.1f} "
                  f"{a['peak'] / 2**20:>6.0f} {b['time']:>7.1f} {b['cpu']:>7.1f} "
                  f"{b['peak'] / 2**20:>6.0f} {b['time'] / a['time']:>6.2f} "
                  f"{b['times']['reduce']:>8.1f} {b['n_reduced']:>6} {lb.size:>5} "
                  f"{err:>9.1e} {b['residual']:>8.1e}", flush=True)
    alone = []
    for size in args.amls_only:
        for k in args.modes:
            ref = [r for r in rows if r["k"] == k][-1]["lanczos"]
            lam = np.array(ref["lam"])
            wmax = float(np.sqrt(0.5 * (lam[k - 1] + lam[k])))
            b = measure("amls", size, k, args, wmax)
            alone.append({"amls": b, "k": k})
            print(f"{b['n']:>7} {k:>4} {'-':>7} {'-':>7} {'-':>6} {b['time']:>7.1f} "
                  f"{b['cpu']:>7.1f} {b['peak'] / 2**20:>6.0f} {'-':>6} "
                  f"{b['times']['reduce']:>8.1f} {b['n_reduced']:>6} {len(b['lam']):>5} "
                  f"{'-':>9} {b['residual']:>8.1e}", flush=True)
    growth(rows)
    growth_alone(rows + alone)
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"machine": machine(), "rows": rows, "args": vars(args)}, f, indent=1)


def growth(rows: list[dict]) -> None:
    """The fitted exponents of ``t ~ n^a`` (each k, over the sizes) and ``t ~ k^b`` (each n,
    over the numbers of modes), for Lanczos and AMLS (least squares on the logarithms)."""
    def slope(x: list[float], y: list[float]) -> float:
        return float(np.polyfit(np.log(x), np.log(y), 1)[0])

    for key, other, name in (("k", "n", "modes"), ("n", "k", "DOF")):
        groups: dict[int, list[dict]] = {}
        for r in rows:
            groups.setdefault(r["k"] if key == "k" else r["lanczos"]["n"], []).append(r)
        for value, rs in sorted(groups.items()):
            if len(rs) < 2:
                continue
            x = [r["lanczos"]["n"] if key == "k" else r["k"] for r in rs]
            fit = {f"{side} {what}": slope(x, [r[side][what] for r in rs])
                   for side in ("lanczos", "amls") for what in ("time", "cpu")}
            print(f"growth at {key} = {value}: t ~ {other}^a over {other} = "
                  f"{', '.join(str(v) for v in x)}: Lanczos a = {fit['lanczos time']:.2f} "
                  f"(CPU {fit['lanczos cpu']:.2f}), AMLS a = {fit['amls time']:.2f} "
                  f"(CPU {fit['amls cpu']:.2f})")


def growth_alone(rows: list[dict]) -> None:
    """AMLS's own ``t ~ n^a`` (whole run and reduction) for each k over every size run,
    those without a Lanczos reference included."""
    for k in sorted({r["k"] for r in rows}):
        rs = [r["amls"] for r in rows if r["k"] == k]
        if len(rs) < 2:
            continue
        n = np.log([r["n"] for r in rs])
        whole = float(np.polyfit(n, np.log([r["time"] for r in rs]), 1)[0])
        red = float(np.polyfit(n, np.log([r["times"]["reduce"] for r in rs]), 1)[0])
        print(f"AMLS growth at k = {k} over n = {', '.join(str(r['n']) for r in rs)}: "
              f"t ~ n^{whole:.2f}, reduction ~ n^{red:.2f}")


def accuracy() -> None:
    """The cut-off against accuracy table (module docstring)."""
    import scipy.linalg as sla

    from substruct.linalg.amls import amls_modes
    from substruct.models.solid import BoxGrid, solid_box
    b = solid_box("box", BoxGrid((4.0, 1.0, 1.0), (24, 6, 6)), 2.1e11, 0.3, 7850.0,
                  fixed=[{"box": [[0, 0, 0], [0, 1, 1]]}])
    K, M = sp.csr_array(b.K), sp.csr_array(b.M)
    lam = sla.eigh(K.toarray(), M.toarray(), eigvals_only=True)
    k = 30
    wmax = float(np.sqrt(0.5 * (lam[k - 1] + lam[k])))
    print(f"clamped box 24 x 6 x 6 Q1, {K.shape[0]} coordinates, the {k} modes below "
          f"{wmax:.1f} rad/s, leaves <= 200, no iteration; reference: dense eigh")
    print(f"{'cut-off':>8} {'reduced':>8} {'found':>6} {'max df/f':>9} {'median df/f':>11}")
    cut, err = [], []
    for r in (1.5, 2.0, 3.0, 4.0, 6.0, 8.0, 1e6):
        out = amls_modes(K, M, wmax, cutoff=r, leaf_size=200)
        m = out.lam.size
        rel = np.sqrt(out.lam / lam[:m]) - 1
        print(f"{r:>8g} {out.n_reduced:>8} {m:>6} {rel.max():>9.1e} {np.median(rel):>11.1e}")
        if out.n_reduced < K.shape[0]:   # truncated (every mode kept: round-off)
            cut.append(r)
            err.append(float(rel.max()))
    rate = -float(np.polyfit(np.log(cut), np.log(err), 1)[0])
    print(f"fitted on the truncated rows: max df/f ~ r^-{rate:.1f} (cut-off {cut[0]:g} to "
          f"{cut[-1]:g})")


if __name__ == "__main__":
    main()
