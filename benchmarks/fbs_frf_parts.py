"""Coupling of two parts known only by their receptances (``type: frf``): substruct against
pyFBS's coupling step and a lean NumPy LM-FBS on the same data.

    OMP_NUM_THREADS=1 python benchmarks/fbs_frf_parts.py [--channels 100] [--interface 12]
        [--modes 40] [--frequencies 1000] [--repeat 3] [--pyfbs PYTHON] [--no-command]

The data: two parts of ``--channels`` channels each (nodes ``1, 2, ...`` in ``x, y, z``), of
which the first ``--interface`` are joined pairwise (``A@1:x`` to ``B@1:x``, ...), as
measured receptances are given: synthesised by modal sums (``--modes`` modes a part between
20 and 2,000 Hz, random real shapes, 1 to 3 % modal damping, plus a small random symmetric
residual flexibility so that every channel is independent, fixed seed) at ``--frequencies``
frequencies from 10 to 1,000 Hz, written as the ``.npz`` files of a case (``H``, ``labels``,
``omega``), and held in memory as read from them (a frequency's matrix contiguous).
Outputs and inputs: every channel of both parts.

Routes, in one process unless said:

(s) substruct, library: ``substruct.analysis.frf.coupling_selected.couple_selected``, what
    ``substruct run`` computes (LM-FBS by a linear solve a frequency for the outputs x inputs
    asked, the interface compatibility at every frequency, checked by the generalized-inverse
    form at 32 spread frequencies), warm: the median of ``--repeat`` calls, alternated with
    those of (l) (l s, s l, l s, ...) after one untimed call of each, so that neither route
    always finds the memory the other just freed;
(f) the same as a fresh process: imports, reading the two ``.npz`` files, the coupling;
(r) ``substruct run parts.yaml --quiet --no-pictures``: a case of two ``type: frf`` parts
    (the ``.npz`` files), the connections, ``analysis.frf`` on the files' grid, a fresh
    process (its checks and the HDF5 result file included);
(p) pyFBS's coupling step (``fbs_common.pyfbs_coupling``) in the pyFBS environment's Python
    (``--pyfbs``; not a dependency), a subprocess on the data saved to a temporary ``.npz``:
    timed inside the process after a warm-up, and as the whole process; without it the row
    says "pyFBS not importable";
(l) lean NumPy LM-FBS (``fbs_common.lean_lmfbs``), warm, alternated with (s).

CPU seconds (user + system; of the child for a fresh process); wall clock too.  Differences:
``max |H - H_l| / max |H_l|`` against (l).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
from fbs_common import child, lean_lmfbs, run_pyfbs  # noqa: E402

F_LO, F_HI = 10.0, 1000.0


def labels(n: int) -> list[str]:
    return [f"{1 + i // 3}:{'xyz'[i % 3]}" for i in range(n)]


def synthesise(n: int, modes: int, w: np.ndarray, seed: int) -> np.ndarray:
    r"""A measured-style receptance, ``sum_r phi_r phi_r^T / (w_r^2 - w^2 + 2 i z_r w_r w) +
    R``, ``(n_omega, n, n)``, complex symmetric."""
    rng = np.random.default_rng(seed)
    wr = 2 * np.pi * np.sort(rng.uniform(20.0, 2000.0, modes))
    zeta = rng.uniform(0.01, 0.03, modes)
    phi = rng.normal(size=(n, modes))
    G = rng.normal(size=(n, n))
    R = 0.02 * (G @ G.T) / (n * wr[-1] ** 2)
    den = wr**2 - w[:, None] ** 2 + 2j * zeta * wr * w[:, None]  # (k, modes)
    Y = np.einsum("ir,kr,jr->kij", phi, 1.0 / den, phi, optimize=True) + R[None]
    # laid out as the parts' files give it (a frequency's matrix contiguous), not in the
    # frequency-fastest order the einsum leaves
    return np.ascontiguousarray(Y)


def case_text(files: tuple[str, str], w: np.ndarray, n: int, m: int) -> str:
    lab = labels(n)
    pts = ", ".join(f"{p}@{x}" for p in "AB" for x in lab)
    conns = ", ".join(f"[A@{x}, B@{x}]" for x in lab[:m])
    return (f"name: frf_parts\nsubstructures:\n"
            f"  - {{name: A, type: frf, file: {files[0]}}}\n"
            f"  - {{name: B, type: frf, file: {files[1]}}}\n"
            f"connections: [{conns}]\n"
            f"analysis:\n  frf:\n    omega: {{start: {float(w[0])!r}, "
            f"stop: {float(w[-1])!r}, num: {len(w)}}}\n"
            f"    inputs: [{pts}]\n    outputs: [{pts}]\n"
            f"output: {{pictures: false}}\n")


def couple_library(Ya: np.ndarray, Yb: np.ndarray, w: np.ndarray, m: int):
    """(s): ``couple_selected`` of the two parts joined at their first ``m`` channels, every
    channel an output and an input; ``(omega, H, agreement)``."""
    from substruct.analysis.frf.coupling import FrfPart
    from substruct.analysis.frf.coupling_selected import couple_selected

    lab = labels(Ya.shape[1])
    parts = [FrfPart("A", w, lab, Ya), FrfPart("B", w, lab, Yb)]
    every = [f"{p}@{x}" for p in "AB" for x in lab]
    got = couple_selected(parts, [(f"A@{x}", f"B@{x}") for x in lab[:m]], every, every)
    return got.omega, got.H, got.agreement


def alternated(runs: dict, repeat: int) -> dict:
    """``repeat`` calls of each of ``runs`` (name: callable), alternated: the order of the
    names, then reversed, and so on, after one untimed call of each (so that the first timed
    call of the second name does not alone find the first's answer still held).  Per name:
    the median wall and CPU seconds, every CPU time, the last answer, and every call's system
    time (the kernel's share of the CPU: most of it is the first touch of the new answer's
    pages)."""
    got: dict = {name: {"cpu": [], "wall": [], "sys": [], "out": None} for name in runs}
    names = list(runs)
    for name in names:  # one call of each first, untimed: each then holds one answer, and
        got[name]["out"] = runs[name]()  # a timed call frees it before making the next
    for r in range(repeat):
        for name in names if r % 2 == 0 else names[::-1]:
            got[name]["out"] = None  # the previous answer freed before the next call
            t0, c0 = time.perf_counter(), time.process_time()
            s0 = resource.getrusage(resource.RUSAGE_SELF).ru_stime
            got[name]["out"] = runs[name]()
            got[name]["cpu"].append(time.process_time() - c0)
            got[name]["sys"].append(resource.getrusage(resource.RUSAGE_SELF).ru_stime - s0)
            got[name]["wall"].append(time.perf_counter() - t0)
    return {name: (statistics.median(g["wall"]), statistics.median(g["cpu"]), g["cpu"],
                   g["out"], g["sys"]) for name, g in got.items()}


def worker_library(files: list[str], m: int, dst: str) -> None:
    """(f), inside the fresh process: read the files, couple, save."""
    c0, t0 = time.process_time(), time.perf_counter()
    parts = []
    for f in files:
        with np.load(f) as z:
            parts.append((z["H"], z["omega"]))
    w, Yc, agreement = couple_library(parts[0][0], parts[1][0], parts[0][1], m)
    np.savez(dst, H=Yc, times=json.dumps({"cpu": time.process_time() - c0,
                                          "wall": time.perf_counter() - t0,
                                          "agreement": agreement}))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--channels", type=int, default=100, help="channels of each part")
    ap.add_argument("--interface", type=int, default=12, help="channels joined")
    ap.add_argument("--modes", type=int, default=40, help="modes of each part's modal sum")
    ap.add_argument("--frequencies", type=int, default=1000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--pyfbs", help="the Python of an environment with pyFBS")
    ap.add_argument("--no-command", action="store_true", help="leave out (r)")
    ap.add_argument("--worker-library", nargs=3, help=argparse.SUPPRESS)
    args = ap.parse_args()
    m, n = args.interface, args.channels
    if args.worker_library:
        worker_library(args.worker_library[:2], m, args.worker_library[2])
        return
    import scipy

    w = 2 * np.pi * np.linspace(F_LO, F_HI, args.frequencies)
    Ya, Yb = synthesise(n, args.modes, w, 1), synthesise(n, args.modes, w, 2)
    B = np.zeros((m, 2 * n))
    B[np.arange(m), np.arange(m)] = 1.0
    B[np.arange(m), n + np.arange(m)] = -1.0
    every = np.arange(2 * n)
    print(f"# {platform.processor() or platform.machine()}, Python {platform.python_version()},"
          f" NumPy {np.__version__}, SciPy {scipy.__version__}, OMP_NUM_THREADS="
          f"{os.environ.get('OMP_NUM_THREADS', 'unset')}")
    print(f"# two type: frf parts of {n} channels ({args.modes} modes + residual each), {m} "
          f"joined, {len(w)} frequencies {F_LO:g}-{F_HI:g} Hz, all {2 * n} x {2 * n} coupled "
          f"receptances")
    rows: list[tuple[str, float, float, str, float]] = []
    couple_library(Ya[:2], Yb[:2], w[:2], m)  # warm: the imports and first calls
    lean_lmfbs([Ya[:2], Yb[:2]], B, every, every)
    got = alternated({"l": lambda: lean_lmfbs([Ya, Yb], B, every, every),
                      "s": lambda: couple_library(Ya, Yb, w, m)}, args.repeat)
    Hl = got["l"][3]
    scale = float(np.abs(Hl).max())

    def diff(H: np.ndarray) -> float:
        return float(max(np.abs(H[k] - Hl[k]).max() for k in range(len(w)))) / scale

    rows.append(("l lean NumPy LM-FBS, warm", got["l"][1], got["l"][0], str(args.repeat), 0.0))
    _, Hs, agreement = got["s"][3]
    rows.append(("s substruct couple_selected (lm-fbs, checks), warm", got["s"][1],
                 got["s"][0], str(args.repeat), diff(Hs)))
    each = ", ".join(f"{a:.2f}/{b:.2f}" for a, b in zip(got["l"][2], got["s"][2]))
    system = ", ".join(f"{a:.2f}/{b:.2f}" for a, b in zip(got["l"][4], got["s"][4]))
    ratios = [a / b for a, b in zip(got["l"][2], got["s"][2])]
    note = (f"# (s) generalized-inverse check (32 frequencies) {agreement:.1e}\n"
            f"# alternated calls, CPU s of (l)/(s) a pair: {each}; (l)/(s) "
            f"{min(ratios):.2f}x to {max(ratios):.2f}x\n# of which system time (page faults), "
            f"(l)/(s) a pair: {system}")
    del Hs, got
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        env = dict(os.environ, PYTHONPATH=str(ROOT))
        files = []
        for name, Y in (("a", Ya), ("b", Yb)):
            path = work / f"part_{name}.npz"
            np.savez(path, H=Y, labels=np.array(labels(n)), omega=w)
            files.append(str(path))
        out = work / "lib.npz"
        proc = child([sys.executable, __file__, "--interface", str(m), "--worker-library",
                      *files, str(out)], env=env)
        with np.load(out) as z:
            rows.append(("f substruct couple, fresh process (reads the .npz)", proc["cpu"],
                         proc["wall"], "1", diff(z["H"])))
        if not args.no_command:
            import h5py

            case = work / "parts.yaml"
            case.write_text(case_text(("part_a.npz", "part_b.npz"), w, n, m))
            proc = child([sys.executable, "-m", "substruct.cli", "run", str(case), "--out",
                          str(work / "out"), "--force", "--quiet", "--no-pictures"], env=env)
            with h5py.File(next((work / "out").glob("*.h5")), "r") as h5:
                rows.append(("r substruct run parts.yaml, fresh process", proc["cpu"],
                             proc["wall"], "1", diff(h5["frf/H"][...])))
        p = run_pyfbs(args.pyfbs, [Ya, Yb], B, every, every, work)
    if "error" in p:
        rows.append((f"p pyFBS: {p['error']}", float("nan"), float("nan"), "0", float("nan")))
    else:
        rows.append((f"p pyFBS {p['version']} coupling step, warm", p["cpu"], p["wall"], "1",
                     diff(p["H"])))
        rows.append(("p  pyFBS, fresh process", p["process_cpu"], p["process_wall"], "1",
                     diff(p["H"])))
        note += f"\n# (p) interface inverse by {p['how']}"
    report(rows, note)


def report(rows, note: str) -> None:
    get = {r[0][:2].strip(): r for r in rows if r[0][1] == " "}
    s, f = get["s"][1], get["f"][1]
    print(f"{'route':62s} {'CPU s':>9s} {'wall s':>9s} {'runs':>4s} {'vs (l)':>8s} "
          f"{'CPU / (s)':>9s}")
    for name, cpu, wall, runs, d in rows:
        print(f"{name:62s} {cpu:9.2f} {wall:9.2f} {runs:>4s} {d:8.1e} {cpu / s:9.2f}")
    print(note)
    lean = get["l"][1]
    print(f"# target (c): substruct ahead of the lean NumPy LM-FBS: warm {lean / s:.2f}x -> "
          f"{'holds' if lean > s else 'does not hold'}")
    p = [r for r in rows if r[0].startswith("p pyFBS") and "coupling" in r[0]]
    if p:
        proc = next(r for r in rows if r[0].startswith("p  pyFBS, fresh"))
        print(f"# target (c): substruct ahead of pyFBS's coupling step: warm {p[0][1] / s:.2f}x,"
              f" fresh process {proc[1] / f:.2f}x -> "
              f"{'holds' if p[0][1] > s and proc[1] > f else 'does not hold'}")
    else:
        print("# target (c) against pyFBS: not measured, pyFBS not importable")


if __name__ == "__main__":
    main()
