"""``substruct run`` on two big outputs streamed into the result file, against the library and
against the code before the streaming.

    OMP_NUM_THREADS=1 python benchmarks/run_streamed.py --before PATH [--repeat 1]
                                                        [--elements 50000] [--steps 2000]
                                                        [--frequencies 300] [--roots 40]

Two cases, each side a fresh process (imports counted), CPU time (user + system of the
process and the children it waited for) and peak resident set (the largest process, ``wait4``):

* transient: a fixed-free rod of ``--elements`` linear elements (as many coordinates) struck at
  its tip, ``--steps`` Newmark steps, the whole field stored at every step (``field_every:
  1``; 2,000 steps of 50,000 coordinates: 0.80 GB), the tip's history recorded, no check form;
* modal: the two tied 200-mass chains of ``benchmarks/frf_sweep.py``, all 400 x 400 receptances
  at ``--frequencies`` frequencies from 1 to 20 rad/s by modal superposition of ``--roots``
  roots (40: up to 30 rad/s) with the second-order residual (300 frequencies: 0.77 GB).  The
  truncation leaves the direct check above 1e-6: the case's ``tolerance`` is set to 1, as the
  accuracy is not measured here (the figure is printed).

(a) the library: a process that loads the case, builds the model, computes the analysis in
memory (``transient_result`` / ``frf_result`` of ``substruct.run``, timed) and writes the big
array with ``ndarray.tofile`` (timed: the time to write the output), with this checkout's code
(the reference) and with the code before;
(b) ``substruct run CASE --quiet --no-pictures`` with the code at ``--before`` (on
``PYTHONPATH``), then with this checkout's, in turn, ``--repeat`` times; medians.  Printed: (b)'s
CPU over (a)'s analysis + write (target 1.3), and its peak against the result file's size
(target: at most the size + 1 GB).  Each (b)'s big dataset is compared with (a)'s array, in a
process of its own: the code after gives it bit for bit (the code before summed the modes
in another order: equal to rounding only).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
from frf_sweep import N_CHAIN, case_text, chains  # noqa: E402
from fbs_common import child  # noqa: E402

ROD = """\
name: {name}
units: "N, m, kg, s"
substructures:
  - name: rod
    type: rod
    length: 1.0
    EA: 2.1e7
    m: 0.785
    support: fixed-free
    discretization: {{method: fe, elements: {elements}, order: 1}}
analysis:
  transient:
    t_end: {t_end}
    dt: 1.0e-6
    loads:
      - {{point: rod@1, amplitude: 500, shape: half-sine, duration: 2.0e-4}}
    outputs: [rod@1]
    field_every: 1
