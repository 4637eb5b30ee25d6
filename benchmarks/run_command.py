"""End-to-end benchmark: ``substruct run`` of the box cases against the monolithic baseline.

    OMP_NUM_THREADS=1 python benchmarks/run_command.py [--sizes 10000 30000 100000] [--big]
                                                       [--quick] [--repeat 3]

The model is the one of ``benchmarks/modes.py``: a clamped steel box ``4 x 1 x 1`` of Q1
hexahedra made of two halves tied node to node at ``x = 2``, two tuned absorbers (free-free
spring-masses on massless boundary coordinates, one at an interpolated point) and one
four-term multi-point constraint; the lowest 20 coupled modes.  Here it is a case file, and
what is timed is the command a user runs:

(a) ``substruct run box.yaml --out <tmp> --force --quiet --no-pictures`` in a subprocess:
    Python start-up, imports, reading and checking the case, meshing, assembly, the production
    solve (null-space form, KKT and generalized-inverse residual checks), the results file;
(b) the baseline of ``benchmarks/modes.py`` in a subprocess: the monolithic mesh with the
    absorbers stamped into ``K`` and ``M`` and the constraint eliminated by hand, then
    ``eigsh`` in shift-invert mode with ``OPinv`` from the same factorization (the model built
    outside the timing; only its solve timed).

Time: wall clock of the subprocess, median of ``--repeat`` runs (one run where a run takes
over 60 s); and the CPU time (user + system) of each whole process, which a machine shared
with other jobs disturbs far less than the wall clock (b's process builds the monolithic
model once and solves it up to ``--repeat`` times: the CPU of the extra solves is taken off).  Memory: the peak resident set of the subprocess (``ru_maxrss`` of the child).
Sizes 10k, 30k and 100k coordinates (``--quick``: 10k and 30k, one run each, about two
minutes); ``--big`` adds 300k.  The frequencies of (a), read back from its ``--json``
summary, are compared with (b).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from modes import LX, LY, LZ, MPC, N_MODES, absorber_params, best_factorization  # noqa: E402
from modes import divisions, machine  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def case_text(target: int) -> str:
    """The box case of about ``target`` coordinates as YAML."""
    nxh, m = divisions(target)
    half = f"lengths: [{LX / 2}, {LY}, {LZ}], divisions: [{nxh}, {m}, {m}]"
    (n1, m1, k1, p1, c1), (n2, m2, k2, p2, c2) = absorber_params()

    def at(xyz, comp):
        side = "left" if xyz[0] < LX / 2 else "right"
        return f"{side}@{xyz[0]:g},{xyz[1]:g},{xyz[2]:g}:{comp}"
    terms = "\n".join(f"      {at(x, 'z')}: {c:g}" for x, c in MPC)
    return f"""\
name: box
substructures:
  - name: left
    type: solid
    box: {{{half}}}
    E: 2.1e11
    nu: 0.3
    rho: 7850
    fixed: [{{box: [[0, 0, 0], [0, {LY}, {LZ}]]}}]
  - name: right
    type: solid
    box: {{{half}, origin: [{LX / 2}, 0, 0]}}
    E: 2.1e11
    nu: 0.3
    rho: 7850
  - {{name: {n1}, type: free-free, mass: {m1!r}, stiffness: {k1!r}}}
  - {{name: {n2}, type: free-free, mass: {m2!r}, stiffness: {k2!r}}}
interfaces:
  - {{name: joint, between: [left, right], nodes: {{box: [[{LX / 2}, 0, 0], [{LX / 2}, {LY}, {LZ}]]}}}}
connections:
  - ["{at(p1, c1)}", {n1}]
  - ["{at(p2, c2)}", {n2}]
constraints:
  - name: mpc
    terms:
{terms}
analysis:
  modes: {{count: {N_MODES}}}
