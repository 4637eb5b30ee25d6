r"""The production receptance sweep: the null-space form on a sparse master-slave basis, one
sparse factorization per frequency, every input at once, no dense ``n x n`` block.

Under ``A q = 0`` the displacements are :math:`q = T p` (``A T = 0``,
:func:`substruct.linalg.nullspace.master_slave`), and the receptance of eq (15) is

.. math::  \hat H(\omega) = T\, Z_T(\omega)^{-1}\, T^T, \qquad
           Z_T(\omega) = T^T K T - \omega^2\, T^T M T + i \omega\, T^T C T ,

so that for inputs ``E`` (columns) and outputs ``O`` (rows)

.. math::  H[k] = (O T)\, Z_T(\omega_k)^{-1} (T^T E).

``T^T K T``, ``T^T M T``, ``T^T C T``, ``O T`` and ``T^T E`` are formed once; at each frequency
:math:`Z_T` (complex symmetric, not Hermitian) is factorized by SuperLU in one fill-reducing
ordering computed once for the sweep (:func:`substruct.linalg.factorize.fill_ordering`,
:func:`substruct.linalg.factorize.complex_symmetric`) and solved for all inputs in one call.
Where a reverse Cuthill-McKee ordering makes :math:`Z_T` narrow (half-bandwidth at most
:data:`substruct.linalg.banded.BAND_MAX`: chains, rods, beams) the factorization is LAPACK's band
LU instead (:mod:`substruct.linalg.banded`): with many inputs its substitutions in compiled
loops over the inputs (:func:`~substruct.linalg.banded.band_solve_many`), with few LAPACK's
``gbsv``.  The outputs are gathered by rows (:class:`Gather`).  The
reduced system has ``n - rank(A)`` unknowns instead of the ``n + m`` of the KKT system and
the ``n + m`` of the bordered generalized-inverse system, and needs one factorization a
frequency instead of their two.

Given a ``sink`` (:class:`~substruct.analysis.frf.stream.FrequencySink`), the sweep holds one
block of frequencies (as many as the sink asks for) and hands each block to the sink when it
is full: the whole output is never in memory (``substruct run`` writes the blocks to the
result file as they come).  Each frequency's numbers are the same, bit for bit, either way.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
import scipy.sparse as sp

from substruct.analysis.errors import AnalysisInputError, require_analysis_memory
from substruct.analysis.frf.stream import FrequencySink
from substruct.analysis.modes.krylov import eliminate
from substruct.linalg.banded import (
    BAND_MAX,
    band_ordering,
    band_solve,
    band_solve_many,
    band_storage,
    kernel_pays,
)
from substruct.linalg.factorize import complex_symmetric, fill_ordering
from substruct.linalg.memory import factor_memory
from substruct.linalg.scaling import equilibrate

__all__ = ["Gather", "null_space_sparse_sweep"]


class Gather:
    r"""``out = O X`` for a sparse ``O`` whose rows are mostly single entries (outputs at
    coordinates that the elimination kept): those rows copied from rows of ``X`` (scaled
    where the entry is not 1), runs of consecutive rows as one slice copy each, the others
    (outputs at eliminated coordinates, interpolated points) by a product with their few
    rows."""

    def __init__(self, O: sp.csr_array) -> None:
        counts = np.diff(O.indptr)
        single = np.flatnonzero(counts == 1)
        cols = O.indices[O.indptr[single]]
        vals = O.data[O.indptr[single]]
        unit = vals == 1.0
        self.scaled = (single[~unit], cols[~unit], vals[~unit][:, None])
        rows, cols = single[unit], cols[unit]
        # runs of unit rows: out[r0:r0+len] = X[c0:c0+len] (or reversed, step -1)
        self.runs: list[tuple[slice, slice]] = []
        k = 0
        while k < rows.size:
            step = int(cols[k + 1] - cols[k]) if k + 1 < rows.size else 1
            step = step if step in (1, -1) else 1
            e = k + 1
            while e < rows.size and rows[e] == rows[e - 1] + 1 and \
                    cols[e] == cols[e - 1] + step:
                e += 1
            stop = int(cols[e - 1]) + step
            self.runs.append((slice(int(rows[k]), int(rows[e - 1]) + 1),
                              slice(int(cols[k]), None if stop < 0 else stop, step)))
            k = e
        if len(self.runs) > max(8, rows.size // 8):  # scattered: one fancy copy
            self.runs = []
            self.unit: tuple[np.ndarray, np.ndarray] | None = (rows, cols)
        else:
            self.unit = None
        self.other = np.flatnonzero(counts != 1)
        self.rest = sp.csr_array(O[self.other])
        # a few such rows (constraint rows, interpolated points): dense, one BLAS product
        self.rest_dense = self.rest.toarray() if self.other.size <= 64 else None

    def __call__(self, X: np.ndarray, out: np.ndarray) -> None:
        """Write ``O X`` into ``out`` (``X`` with C-contiguous rows)."""
        for r, c in self.runs:
            out[r] = X[c]
        if self.unit is not None:
            out[self.unit[0]] = X[self.unit[1]]
        rows, cols, vals = self.scaled
        if rows.size:
            out[rows] = vals * X[cols]
        if self.other.size:
            out[self.other] = self.rest_dense @ X if self.rest_dense is not None else \
                self.rest @ X


def _singular(omega: float) -> AnalysisInputError:
    return AnalysisInputError(f"the receptance is singular at omega = {omega:g} rad/s (a "
                              f"resonance of an undamped system, or a rigid-body motion at "
                              f"omega = 0)")


def null_space_sparse_sweep(K: sp.sparray, M: sp.sparray, C: sp.sparray | None,
                            A: sp.sparray, omegas: np.ndarray, inputs: sp.sparray,
                            outputs: sp.sparray,
                            progress: Callable[[int], None] | None = None,
                            sink: FrequencySink | None = None) -> np.ndarray | None:
    r"""``H[k] = (O T) Z_T(\omega_k)^{-1} (T^T E)`` for a system under ``A q = 0`` (module
    docstring), complex ``(n_omega, n_outputs, n_inputs)``.

    Args:
        K, M, C: sparse ``n x n`` (``C`` may be ``None``).
        A: ``m x n`` constraint rows, any rank (equilibrated here).
        omegas: circular frequencies (rad/s).
        inputs: ``n x p`` generalized forces (columns).
        outputs: ``q x n`` output rows.
        progress: called with the number of frequencies done, every 10 frequencies.
        sink: if given, the receptances go to it a block of frequencies at a time
            (``sink.open(shape, dtype)`` gives the block's length, then
            ``sink.write(start, block)`` for each block, in order) and ``None`` is returned;
            the memory check then counts one block, not the whole output.

    Returns:
        ``H``, or ``None`` with a ``sink``.

    Raises:
        ValueError: ``Z_T`` singular at a frequency (a resonance of an undamped system, or
            ``omega = 0`` with a rigid-body motion); the factorization would not fit the
            memory available.
    """
    Ks, Ms = sp.csr_array(K, dtype=float), sp.csr_array(M, dtype=float)
    n = Ks.shape[0]
    As = sp.csr_array(A, dtype=float)
    As.eliminate_zeros()
    As = sp.csr_array(equilibrate(As).A) if As.shape[0] else sp.csr_array((0, n))
    T = sp.csc_array(eliminate(Ms, As).T)
    Tt = sp.csr_array(T.T)
    Kt = sp.csc_array(Tt @ Ks @ T)
    Mt = sp.csc_array(Tt @ Ms @ T)
    Ct = None if C is None or not sp.csr_array(C).nnz else \
        sp.csc_array(Tt @ sp.csr_array(C, dtype=float) @ T)
    w = np.asarray(omegas, dtype=float)
    OT = sp.csr_array(sp.csr_array(outputs, dtype=float) @ T)
    B = np.asarray(sp.csr_array(Tt @ sp.csc_array(inputs, dtype=float)).toarray(),
                   dtype=complex)
    pattern = abs(Kt) + abs(Mt) + (abs(Ct) if Ct is not None else 0)
    shape = (w.size, OT.shape[0], B.shape[1])
    rows = w.size if sink is None else max(1, min(w.size, sink.open(shape, np.dtype(complex))))
    out_bytes = 16.0 * rows * OT.shape[0] * B.shape[1]
    require_analysis_memory(
        factor_memory(pattern, "superlu", complex_factor=True) + out_bytes,
        f"the receptance sweep of {Kt.shape[0]} reduced coordinates "
        f"({w.size} frequencies x {OT.shape[0]} outputs x {B.shape[1]} inputs)")
    order, width = band_ordering(pattern)
    banded = width <= BAND_MAX
    p = order if banded else fill_ordering(pattern)  # one ordering for every frequency
    Kp, Mp = sp.csc_array(Kt[p][:, p]), sp.csc_array(Mt[p][:, p])
    Cp = None if Ct is None else sp.csc_array(Ct[p][:, p])
    Bp = np.asfortranarray(B[p])
    gather = Gather(sp.csr_array(OT[:, p]))
    H = np.empty((rows, OT.shape[0], B.shape[1]), dtype=complex)  # the output, or one block
    many = banded and kernel_pays(Kt.shape[0], B.shape[1], w.size)
    if banded:
        Kb, Mb = band_storage(Kp, width), band_storage(Mp, width)
        Cb = None if Cp is None else band_storage(Cp, width)
    Bc = np.ascontiguousarray(Bp) if many else Bp  # the kernel's rows: C order
    X = np.empty(Bp.shape if many else (0, 0), dtype=complex)  # the kernel's solution
    for k, wk in enumerate(w):
        try:
            if banded:
                Zb = np.asarray(Kb - wk**2 * Mb + (0.0 if Cb is None else 1j * wk * Cb),
                                dtype=complex)
                if many:
                    band_solve_many(Zb, width, Bc, X)
                    Xk = X
                else:
                    Xk = band_solve(Zb, width, Bp)
            else:
                Z = Kp.astype(complex) - wk**2 * Mp + (0.0 if Cp is None else 1j * wk * Cp)
                Xk = complex_symmetric(Z, ordered=True)(Bp)
        except (RuntimeError, np.linalg.LinAlgError) as exc:
            raise _singular(wk) from exc
        gather(np.asarray(Xk).reshape(Bp.shape), H[k % rows])
        if sink is not None and ((k + 1) % rows == 0 or k + 1 == w.size):
            start = k // rows * rows
            sink.write(start, H[:k + 1 - start])
        if progress is not None and ((k + 1) % 10 == 0 or k + 1 == w.size):
            progress(k + 1)
    return None if sink is not None else H
