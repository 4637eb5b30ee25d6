"""Virtual point transformation and coupling: substruct against pyFBS on the same data.

Two parts, each with ``--vps`` virtual points; every virtual point has three triaxial sensors
and ``--impacts`` impacts on a 50 mm adapter (random rotations and offsets, fixed seed), and
each part two more sensors and impacts that pass through.  The "measured" receptances are the
rigid-adapter kinematics of a random symmetric complex receptance of the virtual points and
pass-through channels (``R_u Y_q R_f^T``), so that the exact answer is known; ``--noise``
multiplies every entry by ``1 + eps n`` (complex Gaussian ``n``).

Measured, each the median of ``--repeat`` runs, in CPU time of the process (one BLAS thread:
run with ``OMP_NUM_THREADS=1``; CPU time does not count the waits of a shared machine):

* substruct: ``virtual_point_transform`` (both parts), ``vp_part`` (the transformation of the
  receptances) and ``couple_virtual_points`` (LM-FBS at every virtual point);
* pyFBS (in its own environment, ``--pyfbs PYTHON``): ``pyfbs.interface.vpt.VPT`` built from
  its channel and impact data frames, ``apply_vpt``, and the LM-FBS of its documentation
  examples written in numpy (pyFBS has no coupling function).

The transformed receptances of the two are compared entry by entry (the largest difference
over the largest entry), and the substruct transformation against the exact ``Y_q``.

    python benchmarks/vpt.py                                   # substruct alone
    python benchmarks/vpt.py --pyfbs /path/to/venv/bin/python  # and pyFBS on the same data
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


def _rotation(rng: np.random.Generator) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    return q * np.sign(np.diag(r))[None, :]


def make_data(n_freq: int, n_vp: int, n_imp: int, seed: int) -> dict:
    """Channel geometry, virtual points and the receptances of two parts."""
    rng = np.random.default_rng(seed)
    data: dict = {"parts": []}
    for part in ("A", "B"):
        sens, imps, vps = [], [], []
        for v in range(n_vp):
            c = np.array([0.3 * v, 0.1 * (v % 2), 0.0])
            vps.append((f"V{v}", c.tolist()))
            for s in range(3):
                axes, spot = _rotation(rng), c + rng.uniform(-0.025, 0.025, 3)
                for a in range(3):
                    sens.append((f"{part}V{v}S{s}{'xyz'[a]}", spot.tolist(), axes[:, a].tolist(),
                                 v))
            for h in range(n_imp):
                d = rng.normal(size=3)
                imps.append((f"{part}V{v}H{h}", (c + rng.uniform(-0.025, 0.025, 3)).tolist(),
                             (d / np.linalg.norm(d)).tolist(), v))
        for k in range(2):
            sens.append((f"{part}P{k}", [1.0 + k, 0.5, 0.0], [0.0, 0.0, 1.0], -1))
            imps.append((f"{part}Q{k}", [1.0 + k, 0.5, 0.1], [1.0, 0.0, 0.0], -1))
        data["parts"].append({"name": part, "sensors": sens, "impacts": imps, "vps": vps})
    data["n_freq"] = n_freq
    data["seed"] = seed
    return data


def _idm(pos, d, p):
    r = np.asarray(pos) - np.asarray(p)
    return np.concatenate([d, np.cross(r, d)])


def receptances(data: dict, noise: float) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """The measured receptance of each part and the exact one of its virtual points (and
    pass-through channels)."""
    rng = np.random.default_rng(data["seed"] + 1)
    measured, exact = [], []
    for p in data["parts"]:
        vp_pos = [c for _, c in p["vps"]]
        n_q = 6 * len(vp_pos) + 2
        k = data["n_freq"]
        X = rng.normal(size=(k, n_q, n_q)) + 1j * rng.normal(size=(k, n_q, n_q))
        Yq = (X + np.swapaxes(X, 1, 2)) * 1e-6

        def rows(chans):
            R = np.zeros((len(chans), n_q))
            for i, (_, pos, d, v) in enumerate(chans):
                if v >= 0:
                    R[i, 6 * v:6 * v + 6] = _idm(pos, d, vp_pos[v])
                else:
                    R[i, 6 * len(vp_pos) + int(_[-1])] = 1.0
            return R

        Ru, Rf = rows(p["sensors"]), rows(p["impacts"])
        Y = np.einsum("sq,kqm,im->ksi", Ru, Yq, Rf, optimize=True)
        if noise:
            Y = Y * (1 + noise * (rng.normal(size=Y.shape) + 1j * rng.normal(size=Y.shape))
                     / np.sqrt(2))
        measured.append(Y)
        exact.append(Yq)
    return measured, exact


def run_substruct(data: dict, Ys: list[np.ndarray], repeat: int) -> dict:
    sys.path.insert(0, str(HERE.parent))
    from substruct.analysis.frf.virtual_point import VirtualPoint, virtual_point_transform
    from substruct.analysis.frf.vp_coupling import couple_virtual_points, vp_part
    from substruct.case.channels import parse_channels

    omega = np.linspace(1.0, 1000.0, data["n_freq"])
    times: dict[str, list[float]] = {"transform": [], "couple": [], "checked": []}
    for _ in range(repeat):
        t0 = time.process_time()
        parts = []
        for p, Y in zip(data["parts"], Ys):
            rows = [{"name": n, "node": "1", "x": x[0], "y": x[1], "z": x[2], "dx": d[0],
                     "dy": d[1], "dz": d[2], "kind": kind}
                    for chans, kind in ((p["sensors"], "sensor"), (p["impacts"], "impact"))
                    for n, x, d, _ in chans]
            table = parse_channels(rows, p["name"])
            vps = [VirtualPoint(name, tuple(c),
                                tuple(s[0] for s in p["sensors"] if s[3] == v),
                                tuple(h[0] for h in p["impacts"] if h[3] == v))
                   for v, (name, c) in enumerate(p["vps"])]
            vpt = virtual_point_transform(table, vps, [s[0] for s in p["sensors"]],
                                          [h[0] for h in p["impacts"]])
            parts.append(vp_part(p["name"], omega, vpt, Y))
        t1 = time.process_time()
        pairs = [(f"A@{name}:{c}", f"B@{name}:{c}") for name, _ in data["parts"][0]["vps"]
                 for c in ("x", "y", "z", "rx", "ry", "rz")]
        couple_virtual_points(parts, pairs, check=False)
        t2 = time.process_time()
        res = couple_virtual_points(parts, pairs)
        t3 = time.process_time()
        times["transform"].append(t1 - t0)
        times["couple"].append(t2 - t1)
        times["checked"].append(t3 - t2)
    return {"times": {k: float(np.median(v)) for k, v in times.items()},
            "Yq": [p.Y for p in parts], "agreement": res.agreement}


def run_pyfbs(data: dict, Ys: list[np.ndarray], repeat: int) -> dict:
    import pandas as pd
    from pyfbs.interface.vpt import VPT

    def frame(chans, vp_of, kind):
        rows = []
        for n, x, d, v in chans:
            rows.append({"Name": n, "Description": "ux" if kind == "chn" else "fx",
                         "Quantity": "Acceleration", "Grouping": v if v >= 0 else 100 + len(rows),
                         "Position_1": x[0], "Position_2": x[1], "Position_3": x[2],
                         "Direction_1": d[0], "Direction_2": d[1], "Direction_3": d[2]})
        return pd.DataFrame(rows)

    def vp_frame(vps, kind):
        comps = ("ux", "uy", "uz", "rx", "ry", "rz") if kind == "chn" else \
            ("fx", "fy", "fz", "mx", "my", "mz")
        rows = []
        for v, (name, c) in enumerate(vps):
            for q in comps:
                rows.append({"Name": f"{name}-{q}", "Description": q, "Quantity": "Acceleration",
                             "Grouping": v, "Position_1": c[0], "Position_2": c[1],
                             "Position_3": c[2], "Direction_1": 1.0, "Direction_2": 0.0,
                             "Direction_3": 0.0})
        return pd.DataFrame(rows)

    freq = np.linspace(1.0, 1000.0, data["n_freq"]) / (2 * np.pi)
    times: dict[str, list[float]] = {"transform": [], "couple": []}
    for _ in range(repeat):
        t0 = time.process_time()
        out = []
        for p, Y in zip(data["parts"], Ys):
            vpt = VPT(frame(p["sensors"], None, "chn"), frame(p["impacts"], None, "imp"),
                      vp_frame(p["vps"], "chn"), vp_frame(p["vps"], "imp"))
            vpt.apply_vpt(freq, Y)
            out.append(vpt.frf)
        t1 = time.process_time()
        n = [Yq.shape[1] for Yq in out]
        n_vp = 6 * len(data["parts"][0]["vps"])
        Y = np.zeros((len(freq), sum(n), sum(n)), dtype=complex)
        Y[:, :n[0], :n[0]] = out[0]
        Y[:, n[0]:, n[0]:] = out[1]
        B = np.zeros((n_vp, sum(n)))
        B[:, :n_vp] = np.eye(n_vp)
        B[:, n[0]:n[0] + n_vp] = -np.eye(n_vp)
        Y - Y @ B.T @ np.linalg.inv(B @ Y @ B.T) @ B @ Y
        t2 = time.process_time()
        times["transform"].append(t1 - t0)
        times["couple"].append(t2 - t1)
    return {"times": {k: float(np.median(v)) for k, v in times.items()}, "Yq": out}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--freq", type=int, default=1000)
    ap.add_argument("--vps", type=int, default=6)
    ap.add_argument("--impacts", type=int, default=8)
    ap.add_argument("--noise", type=float, default=0.0)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--pyfbs", help="the python of an environment with pyFBS")
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    args = ap.parse_args()
    data = make_data(args.freq, args.vps, args.impacts, seed=5)
    Ys, exact = receptances(data, args.noise)
    if args.worker:  # inside the pyFBS environment
        res = run_pyfbs(data, Ys, args.repeat)
        np.savez(args.worker, A=res["Yq"][0], B=res["Yq"][1],
                 times=json.dumps(res["times"]))
        return
    n_ch = len(data["parts"][0]["sensors"])
    print(f"{args.freq} frequencies, {args.vps} virtual points, {n_ch} sensor and "
          f"{len(data['parts'][0]['impacts'])} impact channels a part, noise {args.noise}")
    ours = run_substruct(data, Ys, args.repeat)
    err = max(float(np.abs(a - e).max() / np.abs(e).max()) for a, e in zip(ours["Yq"], exact))
    print(f"substruct: transform {ours['times']['transform']:.3f} s, couple "
          f"{ours['times']['couple']:.3f} s ({ours['times']['checked']:.3f} s with the "
          f"generalized-inverse check); Y_qm vs exact {err:.1e}; LM-FBS vs generalized "
          f"inverse {ours['agreement']:.1e}")
    if args.pyfbs:
        with tempfile.TemporaryDirectory() as tmp:
            out = Path(tmp) / "pyfbs.npz"
            env = dict(os.environ, PYTHONPATH="")
            subprocess.run([args.pyfbs, __file__, "--freq", str(args.freq), "--vps",
                            str(args.vps), "--impacts", str(args.impacts), "--noise",
                            str(args.noise), "--repeat", str(args.repeat), "--worker", str(out)],
                           check=True, env=env)
            z = np.load(out)
            theirs = [z["A"], z["B"]]
            t = json.loads(str(z["times"]))
        diff = max(float(np.abs(a - b).max() / np.abs(a).max())
                   for a, b in zip(ours["Yq"], theirs))
        err_p = max(float(np.abs(a - e).max() / np.abs(e).max())
                    for a, e in zip(theirs, exact))
        print(f"pyFBS:     transform {t['transform']:.3f} s, couple {t['couple']:.3f} s; "
              f"Y_qm vs exact {err_p:.1e}, vs substruct {diff:.1e}")
        print(f"time ratio substruct / pyFBS: transform "
              f"{ours['times']['transform'] / t['transform']:.2f}, couple "
              f"{ours['times']['couple'] / t['couple']:.2f}")


if __name__ == "__main__":
    main()