output: {{pictures: false}}
"""
DATASET = {"transient": "transient/snapshots", "modal": "frf/H"}


def write_cases(work: Path, opts: argparse.Namespace) -> dict[str, Path]:
    import scipy.io
    import scipy.sparse as sp

    rod = work / "rod_fields.yaml"
    rod.write_text(ROD.format(name="rod_fields", elements=opts.elements,
                              t_end=f"{opts.steps * 1e-6:.9g}"))
    K, M, C, _ = chains()
    files = {}
    for name, X in (("K", K), ("M", M), ("C", C)):
        path = work / f"chain_{name}.mtx"
        scipy.io.mmwrite(path, sp.coo_matrix(X[:N_CHAIN, :N_CHAIN]), symmetry="symmetric")
        files[name] = path.name
    text = case_text(N_CHAIN, np.linspace(1.0, 20.0, opts.frequencies), files)
    text = text.replace("analysis:\n  frf:\n", "analysis:\n  frf:\n    method: modal\n"
                        f"    modal: {{count: {opts.roots}}}\n    tolerance: 1.0\n")
    modal = work / "two_chains.yaml"
    modal.write_text(text)
    return {"transient": rod, "modal": modal}


def worker_library(kind: str, case_path: str, raw: str) -> None:
    """(a), in its own process: the analysis in memory and the raw write, timed; one JSON
    line."""
    from substruct.case.loader import load_case
    from substruct.run import runner
    from substruct.run.analyses import frf_result
    from substruct.run.transient_run import transient_result

    case = load_case(case_path, [])
    model = runner.build_model(case)
    c0, t0 = time.process_time(), time.perf_counter()
    note = ""
    if kind == "transient":
        big = np.asarray(transient_result(case, model).snapshots)
    else:
        res = frf_result(case, model, None)
        big = np.asarray(res.H)
        note = f"{res.method}; check {res.agreement}"
    c1, t1 = time.process_time(), time.perf_counter()
    big.tofile(raw)
    c2, t2 = time.process_time(), time.perf_counter()
    print(json.dumps({"analysis_cpu": c1 - c0, "analysis_wall": t1 - t0, "write_cpu": c2 - c1,
                      "write_wall": t2 - t1, "shape": big.shape, "dtype": big.dtype.str,
                      "note": note}))


def worker_compare(h5: str, name: str, raw: str, shape: str, dtype: str) -> None:
    """Whether ``h5[name]`` holds the raw array, a block at a time: one JSON line."""
    import h5py

    dims = tuple(int(d) for d in shape.split(","))
    ref = np.memmap(raw, dtype=np.dtype(dtype), mode="r", shape=dims)
    with h5py.File(h5, "r") as f:
        ds = f[name]
        step = max(1, (64 << 20) // max(1, ref[0].nbytes))
        equal = ds.shape == dims and all(np.array_equal(ds[k:k + step], ref[k:k + step])
                                         for k in range(0, dims[0], step))
    print(json.dumps({"equal": bool(equal)}))


def measure(kind: str, case: Path, opts: argparse.Namespace, envs: dict[str, dict],
            work: Path) -> None:
    raw = work / f"{kind}.raw"
    a = child([sys.executable, __file__, "--worker", "library", "--kind", kind, "--case",
               str(case), "--raw", str(raw)], envs["after"], work)
    a.update(json.loads(a["out"].strip().splitlines()[-1]))
    a0 = child([sys.executable, __file__, "--worker", "library", "--kind", kind, "--case",
                str(case), "--raw", str(work / "before.raw")], envs["before"], work)
    a0.update(json.loads(a0["out"].strip().splitlines()[-1]))
    (work / "before.raw").unlink()
    rows: dict[str, list[dict]] = {"before": [], "after": []}
    for _ in range(opts.repeat):
        for side in ("before", "after"):
            out = work / f"out_{side}"
            b = child([sys.executable, "-m", "substruct.cli", "run", str(case), "--out",
                       str(out), "--force", "--quiet", "--no-pictures"], envs[side], work)
            h5 = out / f"{case.stem}.h5"
            b["size"] = h5.stat().st_size
            cmp = child([sys.executable, __file__, "--worker", "compare", "--h5", str(h5),
                         "--name", DATASET[kind], "--raw", str(raw), "--shape",
                         ",".join(str(d) for d in a["shape"]), "--dtype", a["dtype"]],
                        envs["after"], work)
            b["equal"] = json.loads(cmp["out"].strip().splitlines()[-1])["equal"]
            rows[side].append(b)
            h5.unlink()
    raw.unlink()
    lib = a["analysis_cpu"] + a["write_cpu"]
    size = statistics.median(r["size"] for r in rows["after"])
    print(f"\n{kind}: output {np.prod(a['shape']) * np.dtype(a['dtype']).itemsize / 1e9:.2f} "
          f"GB {tuple(a['shape'])}, result file {size / 1e9:.2f} GB, {opts.repeat} run(s) "
          f"of each side")
    print(f"{'row':52s} {'CPU s':>8s} {'wall s':>8s} {'peak GB':>8s}")
    print(f"{'(a) library: analysis in memory':52s} {a['analysis_cpu']:8.2f} "
          f"{a['analysis_wall']:8.2f}")
    print(f"{'(a) library: write the output (tofile)':52s} {a['write_cpu']:8.2f} "
          f"{a['write_wall']:8.2f}")
    print(f"{'(a) library: whole process':52s} {a['cpu']:8.2f} {a['wall']:8.2f} "
          f"{a['peak'] / 1e9:8.2f}")
    print(f"{'(a) library before: analysis in memory':52s} {a0['analysis_cpu']:8.2f} "
          f"{a0['analysis_wall']:8.2f}")
    print(f"{'(a) library before: whole process':52s} {a0['cpu']:8.2f} {a0['wall']:8.2f} "
          f"{a0['peak'] / 1e9:8.2f}")
    for side in ("before", "after"):
        med = {k: statistics.median(r[k] for r in rows[side]) for k in ("cpu", "wall")}
        peak = max(r["peak"] for r in rows[side])
        print(f"{'(b) substruct run, ' + side:52s} {med['cpu']:8.2f} {med['wall']:8.2f} "
              f"{peak / 1e9:8.2f}")
        print(f"{'    (b) / (a) analysis + write (target 1.3)':52s} {med['cpu'] / lib:8.2f}")
        print(f"{'    peak - result file (target 1 GB)':52s} {'':8s} {'':8s} "
              f"{(peak - size) / 1e9:8.2f}")
        same = all(r["equal"] for r in rows[side])
        print(f"    file equal to (a)'s array bit for bit: {'yes' if same else 'no'}")
    if a["note"]:
        print(f"(a) {a['note']}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", help="the checkout of the code before")
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--elements", type=int, default=50000)
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--frequencies", type=int, default=300)
    parser.add_argument("--roots", type=int, default=40)
    parser.add_argument("--only", choices=list(DATASET))
    parser.add_argument("--worker", choices=["library", "compare"], help=argparse.SUPPRESS)
    for name in ("kind", "case", "raw", "h5", "name", "shape", "dtype"):
        parser.add_argument(f"--{name}", help=argparse.SUPPRESS)
    opts = parser.parse_args()
    if opts.worker == "library":
        worker_library(opts.kind, opts.case, opts.raw)
        return
    if opts.worker == "compare":
        worker_compare(opts.h5, opts.name, opts.raw, opts.shape, opts.dtype)
        return
    if not opts.before:
        parser.error("--before: the checkout of the code to compare with")
    base = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
            "MKL_NUM_THREADS": "1", "MPLBACKEND": "Agg"}
    base.pop("PYTHONDONTWRITEBYTECODE", None)
    envs = {side: {**base, "PYTHONPATH": str(path)} for side, path in
            (("before", Path(opts.before).resolve()), ("after", ROOT))}
    import h5py
    import scipy

    print(f"# {platform.processor() or platform.machine()}, {os.cpu_count()} cores, Python "
          f"{platform.python_version()}, NumPy {np.__version__}, SciPy {scipy.__version__}, "
          f"h5py {h5py.__version__} (HDF5 {h5py.version.hdf5_version})")
    with tempfile.TemporaryDirectory() as tmp:
        cases = write_cases(Path(tmp), opts)
        for kind, case in cases.items():
            if opts.only in (None, kind):
                measure(kind, case, opts, envs, Path(tmp))


if __name__ == "__main__":
    main()
