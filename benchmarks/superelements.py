"""Reading and coupling many Craig-Bampton superelements delivered as OP4 files.

``count`` synthetic superelements, each of ``boundary`` boundary coordinates (grids with six
components) and ``modal`` fixed-interface modes, are written as binary OP4 files (``MAA``
dense where a Craig-Bampton mass is, ``KAA`` as sparse strings, the DOF map ``DOFS``) in a
temporary folder with a case that chains them: the last 41 grids of each are tied to the
first 41 of the next, and the first superelement is clamped there.  The matrices are those
of a Craig-Bampton model: ``K = diag(Omega^2, K_bb)`` with ``K_bb`` a chain of springs along
the boundary coordinates, ``M = [[I, M_qb], [M_bq, M_bb]]`` with a dense, small coupling.

Each phase runs in a fresh process so that its peak resident memory (``ru_maxrss``) is its own:

* ``read``: :func:`substruct.load_case` (every OP4 file read and checked: sizes before
  allocating, symmetry, positive semidefiniteness by a dense eigenvalue solve of each 700 x 700
  matrix, the DOF map);
* ``couple``: the above, the superelements built and
  :func:`substruct.assembly.stack.assemble` (the stacked sparse matrices and the constraint
  rows of every tie; the 12 000 ties are made in the script, as a case file holds 200 kB);
* ``modes`` (``--modes``): the above and the 10 lowest coupled modes (sparse solver; the
  parts share their fixed-interface frequencies, so the lowest modes are a cluster of one per
  part, which the Lanczos solver resolves with a larger basis after its first attempt).

    python benchmarks/superelements.py --quick     # 5 superelements, seconds
    python benchmarks/superelements.py             # 50 x (500 + 200)
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import resource
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sp

from substruct.io.op4 import write_op4

TIED = 41  # grids tied between neighbours (246 coordinates)


def grids(boundary: int) -> list[tuple[int, int]]:
    """``(grid, component)`` of the boundary: grids 1, 2, ... with six components each."""
    return [(1 + k // 6, 1 + k % 6) for k in range(boundary)]


def write_superelement(path: Path, boundary: int, modal: int, seed: int) -> None:
    """One synthetic Craig-Bampton model (module docstring) as a binary OP4 file."""
    rng = np.random.default_rng(seed)
    omega2 = (2 * np.pi * np.linspace(5.0, 400.0, modal)) ** 2
    chain = sp.diags([np.full(boundary - 1, -1.0), np.full(boundary, 2.0 + 1e-3),
                      np.full(boundary - 1, -1.0)], [-1, 0, 1]) * 1e6
    K = sp.block_diag([sp.diags(omega2), chain], format="csc")
    coupling = 0.3 * rng.standard_normal((modal, boundary)) / np.sqrt(modal * boundary)
    M = np.zeros((modal + boundary,) * 2)
    M[:modal, :modal] = np.eye(modal)
    M[modal:, modal:] = np.diag(rng.uniform(0.5, 1.5, boundary))
    M[:modal, modal:] = coupling
    M[modal:, :modal] = coupling.T
    dofs = np.array([(0, 0)] * modal + grids(boundary), dtype=float)
    write_op4(path, {"MAA": M, "KAA": K, "DOFS": dofs}, binary=True)


def write_case(folder: Path, count: int, boundary: int, modal: int) -> Path:
    """The OP4 files and the case listing them (the ties are made by :func:`ties`: 12 000 of
    them would not fit the 200 kB a case file may hold)."""
    lines = ["name: chain", "substructures:"]
    for i in range(count):
        write_superelement(folder / f"s{i}.op4", boundary, modal, i)
        lines.append(f"  - {{name: s{i}, type: superelement, file: s{i}.op4, M: MAA, K: KAA, "
                     "dofs: {key: DOFS}}")
    lines += ["analysis:", "  modes: {count: 10}"]
    (folder / "chain.yaml").write_text("\n".join(lines) + "\n")
    return folder / "chain.yaml"


def ties(count: int, boundary: int) -> tuple[list[Any], list[Any]]:
    """The connections (the last :data:`TIED` full grids of each superelement to the first of
    the next) and the clamp of the first superelement's first grids."""
    from substruct.assembly.stack import Connection, LinearConstraint, PointRef

    last = boundary // 6  # the last grid with all six components
    comps = ("ux", "uy", "uz", "rx", "ry", "rz")
    conn = [Connection(PointRef(f"s{i}", f"{last - TIED + 1 + j}:{c}"),
                       PointRef(f"s{i + 1}", f"{1 + j}:{c}"))
            for i in range(count - 1) for j in range(TIED) for c in comps]
    clamp = [LinearConstraint(((PointRef("s0", f"{1 + j}:{c}"), 1.0),), name=f"c{j}{c}")
             for j in range(TIED) for c in comps]
    return conn, clamp


