"""Receptances of a 3D assembly of two solid parts: substruct against the direct sparse route,
pyFBS's LM-FBS and a lean NumPy LM-FBS given the parts' receptances.

    OMP_NUM_THREADS=1 python benchmarks/fbs_assembly.py [--dof 20000] [--points 50]
        [--frequencies 1000] [--direct-frequencies 3] [--cutoff 3] [--repeat 3]
        [--pyfbs PYTHON] [--no-command]

The model: two steel bars of Q1 hexahedra (section 0.1 x 0.08 m, 6 x 6 elements), each about
``--dof`` coordinates, end to end, tied node to node at the joint (147 tie rows), the first
clamped at ``x = 0``, the second at its far end; Rayleigh damping ``C = alpha M + beta K``
(about 1 % at 20 and 150 Hz).  ``--points`` points a part on two edges (``z`` on one, ``y``
on the other) are both the outputs and the inputs: 100 x 100 receptances by default, at
``--frequencies`` frequencies from 5 to 150 Hz (the first six or so coupled modes).

Routes, in one process unless said:

(d) direct: the assembled constrained system on its master-slave basis, ``T^T Z(w) T``, one
    ``scipy.sparse.linalg.splu`` a frequency (``MMD_AT_PLUS_A`` ordering), solved for the
    inputs, ``H = O T X``; on ``--direct-frequencies`` frequencies spread over the grid, the
    time scaled to the whole grid (its cost is the same at every frequency), and the
    reference of every difference printed;
(s) substruct, library: ``receptance_sweep(..., method="modal")`` of the assembly (the coupled
    modes up to ``--cutoff`` x the highest frequency, the second-order residual, its own
    direct check at three frequencies), warm (median of ``--repeat``);
(f) the same, as a fresh process: imports, Numba, the meshing of the parts, the assembly and
    the sweep;
(r) ``substruct run bars.yaml --quiet --no-pictures`` of the equivalent case file (two
    ``type: solid`` boxes, the interface, ``analysis.frf`` with ``method: modal``), a fresh
    process;
(u) the parts' receptances on their channels (the part's points and its interface
    coordinates), each part's modal sweep (``receptance_sweep`` of the part alone, the same
    options), computed once: the input of the LM-FBS routes, its time counted apart;
(p) pyFBS's LM-FBS (``fbs_common.pyfbs_coupling``) on (u), run by the pyFBS environment's
    Python (``--pyfbs``; pyFBS is not a dependency) in a subprocess on the data saved to a
    temporary ``.npz``: the coupling timed inside that process after a warm-up, and the whole
    process; without ``--pyfbs`` (or without pyFBS there) the row says "pyFBS not importable";
(l) lean NumPy LM-FBS (``fbs_common.lean_lmfbs``) on (u), warm.

Times are CPU seconds (user + system; of the child for a fresh process), which the shared
machine disturbs less than the wall clock (printed too).  Differences are
``max |H - H_d| / max |H_d|`` at the directly solved frequencies.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
from fbs_common import child, lean_lmfbs, run_pyfbs, timed  # noqa: E402

E_MOD, NU, RHO = 2.1e11, 0.3, 7850.0
LX, LY, LZ, SECTION = 2.25, 0.1, 0.08, 6
F_LO, F_HI = 5.0, 150.0
W1, W2 = 2 * np.pi * 20.0, 2 * np.pi * 150.0
TOLERANCE = 1e-3  # the modal sum's check against the direct solve (error ~ (1/cutoff)^3)
ALPHA, BETA = 2 * 0.01 * W1 * W2 / (W1 + W2), 2 * 0.01 / (W1 + W2)


def elements(dof: int) -> int:
    """Elements along a bar for about ``dof`` free coordinates (one end face held)."""
    return max(4, round(dof / (3 * (SECTION + 1) ** 2)))


def points(nx: int, per_part: int) -> list[tuple[str, tuple[float, float, float], str]]:
    """``(part, xyz, component)`` of the outputs (= inputs): nodes on two edges of each bar,
    off the clamped faces and the joint."""
    L = LX
    dx = L / nx
    idx = np.unique(np.linspace(1, nx - 1, max(1, per_part // 2)).round().astype(int))
    out = []
    for part, x0 in (("A", 0.0), ("B", L)):
        for i in idx:
            out.append((part, (x0 + i * dx, LY, LZ), "z"))
        for i in idx:
            out.append((part, (x0 + i * dx, 0.0, LZ), "y"))
    return out


def build(nx: int, per_part: int):
    """The two bars, their assembly, and the point references."""
    from substruct.assembly.interfaces import tie_nodes
    from substruct.assembly.stack import PointRef, assemble
    from substruct.models.solid import BoxGrid, solid_box

    L = LX
    damping = {"rayleigh": [ALPHA, BETA]}
    a = solid_box("A", BoxGrid((L, LY, LZ), (nx, SECTION, SECTION)), E_MOD, NU, RHO,
                  fixed=[{"box": [[0, 0, 0], [0, LY, LZ]]}], damping=damping)
    b = solid_box("B", BoxGrid((L, LY, LZ), (nx, SECTION, SECTION), origin=(L, 0, 0)), E_MOD,
                  NU, RHO, fixed=[{"box": [[2 * L, 0, 0], [2 * L, LY, LZ]]}], damping=damping)
    asm = assemble([a, b], tie_nodes(a, b, {"box": [[L, 0, 0], [L, LY, LZ]]}), [])
    refs = [PointRef(p, {"at": list(x), "component": c}) for p, x, c in points(nx, per_part)]
    return asm, refs


def omegas(count: int) -> np.ndarray:
    return 2 * np.pi * np.linspace(F_LO, F_HI, count)


def library(nx: int, per_part: int, w: np.ndarray, cutoff: float):
    """(s): the modal sweep of the assembly through the library."""
    import scipy.sparse as sp

    from substruct.analysis.api import receptance_sweep
    from substruct.analysis.frf.modal import ModalOptions

    asm, refs = build(nx, per_part)
    O = asm.rows(refs)
    return receptance_sweep(asm.K, asm.M, asm.C, asm.A, w, sp.csc_array(O.T), O,
                            method="modal", modal=ModalOptions(cutoff=cutoff),
                            tolerance=TOLERANCE)


def direct(asm, O, w: np.ndarray) -> np.ndarray:
    """(d): ``splu`` of ``T^T Z T`` a frequency, ``H = O T Z_T^-1 T^T O^T``."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    from substruct.linalg.nullspace import master_slave

    T = sp.csc_array(master_slave(asm.A).T)
    Kt, Mt, Ct = (sp.csc_array(T.T @ X @ T) for X in (asm.K, asm.M, asm.C))
    OT = (O @ T).toarray()
    H = np.empty((len(w), O.shape[0], O.shape[0]), dtype=complex)
    for k, wk in enumerate(w):
        lu = spla.splu(sp.csc_array(Kt - wk**2 * Mt + 1j * wk * Ct), permc_spec="MMD_AT_PLUS_A")
        H[k] = OT @ lu.solve(np.ascontiguousarray(OT.T, dtype=complex))
    return H