output: {{pictures: false}}
"""


def child(cmd: list[str], env: dict) -> tuple[float, float, str, float]:
    """Wall time, peak resident set (bytes, ``ru_maxrss`` of this child by ``wait4``),
    stdout and CPU time (user + system, ``wait4``) of one subprocess."""
    with tempfile.TemporaryFile() as err:
        t0 = time.perf_counter()
        proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=err)
        assert proc.stdout is not None
        out = proc.stdout.read().decode()
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - t0
        proc.returncode = os.waitstatus_to_exitcode(status)
        if proc.returncode != 0:
            err.seek(0)
            raise RuntimeError(f"{' '.join(cmd)} failed ({proc.returncode}):\n"
                               f"{err.read().decode()[-3000:]}")
    return wall, usage.ru_maxrss * 1024.0, out, usage.ru_utime + usage.ru_stime


def run_a(size: int, repeat: int, env: dict, work: Path) -> dict:
    case = work / f"box_{size}.yaml"
    case.write_text(case_text(size))
    exe = str(Path(sys.executable).parent / "substruct")
    cmd = [exe, "run", str(case), "--out", str(work / f"out_{size}"), "--force", "--quiet",
           "--no-pictures", "--json"]
    walls, cpus, peak, summary = [], [], 0.0, ""
    for i in range(repeat):
        wall, peak_i, summary, cpu = child(cmd, env)
        walls.append(wall)
        cpus.append(cpu)
        peak = max(peak, peak_i)
        if wall > 60.0:
            break
    data = json.loads(summary)
    return {"time": statistics.median(walls), "cpu": statistics.median(cpus),
            "runs": len(walls), "peak": peak,
            "n": data["model"]["n_dof"], "omega": data["modes"]["omega"],
            "method": data["modes"]["method"], "agreement": data["modes"]["agreement"]}


def run_b(size: int, repeat: int, env: dict, fact: str) -> dict:
    cmd = [sys.executable, str(Path(__file__).with_name("modes.py")), "--worker", "b",
           "--size", str(size), "--factorization", fact, "--repeat", str(repeat)]
    wall, peak, out, cpu = child(cmd, env)
    data = json.loads(out.strip().splitlines()[-1])
    runs = len(data["times"])  # one build, `runs` solves: the CPU of a build and one solve
    return {"time": data["time"], "process": wall, "cpu": cpu - (runs - 1) * data["cpu"],
            "peak": peak, "n": data["n"],
            "omega": 2 * np.pi * np.asarray(data["freq_hz"]), "runs": len(data["times"])}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[10000, 30000, 100000])
    parser.add_argument("--big", action="store_true", help="add 300k coordinates")
    parser.add_argument("--quick", action="store_true", help="10k and 30k, one run each")
    parser.add_argument("--repeat", type=int, default=3)
    opts = parser.parse_args()
    sizes = [10000, 30000] if opts.quick else sorted(opts.sizes + ([300000] if opts.big else []))
    repeat = 1 if opts.quick else opts.repeat
    fact = best_factorization()
    env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
           "MKL_NUM_THREADS": "1", "MPLBACKEND": "Agg"}
    print(f"machine: {machine()}")
    print(f"factorization: {fact} (the baseline's and the one substruct picks)")
    print(f"\n{'n':>8} {'a: run s':>9} {'a: MB':>7} {'b: solve s':>10} {'b: proc s':>9} "
          f"{'b: MB':>7} {'a/b t':>6} {'a/b t proc':>10} {'a/b mem':>7} {'max |wa/wb-1|':>13} "
          f"{'a: cpu s':>8} {'b: cpu s':>8} {'a/b cpu':>7}")
    with tempfile.TemporaryDirectory() as tmp:
        for size in sizes:
            b = run_b(size, repeat, env, fact)
            a = run_a(size, repeat, env, Path(tmp))
            diff = float(np.max(np.abs(np.asarray(a["omega"][:N_MODES]) / b["omega"] - 1)))
            print(f"{a['n']:>8} {a['time']:>9.2f} {a['peak'] / 2**20:>7,.0f} "
                  f"{b['time']:>10.2f} {b['process']:>9.2f} {b['peak'] / 2**20:>7,.0f} "
                  f"{a['time'] / b['time']:>6.2f} {a['time'] / b['process']:>10.2f} "
                  f"{a['peak'] / b['peak']:>7.2f} {diff:>13.1e} {a['cpu']:>8.2f} "
                  f"{b['cpu']:>8.2f} {a['cpu'] / b['cpu']:>7.2f}", flush=True)
            print(f"         (a) {a['method']}, checks "
                  f"{', '.join(f'{k} {v:.1e}' for k, v in a['agreement'].items())}; "
                  f"runs a {a['runs']}, b {b['runs']}", flush=True)


if __name__ == "__main__":
    main()