def phase(args: tuple[str, str]) -> dict[str, Any]:
    """Run ``what`` on the case in this (fresh) process: times and peak memory."""
    what, case_path = args
    out: dict[str, Any] = {"phase": what}
    try:
        _phase(what, case_path, out)
    except Exception as err:  # noqa: BLE001 - reported in the table's process, not lost
        out["error"] = f"{type(err).__name__}: {err}"
    out["peak_gb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20
    return out


def _phase(what: str, case_path: str, out: dict[str, Any]) -> None:
    from substruct import load_case
    from substruct.analysis.api import modes
    from substruct.assembly.stack import assemble
    from substruct.builder.superelements import build_superelement

    t0 = time.perf_counter()
    case = load_case(case_path)
    out["read_s"] = time.perf_counter() - t0
    if what in ("couple", "modes"):
        t1 = time.perf_counter()
        subs = [build_superelement(case, i, spec) for i, spec in enumerate(case.substructures)]
        n_b = sum(1 for g, c in case.substructures[0].dof_table() if c)
        asm = assemble(subs, *ties(len(subs), n_b))
        out["couple_s"] = time.perf_counter() - t1
        out["n_dof"], out["constraints"] = asm.n_dof, asm.A.shape[0]
        out["nnz_M"], out["nnz_K"] = sp.csr_array(asm.M).nnz, sp.csr_array(asm.K).nnz
        if what == "modes":
            t2 = time.perf_counter()
            md = modes(asm.M, None, asm.K, asm.A, 10, what="benchmark")
            out["modes_s"] = time.perf_counter() - t2
            out["f1_hz"] = float(md.freq_hz[0])


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--quick", action="store_true", help="5 superelements")
    p.add_argument("--count", type=int, default=50)
    p.add_argument("--boundary", type=int, default=500)
    p.add_argument("--modal", type=int, default=200)
    p.add_argument("--modes", action="store_true", help="also the 10 lowest coupled modes")
    a = p.parse_args()
    count = 5 if a.quick else a.count
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        case = write_case(Path(tmp), count, a.boundary, a.modal)
        size = sum(f.stat().st_size for f in Path(tmp).glob("*.op4"))
        print(f"{count} superelements of {a.boundary} boundary + {a.modal} modal coordinates: "
              f"{size / 1e6:.1f} MB of binary OP4, written in "
              f"{time.perf_counter() - t0:.1f} s; {(count - 1) * TIED * 6} ties, "
              f"{TIED * 6} clamped")
        phases = ["read", "couple"] + (["modes"] if a.modes else [])
        ctx = mp.get_context("spawn")
        rows = []
        for what in phases:
            with ctx.Pool(1) as pool:
                rows.append(pool.map(phase, [(what, str(case))])[0])
    print(f"{'phase':<8s} {'read (s)':>9s} {'couple (s)':>10s} {'modes (s)':>9s} "
          f"{'peak (GB)':>9s} {'n_dof':>7s} {'rows of A':>9s} {'nnz M':>10s}")
    for r in rows:
        def cell(key: str, fmt: str, width: int) -> str:
            return format(r[key], fmt).rjust(width) if key in r else "-".rjust(width)

        print(f"{r['phase']:<8s} {cell('read_s', '.2f', 9)} {cell('couple_s', '.2f', 10)} "
              f"{cell('modes_s', '.2f', 9)} {cell('peak_gb', '.2f', 9)} "
              f"{cell('n_dof', 'd', 7)} {cell('constraints', 'd', 9)} {cell('nnz_M', 'd', 10)}")
    for r in rows:
        if "error" in r:
            print(f"{r['phase']}: {r['error']}")
    if any("f1_hz" in r for r in rows):
        print(f"first coupled frequency: {rows[-1]['f1_hz']:.4g} Hz")


if __name__ == "__main__":
    main()