def part_receptances(asm, refs, w: np.ndarray, cutoff: float):
    """(u): each part's modal receptance on its channels (its points, then its interface
    coordinates), the signed Boolean ``B`` of the ties on the stacked channels, and the
    stacked indices of the points."""
    import scipy.sparse as sp

    from substruct.analysis.api import receptance_sweep
    from substruct.analysis.frf.modal import ModalOptions

    A = sp.coo_array(asm.A)
    O = sp.csr_array(asm.rows(refs))
    point_dof = O.indices[np.argsort(np.repeat(np.arange(O.shape[0]), np.diff(O.indptr)),
                                     kind="stable")]
    starts = list(asm.offsets) + [asm.n_dof]
    blocks, channels, base = [], [], 0
    for p, sub in enumerate(asm.substructures):
        lo, hi = starts[p], starts[p + 1]
        mine = [d for d in point_dof if lo <= d < hi]
        iface = sorted({int(c) for c in A.col if lo <= c < hi})
        chans = np.array(mine + iface) - lo
        P = sp.csr_array((np.ones(len(chans)), (np.arange(len(chans)), chans)),
                         shape=(len(chans), sub.n_dof))
        res = receptance_sweep(sub.K, sub.M, sub.C, sp.csr_array((0, sub.n_dof)), w,
                               sp.csc_array(P.T), P, method="modal",
                               modal=ModalOptions(cutoff=cutoff), tolerance=TOLERANCE)
        blocks.append(res.H)
        channels.append({int(c) + lo: base + j for j, c in enumerate(chans)})
        base += len(chans)
    where = {g: s for ch in channels for g, s in ch.items()}
    B = np.zeros((A.shape[0], base))
    for r, c, v in zip(A.row, A.col, A.data):
        B[r, where[int(c)]] += v
    stacked = np.array([where[int(d)] for d in point_dof])
    return blocks, B, stacked


