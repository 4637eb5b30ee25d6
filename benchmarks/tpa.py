"""Operational TPA: substruct's transmissibility and path contributions against pyFBS.

Synthetic operating data with a known answer: a modal model (``--modes`` modes with random
real shapes, 2% damping) gives the receptances ``H_is`` from ``--sources`` operating-force
places to ``--indicators`` indicator channels and ``H_ts`` to ``--targets`` targets at
``--freq`` frequencies; ``--conditions`` operating conditions are random complex force
vectors ``F`` (``n_s x n_o`` at every frequency), and the "measured" operating responses are
``U_i = H_is F``, ``U_t = H_ts F``, no noise.  One more condition ``u_i``, ``u_t`` is held out
to validate the prediction.  Two cases:

* ``full``: as many sources as indicators (``--sources`` defaults to ``--indicators``), so
  ``T = U_t U_i^+`` is exactly ``H_ts H_is^-1``;
* ``rank``: half as many sources (``U_i`` of rank ``n_s < n_i``), ``T`` is then not unique and
  the least-squares, minimum-norm one is ``H_ts H_is^+``; the pseudo-inverse must drop the
  ``n_i - n_s`` singular values that are round-off.

pyFBS 1.0.7 has no transmissibility function (its ``pyfbs.tpa`` holds the operational system
identification ``osi_var1``, ``osi_var2``, ``mimo_osi``: receptances estimated from time
signals of responses and forces, one force at a time, a step that comes before this one and
that substruct does not have).  Its pseudo-inverse ``pyfbs.tpinv`` (an SVD; ``trunc`` removes
that many of the smallest singular values) is what its examples write the inversions with,
so its side is ``T = U_t @ tpinv(U_i, trunc)``, the prediction ``T @ u_i`` and the
contributions ``T * u_i`` in numpy.  ``tpinv``'s default ``trunc=None`` raises a TypeError in
1.0.7, so ``trunc=0`` (no truncation) is passed for ``full``; for ``rank`` the run is done
twice, with ``trunc=0`` and with ``trunc = n_i - n_s``.  substruct's side is
``transmissibility`` with its default (singular values below ``1e-12`` of the largest
dropped) and ``operational_contributions``; for ``rank`` also with
``Regularisation("tsvd", rank=n_s)``, the same truncation as ``trunc = n_i - n_s``.

Each time is the median of ``--repeat`` runs in CPU time of the process (run with
``OMP_NUM_THREADS=1``).  The differences are the largest, over the frequencies, of the
largest entry difference over the largest entry at that frequency.

    python benchmarks/tpa.py                                   # substruct alone
    python benchmarks/tpa.py --pyfbs /path/to/venv/bin/python  # and pyFBS on the same data
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


def make_data(n_freq: int, n_i: int, n_t: int, n_s: int, n_o: int, n_modes: int,
              seed: int) -> dict[str, np.ndarray]:
    """Receptances of a modal model and the operating responses of ``n_o + 1`` conditions."""
    rng = np.random.default_rng(seed)
    omega = np.linspace(10.0, 2000.0, n_freq)
    wr = np.sort(rng.uniform(50.0, 2500.0, n_modes))
    phi = rng.normal(size=(n_i + n_t + n_s, n_modes))
    den = 1.0 / (wr[None, :] ** 2 - omega[:, None] ** 2 + 2j * 0.02 * wr[None, :]
                 * omega[:, None])
    src = phi[n_i + n_t:]
    H = np.einsum("pr,kr,sr->kps", phi[:n_i + n_t], den, src, optimize=True)
    F = rng.normal(size=(n_freq, n_s, n_o + 1)) + 1j * rng.normal(size=(n_freq, n_s, n_o + 1))
    U = H @ F
    return {"omega": omega, "H_is": H[:, :n_i], "H_ts": H[:, n_i:],
            "U_i": U[:, :n_i, :n_o], "U_t": U[:, n_i:, :n_o],
            "u_i": U[:, :n_i, n_o], "u_t": U[:, n_i:, n_o]}


def rel(a: np.ndarray, b: np.ndarray) -> float:
    """max over frequencies of max|a - b| / max|b| at that frequency."""
    d = np.abs(a - b).reshape(len(a), -1).max(axis=1)
    return float((d / np.abs(b).reshape(len(b), -1).max(axis=1)).max())


def _timed(fn, repeat: int):
    times, out = [], None
    for _ in range(repeat):
        t0 = time.process_time()
        out = fn()
        times.append(time.process_time() - t0)
    return out, float(np.median(times))


def run_substruct(d: dict[str, np.ndarray], trunc: int, repeat: int) -> dict:
    """``transmissibility`` (default, or TSVD keeping ``n_i - trunc`` values if ``trunc``)
    and ``operational_contributions``."""
    sys.path.insert(0, str(HERE.parent))
    from substruct.analysis.frf.tpa_operational import (operational_contributions,
                                                         transmissibility)
    from substruct.analysis.frf.vp_coupling import Regularisation

    n_i = d["U_i"].shape[1]
    reg = Regularisation("tsvd", rank=n_i - trunc) if trunc else Regularisation()
    T, t_T = _timed(lambda: transmissibility(d["U_i"], d["U_t"], reg), repeat)
    C, t_C = _timed(lambda: operational_contributions(T, d["u_i"]), repeat)
    return {"T": T, "C": C, "pred": C.sum(axis=2), "t_T": t_T, "t_C": t_C}


def run_pyfbs(d: dict[str, np.ndarray], trunc: int, repeat: int) -> dict:
    """``U_t @ pyfbs.tpinv(U_i, trunc)``, ``T * u_i`` and ``T @ u_i``."""
    import pyfbs

    T, t_T = _timed(lambda: d["U_t"] @ pyfbs.tpinv(d["U_i"], trunc=trunc), repeat)
    C, t_C = _timed(lambda: T * d["u_i"][:, None, :], repeat)
    pred = (T @ d["u_i"][:, :, None])[:, :, 0]
    return {"T": T, "C": C, "pred": pred, "t_T": t_T, "t_C": t_C}


def cases(n_i: int, n_s: int) -> list[tuple[str, int, int]]:
    """(name, number of sources, pyFBS truncations) of the two cases."""
    return [("full", n_s, 0), ("rank", n_s // 2, 0), ("rank", n_s // 2, n_i - n_s // 2)]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--freq", type=int, default=1000)
    ap.add_argument("--indicators", type=int, default=12)
    ap.add_argument("--targets", type=int, default=4)
    ap.add_argument("--sources", type=int, help="default: as many as indicators")
    ap.add_argument("--conditions", type=int, default=20)
    ap.add_argument("--modes", type=int, default=40)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--pyfbs", help="the python of an environment with pyFBS")
    ap.add_argument("--worker", nargs=2, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:  # inside the pyFBS environment: data in, results out
        src, dst = args.worker
        z = dict(np.load(src))
        out = {}
        for n, (name, _, trunc) in enumerate(json.loads(str(z.pop("cases")))):
            d = {k[len(f"{n}_"):]: v for k, v in z.items() if k.startswith(f"{n}_")}
            r = run_pyfbs(d, trunc, args.repeat)
            out.update({f"{n}_{k}": v for k, v in r.items()})
        np.savez(dst, **out)
        return
    n_i, n_t, n_o = args.indicators, args.targets, args.conditions
    n_s = args.sources or n_i
    todo = cases(n_i, n_s)
    data = [make_data(args.freq, n_i, n_t, s, n_o, args.modes, seed=7) for _, s, _ in todo]
    print(f"{args.freq} frequencies, {n_i} indicators, {n_t} targets, {n_o} operating "
          f"conditions (+1 held out), {args.modes} modes, no noise")
    theirs: list[dict] = []
    if args.pyfbs:
        with tempfile.TemporaryDirectory() as tmp:
            src, dst = Path(tmp) / "data.npz", Path(tmp) / "pyfbs.npz"
            np.savez(src, cases=json.dumps(todo),
                     **{f"{n}_{k}": v for n, d in enumerate(data) for k, v in d.items()
                        if k in ("U_i", "U_t", "u_i")})
            subprocess.run([args.pyfbs, __file__, "--repeat", str(args.repeat), "--worker",
                            str(src), str(dst)], check=True, env=dict(os.environ, PYTHONPATH=""))
            z = np.load(dst)
            theirs = [{k: z[f"{n}_{k}"] for k in ("T", "C", "pred", "t_T", "t_C")}
                      for n in range(len(todo))]
    for n, ((name, s, trunc), d) in enumerate(zip(todo, data)):
        exact_T = d["H_ts"] @ np.linalg.pinv(d["H_is"])
        sv = np.linalg.svd(d["U_i"], compute_uv=False)
        cond = float((sv[:, 0] / sv[:, s - 1]).max())
        ours = run_substruct(d, 0 if name == "full" or trunc == 0 else trunc, args.repeat)
        how = "default" if name == "full" or trunc == 0 else f"tsvd rank {n_i - trunc}"
        print(f"[{name}: {s} sources; U_i of rank {s}, condition up to {cond:.1e}]")
        print(f"    substruct ({how}): T {ours['t_T'] * 1e3:.1f} ms, "
              f"contributions {ours['t_C'] * 1e3:.2f} ms; T vs H_ts H_is^+ "
              f"{rel(ours['T'], exact_T):.1e}, prediction vs held-out u_t "
              f"{rel(ours['pred'], d['u_t']):.1e}")
        if theirs:
            p = theirs[n]
            print(f"    pyFBS (tpinv trunc={trunc}): T {float(p['t_T']) * 1e3:.1f} ms, "
                  f"contributions {float(p['t_C']) * 1e3:.2f} ms; T vs H_ts H_is^+ "
                  f"{rel(p['T'], exact_T):.1e}, prediction vs held-out u_t "
                  f"{rel(p['pred'], d['u_t']):.1e}")
            print(f"    substruct vs pyFBS: T {rel(p['T'], ours['T']):.1e}, contributions "
                  f"{rel(p['C'], ours['C']):.1e}, prediction {rel(p['pred'], ours['pred']):.1e}"
                  f"; time ratio substruct / pyFBS: T {ours['t_T'] / float(p['t_T']):.2f}, "
                  f"contributions {ours['t_C'] / float(p['t_C']):.2f}")


if __name__ == "__main__":
    main()
