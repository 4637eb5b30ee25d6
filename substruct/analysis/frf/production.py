r"""The production path of receptance sweeps: the numbers from the sparse null-space sweep, the
named formulations as checks at a few frequencies.

For models above :data:`SWEEP_SPARSE_ABOVE` coordinates under ``A q = 0`` (no force-tied
constraint, ``R = 0``), whatever direct formulation a case names, the receptances come from
:func:`substruct.analysis.frf.sparse.null_space_sparse_sweep` (one sparse factorization of
:math:`T^T Z(\omega) T` a frequency, all inputs at once).  The generalized-inverse form of eq
(15) and the KKT form (:func:`substruct.analysis.formulations.coupling.receptance`) then check it at
:data:`CHECK_FREQUENCIES` frequencies of the grid (its first, middle and last), for every
output and up to :data:`CHECK_INPUTS` inputs spread over the list (all of them when there are
no more; :func:`checked_inputs`), each figure

.. math::  \delta = \frac{\max_{k \in \text{checked}} |H^{check}_k - H_k|}
                         {\max_{k \in \text{checked}} |H_k|} .

With hundreds of inputs (every coordinate of two chains: 400) the checks of every input would
cost a quarter of the sweep itself; the sample keeps them within about a tenth.

The constraint residual :math:`\max |A u| / \max |H|` of the null-space sweep (:math:`A T = 0`
holds to round-off by construction) is measured at the same frequencies
(:func:`constraint_residual`), so that the sweep itself computes the outputs only: a
receptance of 1,000 x 400 x 400 is then one contiguous array, written and sent between
processes without a copy.  The checks read only the checked frequencies of the sweep (its
numbers as computed): given a sink (:class:`~substruct.analysis.frf.stream.SweepTap`), the
sweep keeps those as the blocks pass and never holds the whole output.

A sweep with a force-tied constraint (``R != 0``), or of a small model, is left to the direct
formulations (every frequency, every check).
"""

from __future__ import annotations

from typing import Callable, Sequence

import numpy as np
import scipy.sparse as sp

from substruct.analysis.checks import receptance_difference
from substruct.analysis.formulations.coupling import FORMULATIONS, receptance
from substruct.analysis.frf.sparse import null_space_sparse_sweep
from substruct.analysis.frf.stream import SweepTap
from substruct.linalg.scaling import equilibrate
from substruct.vocabulary import KKT, NULL_SPACE
from substruct.linalg.system import ConstrainedSystem

__all__ = [
    "CHECK_FREQUENCIES",
    "CHECK_INPUTS",
    "PRODUCTION_SWEEP",
    "SWEEP_SPARSE_ABOVE",
    "check_frequencies",
    "checked_inputs",
    "constraint_residual",
    "production_sweep",
    "production_sweep_applies",
    "sweep_checks",
]

#: Sweeps of models above this many coordinates take the production path.
SWEEP_SPARSE_ABOVE = 100
#: How many frequencies of the grid the check formulations are solved at.
CHECK_FREQUENCIES = 3
#: At most this many inputs (columns) are solved by the check formulations.
CHECK_INPUTS = 64
#: The method string of a production sweep's result.
PRODUCTION_SWEEP = "null-space/sparse"


def production_sweep_applies(n: int, R: sp.sparray | None, method: str) -> bool:
    """Whether a sweep takes the production path: a direct formulation named (``method`` one of
    :data:`substruct.analysis.formulations.coupling.FORMULATIONS`), no force-tied constraint (``R`` ``None``),
    more than :data:`SWEEP_SPARSE_ABOVE` coordinates."""
    return method in FORMULATIONS and R is None and n > SWEEP_SPARSE_ABOVE


def check_frequencies(count: int) -> np.ndarray:
    """Indices of the checked frequencies of a grid of ``count``: first, middle, last."""
    return np.unique(np.linspace(0, count - 1, min(CHECK_FREQUENCIES, count)).round()
                     .astype(int)) if count else np.zeros(0, dtype=int)