def case_text(nx: int, per_part: int, frequencies: int, cutoff: float) -> str:
    L = LX
    pts = ", ".join(f'"{p}@{x[0]:.12g},{x[1]:.12g},{x[2]:.12g}:{c}"'
                    for p, x, c in points(nx, per_part))
    bars = ""
    for name, origin, end in (("A", 0.0, 0.0), ("B", L, 2 * L)):
        bars += (f"  - name: {name}\n    type: solid\n    box: {{lengths: [{L!r}, {LY}, {LZ}], "
                 f"divisions: [{nx}, {SECTION}, {SECTION}], origin: [{origin!r}, 0, 0]}}\n"
                 f"    E: {E_MOD}\n    nu: {NU}\n    rho: {RHO}\n"
                 f"    fixed: [{{box: [[{end!r}, 0, 0], [{end!r}, {LY}, {LZ}]]}}]\n"
                 f"    damping: {{rayleigh: [{ALPHA!r}, {BETA!r}]}}\n")
    return (f"name: bars\nsubstructures:\n{bars}"
            f"interfaces:\n  - {{name: joint, between: [A, B], nodes: {{box: [[{L!r}, 0, 0], "
            f"[{L!r}, {LY}, {LZ}]]}}}}\n"
            f"analysis:\n  frf:\n    omega: {{start: {F_LO}, stop: {F_HI}, num: {frequencies}}}\n"
            f"    units: Hz\n    method: modal\n    modal: {{cutoff: {cutoff}}}\n"
            f"    tolerance: {TOLERANCE}\n"
            f"    inputs: [{pts}]\n    outputs: [{pts}]\n"
            f"output: {{pictures: false}}\n")


