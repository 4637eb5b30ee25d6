"""Craig-Bampton assembly with interface reduction against the monolithic solve.

A 3D elastic box (unit square section of ``N x N`` cubic hexahedra, clamped at ``x = 0``) is cut
along its length into parts; each part is meshed, reduced (``g`` fixed-interface modes,
polynomial interface bases of degree ``p``) and released on its own, and the parts are coupled
by shared interface coordinates (substruct.models.interface_box, interface_reduction, and the
reference coupling of the tests, tests/reference_reduced_coupling.py).  Rows:

* the error table: the lowest 20 frequencies of the reduced assembly against the monolithic
  shift-invert Lanczos of the same mesh (same factorization), for several ``(g, p)``; the parts
  are reduced once at the largest ``(g, p)`` and truncated to the others (exactly the
  reduction with fewer modes and a lower degree, tested);
* the large run: the assembly only (the monolithic solve does not fit), with the mode shapes
  recovered part by part.

Every run is a fresh process, so its peak resident memory (``ru_maxrss``) is its own.

    python benchmarks/cb_assembly.py --quick          # about a minute
    python benchmarks/cb_assembly.py                  # 300k error table, 1M assembly
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import resource
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
from reference_reduced_coupling import couple_reduced, reduced_modes  # noqa: E402
from substruct.linalg.factorize import factorizer, has_cholmod
from substruct.linalg.lanczos import rayleigh_ritz, shift_invert_lanczos
from substruct.models.interface_box import BoxCut, reduce_box_part
from substruct.models.interface_reduction import truncate_part

N_MODES = 20


def box(section: int, dof: int, parts: int) -> BoxCut:
    """The box of at least ``dof`` free coordinates, cubic elements, cut into ``parts``."""
    nx = int(np.ceil(dof / (3 * (section + 1) ** 2)))
    return BoxCut((nx / section, 1.0, 1.0), (nx, section, section), parts)


def peak_gb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20


def monolithic(cut: BoxCut, factorization: str) -> dict[str, Any]:
    t0 = time.perf_counter()
    whole = cut.whole()
    solve = factorizer(factorization)(whole.K)
    v0 = np.random.default_rng(0).standard_normal(whole.n_dof)
    _, vecs = shift_invert_lanczos(whole.K, whole.M, N_MODES, 0.0, solve, v0)
    lam, _ = rayleigh_ritz(whole.K, whole.M, vecs)
    return {"dof": whole.n_dof, "seconds": time.perf_counter() - t0, "peak": peak_gb(),
            "omega": np.sqrt(lam[:N_MODES])}


def assembly(cut: BoxCut, pairs: list[tuple[int, int]], factorization: str,
             recover: bool) -> dict[str, Any]:
    t0 = time.perf_counter()
    g, p = max(q[0] for q in pairs), max(q[1] for q in pairs)
    parts, part_dof, part_seconds = [], [], []
    for k in range(cut.n_parts):
        tk = time.perf_counter()
        parts.append(reduce_box_part(cut, k, g, p, factorization=factorization,
                                     keep_basis=recover))
        part_dof.append(parts[-1].n_dof)
        part_seconds.append(time.perf_counter() - tk)
    reduced = time.perf_counter() - t0
    out: dict[str, Any] = {"dof": cut.n_dof(), "parts": cut.n_parts, "largest": max(part_dof),
                           "part_seconds": float(np.median(part_seconds)),
                           "reduce_seconds": reduced, "pairs": {}}
    for gq, pq in pairs:
        tq = time.perf_counter()
        small = [truncate_part(part, gq, pq) if (gq, pq) != (g, p) else part
                 for part in parts]
        asm = couple_reduced(small)
        omega, X = reduced_modes(asm, N_MODES)
        out["pairs"][gq, pq] = {"omega": omega, "size": asm.K.shape[0],
                                "seconds": time.perf_counter() - tq}
        if (gq, pq) == (g, p) and recover:
            tr = time.perf_counter()
            shapes = [part.recover(asm.part_coordinates(k, X)) for k, part in enumerate(parts)]
            out["recover_seconds"] = time.perf_counter() - tr
            out["recovered"] = sum(s.shape[0] for s in shapes)
            del shapes
    out["seconds"] = time.perf_counter() - t0
    out["peak"] = peak_gb()
    return out


def in_child(fn: Any, *args: Any) -> Any:
    with mp.get_context("spawn").Pool(1, maxtasksperchild=1) as pool:
        return pool.apply(fn, args)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="small sizes (about a minute)")
    ap.add_argument("--section", type=int, default=10, help="elements across the section")
    ap.add_argument("--error-dof", type=int, default=300_000)
    ap.add_argument("--error-parts", type=int, default=8)
    ap.add_argument("--big-dof", type=int, default=1_000_000)
    ap.add_argument("--big-parts", type=int, default=16)
    ap.add_argument("--pairs", default="10:1,10:2,20:1,20:2,20:4,40:4",
                    help="(g, p) pairs of the error table, g:p,...")
    ap.add_argument("--big", default="20:4", help="(g, p) of the large run")
    ap.add_argument("--factorization", default="auto")
    ap.add_argument("--skip", choices=["error", "big"], action="append", default=[])
    a = ap.parse_args()
    if a.quick:
        a.section, a.error_dof, a.big_dof, a.error_parts, a.big_parts = 4, 6000, 30000, 4, 8
        a.pairs, a.big = "5:1,10:1,10:2,20:2,20:4", "10:2"
    pairs = [(int(s.split(":")[0]), int(s.split(":")[1])) for s in a.pairs.split(",")]
    big = (int(a.big.split(":")[0]), int(a.big.split(":")[1]))
    fact = a.factorization
    print(f"factorization {fact!r} (CHOLMOD importable: {has_cholmod()}); section "
          f"{a.section} x {a.section} hexahedra; {N_MODES} lowest modes")
    if "error" not in a.skip:
        cut = box(a.section, a.error_dof, a.error_parts)
        mono = in_child(monolithic, cut, fact)
        red = in_child(assembly, cut, pairs, fact, False)
        print(f"\n(i) error against the monolithic solve, {mono['dof']:,} DOF, box "
              f"{cut.lengths[0]:g} x 1 x 1, {cut.n_parts} parts (largest {red['largest']:,} "
              "DOF)")
        print(f"monolithic: {mono['seconds']:.1f} s, peak {mono['peak']:.2f} GB; parts "
              f"reduced once at the largest (g, p): {red['reduce_seconds']:.1f} s (median "
              f"{red['part_seconds']:.1f} s a part), peak {red['peak']:.2f} GB "
              f"(x{red['peak'] / mono['peak']:.2f} of monolithic)")
        print(f"{'g':>4} {'p':>3} {'coords':>7} {'max rel err':>12} {'min rel err':>12} "
              f"{'couple+solve s':>15}")
        for (g, p), row in red["pairs"].items():
            err = (row["omega"] - mono["omega"]) / mono["omega"]
            print(f"{g:>4} {p:>3} {row['size']:>7} {err.max():>12.2e} {err.min():>12.2e} "
                  f"{row['seconds']:>15.2f}")
        print(f"lowest monolithic frequencies (Hz): "
              f"{np.array2string(mono['omega'][:6] / (2 * np.pi), precision=2)}")
    if "big" not in a.skip:
        cut = box(a.section, a.big_dof, a.big_parts)
        red = in_child(assembly, cut, [big], fact, True)
        row = red["pairs"][big]
        print(f"\n(ii) assembly of {red['dof']:,} DOF, box {cut.lengths[0]:g} x 1 x 1, "
              f"{red['parts']} parts (largest {red['largest']:,} DOF), g = {big[0]}, "
              f"p = {big[1]}, {row['size']} coupled coordinates")
        print(f"time {red['seconds']:.1f} s (reduce {red['reduce_seconds']:.1f} s, median "
              f"{red['part_seconds']:.1f} s a part; couple+solve {row['seconds']:.2f} s; "
              f"recover {red['recover_seconds']:.1f} s, {red['recovered']:,} DOF x "
              f"{N_MODES}); peak {red['peak']:.2f} GB")
        print(f"lowest frequencies (Hz): "
              f"{np.array2string(row['omega'][:10] / (2 * np.pi), precision=3)}")


if __name__ == "__main__":
    main()