def checked_inputs(count: int) -> np.ndarray:
    """Indices of the inputs the checks solve: all of ``count`` up to :data:`CHECK_INPUTS`,
    else that many spread evenly over the list, its first and last included."""
    if count <= CHECK_INPUTS:
        return np.arange(count)
    return np.unique(np.linspace(0, count - 1, CHECK_INPUTS).round().astype(int))


def production_sweep(K: sp.csr_array, M: sp.csr_array, C: sp.csr_array | None,
                     A: sp.csr_array, omegas: np.ndarray, inputs: sp.csc_array,
                     rows: sp.csr_array, progress: Callable[[int, int, str], None] | None,
                     tap: SweepTap | None = None) -> tuple[np.ndarray | None, np.ndarray]:
    """The production sweep (:func:`~substruct.analysis.frf.sparse.null_space_sparse_sweep`)
    with progress reported as ``progress(done, total, NULL_SPACE)``: ``(H, checked)``, with
    ``checked = H[check_frequencies(len(omegas))]`` as computed.  Given a ``tap``, the blocks
    go to it (it keeps the checked frequencies) and ``H`` is ``None``."""
    total = len(omegas)

    def report(done: int) -> None:
        if progress is not None:
            progress(done, total, NULL_SPACE)

    idx = check_frequencies(total)
    if tap is None:
        H = null_space_sparse_sweep(K, M, C, A, omegas, inputs, rows, progress=report)
        assert H is not None
        return H, H[idx]
    tap.keep(idx)
    null_space_sparse_sweep(K, M, C, A, omegas, inputs, rows, progress=report, sink=tap)
    return None, tap.checked


def constraint_residual(K: sp.csr_array, M: sp.csr_array, C: sp.csr_array | None,
                        A: sp.csr_array, omegas: np.ndarray, inputs: sp.csc_array,
                        checked: np.ndarray) -> float:
    r""":math:`\max |D A u| / \max |H|` of the production sweep, both at
    :func:`check_frequencies` and the :func:`checked_inputs` (``u`` every coordinate's response
    by the null-space sweep, ``D A`` the rows scaled to unit norm); ``checked`` is the sweep's
    ``H`` at :func:`check_frequencies`."""
    idx = check_frequencies(len(omegas))
    if not A.shape[0] or not idx.size:
        return 0.0
    cols = checked_inputs(inputs.shape[1])
    AH = null_space_sparse_sweep(K, M, C, A, omegas[idx], sp.csc_array(inputs[:, cols]),
                                 sp.csr_array(equilibrate(A).A))
    assert AH is not None
    scale = max(float(np.abs(checked[:, :, cols]).max(initial=0.0)), 1e-300)
    return float(np.abs(AH).max(initial=0.0) / scale)


def sweep_checks(system: ConstrainedSystem, omegas: np.ndarray, inputs: sp.csc_array,
                 outputs: sp.csr_array, checked: np.ndarray, method: str,
                 checks: Sequence[str]) -> dict[str, float]:
    """The check figures of a production sweep (``checked``: its ``H`` at
    :func:`check_frequencies`): each of ``method`` and ``checks`` other
    than ``null-space`` (``kkt`` if none is left) solved by
    :func:`substruct.analysis.formulations.coupling.receptance` at :func:`check_frequencies` for every
    output and the :func:`checked_inputs` (the system's own rows, ``R`` none on this path)."""
    labels = None if system.constraint_labels is None else list(system.constraint_labels)
    names = [m for k, m in enumerate([method, *checks])
             if m != NULL_SPACE and m not in [method, *checks][:k]] or [KKT]
    idx = check_frequencies(len(omegas))
    if not idx.size:
        return {m: 0.0 for m in names}
    cols = checked_inputs(inputs.shape[1])
    sample = sp.csc_array(inputs[:, cols])
    out = {}
    for name in names:
        Hc = receptance(system.K, system.M, system.C, system.A, omegas[idx], None, method=name,
                        inputs=sample, outputs=outputs, labels=labels)
        out[name] = receptance_difference(Hc, checked[:, :, cols])
    return out
