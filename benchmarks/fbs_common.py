r"""What the two LM-FBS benchmarks (``fbs_assembly.py``, ``fbs_frf_parts.py``) share: the
coupling of stacked receptances by pyFBS (in another Python, a subprocess) and by a lean
NumPy formula, the timing of a fresh process, and medians.

LM-FBS: with the parts' receptances stacked block-diagonally, :math:`Y(\omega)`, and the
signed Boolean compatibility :math:`B` of the interface,

.. math::  Y_c = Y - Y B^T (B Y B^T)^{-1} B Y .

* pyFBS 1.0.7 ships no coupling function; its LM-FBS is the expression of its coupling
  example on frequency-stacked arrays, evaluated left to right with ``pyfbs.tpinv`` for the
  interface inverse (:func:`pyfbs_coupling`; ``numpy.linalg.pinv`` when pyFBS is not
  importable, and the row then says so), 100 frequencies a stack as in ``frf_sweep.py``.
* lean NumPy (:func:`lean_lmfbs`): only the interface columns of ``B`` enter, and only the
  outputs x inputs asked for are formed, ``Y_oi - (Y_o,I B_I^T) solve(B_I Y_II B_I^T,
  B_I Y_I,i)``, batched over the frequencies by ``numpy.linalg.solve``.

Run as a script (``python fbs_common.py IN.npz OUT.npz``, in the environment that has pyFBS)
it is the pyFBS worker: it reads the parts' receptances, couples them (a warm-up on two
frequencies first, then every frequency, timed inside the process) and writes the coupled
outputs x inputs and its times.  It imports nothing but NumPy (and pyFBS).
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Callable

import numpy as np

HERE = Path(__file__).resolve().parent
STACK = 100  # frequencies a stack of the pyFBS route


def block_diag_stack(blocks: list[np.ndarray], sl: slice) -> np.ndarray:
    """``diag(Y^(s))`` of the frequencies ``sl`` (dense, as a pyFBS user stacks them)."""
    sizes = [b.shape[1] for b in blocks]
    k = len(range(*sl.indices(blocks[0].shape[0])))
    Y = np.zeros((k, sum(sizes), sum(sizes)), dtype=complex)
    at = 0
    for b, n in zip(blocks, sizes):
        Y[:, at:at + n, at:at + n] = b[sl]
        at += n
    return Y


def pyfbs_coupling(blocks: list[np.ndarray], B: np.ndarray, outs: np.ndarray,
                   ins: np.ndarray) -> tuple[np.ndarray, str]:
    """pyFBS's LM-FBS on every frequency, :data:`STACK` at a time: ``Y - Y B^T tpinv(B Y B^T)
    B Y`` left to right on the dense stacks; returns the coupled ``[:, outs][:, :, ins]`` and
    what inverted the interface."""
    try:
        import pyfbs
        inverse: Callable[[np.ndarray], np.ndarray] = lambda X: pyfbs.tpinv(X, trunc=0)
        how = "pyfbs.tpinv"
    except ImportError:
        inverse, how = np.linalg.pinv, "numpy.linalg.pinv (pyFBS not importable)"
    k = blocks[0].shape[0]
    H = np.empty((k, len(outs), len(ins)), dtype=complex)
    for s in range(0, k, STACK):
        Y = block_diag_stack(blocks, slice(s, s + STACK))
        Yc = Y - Y @ B.T @ inverse(B @ Y @ B.T) @ B @ Y
        H[s:s + len(Y)] = Yc[:, outs][:, :, ins]
        del Y, Yc
    return H, how


def lean_lmfbs(blocks: list[np.ndarray], B: np.ndarray, outs: np.ndarray,
               ins: np.ndarray) -> np.ndarray:
    r"""Lean LM-FBS, batched over the frequencies (:data:`STACK` at a time, to bound the
    memory): only the interface columns ``I`` of ``B`` and the asked ``outs x ins``,

    .. math::  H = Y_{oi} - (Y_{oI} B_I^T)\, (B_I Y_{II} B_I^T)^{-1} (B_I Y_{Ii}) ."""
    I = np.flatnonzero(np.any(B != 0, axis=0))
    BI = B[:, I]
    rows = np.concatenate([outs, I])
    cols = np.concatenate([ins, I])
    k = blocks[0].shape[0]
    H = np.empty((k, len(outs), len(ins)), dtype=complex)
    no, ni = len(outs), len(ins)
    sizes = np.cumsum([0] + [b.shape[1] for b in blocks])
    part = np.searchsorted(sizes, np.arange(sizes[-1]), side="right") - 1
    for s in range(0, k, STACK):
        # the rows x cols of diag(Y^(s)) only, taken from the parts' blocks
        sub = np.zeros((len(range(*slice(s, s + STACK).indices(k))), len(rows), len(cols)),
                       dtype=complex)
        for p, b in enumerate(blocks):
            r = np.flatnonzero(part[rows] == p)
            c = np.flatnonzero(part[cols] == p)
            sub[:, r[:, None], c[None, :]] = b[s:s + STACK][:, (rows[r] - sizes[p])[:, None],
                                                           (cols[c] - sizes[p])[None, :]]
        YoI = sub[:, :no, ni:] @ BI.T
        BYBt = BI @ sub[:, no:, ni:] @ BI.T
        BYi = BI @ sub[:, no:, :ni]
        H[s:s + len(sub)] = sub[:, :no, :ni] - YoI @ np.linalg.solve(BYBt, BYi)
    return H


def child(cmd: list[str], env: dict | None = None, cwd: Path | None = None) -> dict:
    """Wall time, CPU time (user + system, ``wait4``: the process and the children it
    waited for) and peak resident set (bytes) of one fresh process, and its standard output."""
    with tempfile.TemporaryFile() as err:
        t0 = time.perf_counter()
        proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=err, cwd=cwd)
        assert proc.stdout is not None
        out = proc.stdout.read().decode()
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - t0
        code = os.waitstatus_to_exitcode(status)
        if code != 0:
            err.seek(0)
            raise RuntimeError(f"{' '.join(cmd)} failed ({code}):\n{err.read().decode()[-3000:]}")
    return {"wall": wall, "cpu": usage.ru_utime + usage.ru_stime,
            "peak": usage.ru_maxrss * 1024.0, "out": out}


def timed(run: Callable[[], object], repeat: int) -> tuple[float, float, int, object]:
    """Median wall and CPU seconds of ``repeat`` calls (one if the first takes over 60 s),
    the number of calls, and the last answer."""
    walls, cpus, out = [], [], None
    for _ in range(repeat):
        out = None
        t0, c0 = time.perf_counter(), time.process_time()
        out = run()
        walls.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
        if walls[0] > 60.0:
            break
    return statistics.median(walls), statistics.median(cpus), len(walls), out


def run_pyfbs(python: str | None, blocks: list[np.ndarray], B: np.ndarray, outs: np.ndarray,
              ins: np.ndarray, work: Path) -> dict:
    """The pyFBS route in ``python`` (another environment): the data saved to an ``.npz``,
    the worker run as a fresh process.  Returns ``{"H", "cpu", "wall"}`` (the coupling, warm,
    timed inside the process), ``"process_cpu"``, ``"process_wall"`` (the whole process:
    start-up, imports, reading the data), ``"version"`` and ``"how"``; or ``{"error": why}``
    when that Python has no pyFBS."""
    if not python:
        return {"error": "pyFBS not importable (no --pyfbs PYTHON given)"}
    probe = subprocess.run([python, "-c", "import pyfbs; from importlib.metadata import "
                            "version; print(version('pyFBS'))"], capture_output=True,
                           text=True, env=dict(os.environ, PYTHONPATH=""))
    if probe.returncode != 0:
        return {"error": f"pyFBS not importable in {python}"}
    src, dst = work / "pyfbs_in.npz", work / "pyfbs_out.npz"
    np.savez(src, B=B, outs=outs, ins=ins, **{f"Y{k}": b for k, b in enumerate(blocks)})
    proc = child([python, str(HERE / "fbs_common.py"), str(src), str(dst)],
                 env=dict(os.environ, PYTHONPATH=""))
    with np.load(dst) as z:
        res = {"H": z["H"], **json.loads(str(z["times"]))}
    src.unlink()
    dst.unlink()
    res.update(process_cpu=proc["cpu"], process_wall=proc["wall"],
               version=probe.stdout.strip())
    return res


def _worker(src: str, dst: str) -> None:
    with np.load(src) as z:
        B, outs, ins = z["B"], z["outs"], z["ins"]
        blocks = [z[f"Y{k}"] for k in range(sum(1 for n in z.files if n.startswith("Y")))]
    pyfbs_coupling([b[:2] for b in blocks], B, outs, ins)  # warm-up: imports, first calls
    t0, c0 = time.perf_counter(), time.process_time()
    H, how = pyfbs_coupling(blocks, B, outs, ins)
    times = {"cpu": time.process_time() - c0, "wall": time.perf_counter() - t0, "how": how}
    np.savez(dst, H=H, times=json.dumps(times))


if __name__ == "__main__":
    _worker(sys.argv[1], sys.argv[2])