def worker_library(args, dst: str) -> None:
    """(f), inside the fresh process: build and sweep; the receptances to ``dst``."""
    c0, t0 = time.process_time(), time.perf_counter()
    res = library(elements(args.dof), args.points, omegas(args.frequencies), args.cutoff)
    np.savez(dst, H=res.H, times=json.dumps({"cpu": time.process_time() - c0,
                                             "wall": time.perf_counter() - t0}))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dof", type=int, default=20000, help="coordinates of each part")
    ap.add_argument("--points", type=int, default=50, help="outputs (= inputs) of each part")
    ap.add_argument("--frequencies", type=int, default=1000)
    ap.add_argument("--direct-frequencies", type=int, default=3)
    ap.add_argument("--cutoff", type=float, default=3.0)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--pyfbs", help="the Python of an environment with pyFBS")
    ap.add_argument("--no-command", action="store_true", help="leave out (r)")
    ap.add_argument("--worker-library", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker_library:
        worker_library(args, args.worker_library)
        return
    import scipy

    import substruct.analysis.api  # noqa: F401  (warm: (s) times the call, not the imports)
    import substruct.analysis.frf.modal  # noqa: F401

    nx = elements(args.dof)
    w = omegas(args.frequencies)
    pick = np.unique(np.linspace(0, len(w) - 1, args.direct_frequencies).round().astype(int))
    asm, refs = build(nx, args.points)
    O = asm.rows(refs)
    print(f"# {platform.processor() or platform.machine()}, Python {platform.python_version()},"
          f" NumPy {np.__version__}, SciPy {scipy.__version__}, OMP_NUM_THREADS="
          f"{os.environ.get('OMP_NUM_THREADS', 'unset')}")
    print(f"# two bars of {asm.substructures[0].n_dof} + {asm.substructures[1].n_dof} "
          f"coordinates, {asm.A.shape[0]} tie rows, {O.shape[0]} outputs x {O.shape[0]} inputs, "
          f"{len(w)} frequencies {F_LO:g}-{F_HI:g} Hz, modes up to {args.cutoff:g} x {F_HI:g} Hz")
    rows: list[tuple[str, float, float, str, float]] = []  # name, CPU, wall, runs, diff
    t, cpu, _, Hd = timed(lambda: direct(asm, O, w[pick]), 1)
    scale = float(np.abs(Hd).max())

    def diff(H: np.ndarray) -> float:
        return float(np.abs(H[pick] - Hd).max()) / scale

    f = len(w) / len(pick)
    rows.append((f"d direct splu, {len(pick)} of {len(w)} frequencies x {f:.0f} (scaled)",
                 cpu * f, t * f, "1", 0.0))
    t, cpu, n, res = timed(lambda: library(nx, args.points, w, args.cutoff), args.repeat)
    Hs = res.H
    rows.append(("s substruct receptance_sweep modal, warm", cpu, t, str(n), diff(Hs)))
    note = f"# (s) {res.method}; checks {res.agreement}"
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        env = dict(os.environ, PYTHONPATH=str(ROOT))
        out = work / "lib.npz"
        proc = child([sys.executable, __file__, "--worker-library", str(out), "--dof",
                      str(args.dof), "--points", str(args.points), "--frequencies",
                      str(args.frequencies), "--cutoff", str(args.cutoff)], env=env)
        with np.load(out) as z:
            same = float(np.abs(z["H"] - Hs).max()) / scale
        rows.append(("f substruct library, fresh process", proc["cpu"], proc["wall"], "1",
                     diff(Hs)))
        note += f"\n# (f) against (s): {same:.1e}"
        if not args.no_command:
            import h5py

            case = work / "bars.yaml"
            case.write_text(case_text(nx, args.points, args.frequencies, args.cutoff))
            proc = child([sys.executable, "-m", "substruct.cli", "run", str(case), "--out",
                          str(work / "out"), "--force", "--quiet", "--no-pictures"], env=env)
            with h5py.File(next((work / "out").glob("*.h5")), "r") as h5:
                Hr = h5["frf/H"][...]
            rows.append(("r substruct run bars.yaml, fresh process", proc["cpu"], proc["wall"],
                         "1", diff(Hr)))
            note += f"; (r) against (s): {float(np.abs(Hr - Hs).max()) / scale:.1e}"
            del Hr
        del Hs, res
        t, cpu, _, (blocks, B, stacked) = timed(
            lambda: part_receptances(asm, refs, w, args.cutoff), 1)
        rows.append((f"u parts' receptances ({' + '.join(str(b.shape[1]) for b in blocks)} "
                     f"channels), once", cpu, t, "1", float("nan")))
        cpu_u, wall_u = cpu, t
        p = run_pyfbs(args.pyfbs, blocks, B, stacked, stacked, work)
    if "error" in p:
        rows.append((f"p pyFBS LM-FBS: {p['error']}", float("nan"), float("nan"), "0",
                     float("nan")))
    else:
        rows.append((f"p pyFBS {p['version']} coupling step, warm", p["cpu"], p["wall"], "1",
                     diff(p["H"])))
        rows.append(("p  pyFBS, fresh process", p["process_cpu"], p["process_wall"], "1",
                     diff(p["H"])))
        rows.append(("p  pyFBS route: u + fresh process", cpu_u + p["process_cpu"],
                     wall_u + p["process_wall"], "1", diff(p["H"])))
        note += f"\n# (p) interface inverse by {p['how']}"
    t, cpu, n, Hl = timed(lambda: lean_lmfbs(blocks, B, stacked, stacked), args.repeat)
    rows.append(("l lean NumPy LM-FBS, warm", cpu, t, str(n), diff(Hl)))
    rows.append(("l  lean route: u + l", cpu_u + cpu, wall_u + t, str(n), diff(Hl)))
    report(rows, note)


def report(rows, note: str) -> None:
    base = {r[0][:2].strip(): r for r in rows if r[0][1] == " "}
    s_cpu, f_cpu = base["s"][1], base["f"][1]
    print(f"{'route':60s} {'CPU s':>9s} {'wall s':>9s} {'runs':>4s} {'vs (d)':>8s} "
          f"{'CPU / (s)':>9s}")
    for name, cpu, wall, runs, d in rows:
        print(f"{name:60s} {cpu:9.2f} {wall:9.2f} {runs:>4s} {d:8.1e} {cpu / s_cpu:9.2f}")
    print(note)
    found = {r[0]: r for r in rows}
    lean = next(r for r in rows if r[0].startswith("l lean"))
    lean_route = next(r for r in rows if r[0].startswith("l  lean route"))
    print(f"# target (b): substruct ahead of the lean NumPy LM-FBS: warm {lean[1] / s_cpu:.2f}x "
          f"(coupling step alone), {lean_route[1] / s_cpu:.2f}x (with the parts' receptances), "
          f"fresh process {lean_route[1] / f_cpu:.2f}x -> "
          f"{'holds' if lean[1] > s_cpu else 'does not hold'}")
    pyf = [r for n, r in found.items() if n.startswith("p pyFBS") and "coupling" in n]
    if pyf:
        proc = next(r for r in rows if r[0].startswith("p  pyFBS, fresh"))
        route = next(r for r in rows if r[0].startswith("p  pyFBS route"))
        print(f"# target (b): substruct ahead of pyFBS: warm {pyf[0][1] / s_cpu:.2f}x (coupling "
              f"step alone), {route[1] / s_cpu:.2f}x (route), fresh process "
              f"{proc[1] / f_cpu:.2f}x (coupling process alone), {route[1] / f_cpu:.2f}x "
              f"(route) -> {'holds' if pyf[0][1] > s_cpu and proc[1] > f_cpu else 'does not hold'}")
    else:
        print("# target (b) against pyFBS: not measured, pyFBS not importable")


if __name__ == "__main__":
    main()
