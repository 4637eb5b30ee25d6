r"""Recovery of superelements' interior responses in a run (:mod:`substruct.run.recovered`).

A part's coordinates are the block :math:`S q` of the coupled model's coordinates (``S`` picks
its rows), so a recovery row is an output row of the coupled model,
:math:`y_s = R_s S q_s`.  The transient analysis records these rows beside the case's outputs
(:func:`recovery_rows`), and :func:`split_recovered` takes them back out, sums the blocks of
each matrix over its histories and leaves the transient result as the case asked for it.
Recovered mode shapes are :math:`\sum_i R_{s_i} \lambda^{p_i} S \phi` (:func:`recover_modes`).
Recovered receptances are :math:`\sum_i (i\omega)^{p_i} R_{s_i} S H(\omega)` (:func:`recover_frf`,
from the receptances of the same rows, computed by a second sweep at the frequencies of the
case's one: the case's sweep streams its outputs to the results file as it goes).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp

from substruct.analysis.results import Modes
from substruct.analysis.transient.results import Transient
from substruct.case.kinds import is_superelement
from substruct.run.recovered import Recovered
from substruct.vocabulary import DERIVATIVE_ORDER

__all__ = ["RecoveryPlan", "recovery_plan", "recover_modes", "recovery_rows",
           "split_recovered", "recover_frf"]



@dataclass
class RecoveryPlan:
    """The recovery matrices of a model: per entry, the part, its block of the coupled
    coordinates and the case's specification."""

    entries: list[tuple[str, slice, Any]]

    def __bool__(self) -> bool:
        return bool(self.entries)

    def empty(self) -> list[Recovered]:
        """One :class:`Recovered` per matrix, nothing recovered yet."""
        return [Recovered(part, spec.name, spec.histories(), spec.row_labels())
                for part, _, spec in self.entries]


def recovery_plan(case: Any, asm: Any) -> RecoveryPlan:
    """The recovery matrices of the superelements of ``case`` on the assembly ``asm``."""
    entries = []
    for spec in case.substructures:
        if is_superelement(spec):
            block = asm.block(spec.name)
            for rec in spec.recovery:
                entries.append((spec.name, block, rec))
    return RecoveryPlan(entries)


def recover_modes(plan: RecoveryPlan, modes: Modes, out: list[Recovered]) -> None:
    r"""Fill ``out[i].modes`` with :math:`\sum_s R_s \lambda^{p_s} \phi_{\text{part}}`
    (real when every value is)."""
    lam = np.asarray(modes.eigenvalues)
    shapes = np.asarray(modes.shapes)
    for rec, (_, block, spec) in zip(out, plan.entries):
        R = spec.matrix_read()
        x = shapes[block]
        n = x.shape[0]
        y = np.zeros((R.shape[0], x.shape[1]), dtype=complex)
        for i, s in enumerate(spec.histories()):
            y += (R[:, i * n:(i + 1) * n] @ x) * lam[None, :] ** DERIVATIVE_ORDER[s]
        rec.modes = y.real.copy() if not np.any(y.imag) else y


def recovery_rows(plan: RecoveryPlan, n: int) -> sp.csr_array:
    """The output rows :math:`R_s S` of every matrix and history, stacked in plan order."""
    blocks = []
    for _, block, spec in plan.entries:
        R = spec.matrix_read()
        m = block.stop - block.start
        for i, _s in enumerate(spec.histories()):
            Rs = sp.coo_array(R[:, i * m:(i + 1) * m])
            blocks.append(sp.csr_array((Rs.data, (Rs.row, Rs.col + block.start)),
                                       shape=(R.shape[0], n)))
    return sp.csr_array(sp.vstack(blocks)) if blocks else sp.csr_array((0, n))


def split_recovered(plan: RecoveryPlan, tr: Transient, n_outputs: int,
                    out: list[Recovered]) -> Transient:
    """The transient result of the case's ``n_outputs`` outputs alone; the rows after them
    (:func:`recovery_rows`) summed into ``out[i].history``."""
    col = n_outputs
    for rec, (_, _, spec) in zip(out, plan.entries):
        rows = spec.matrix_read().shape[0]
        y = np.zeros((len(tr.t), rows))
        for s in spec.histories():
            y += np.asarray(getattr(tr, s))[:, col:col + rows]
            col += rows
        rec.history, rec.t = y, np.asarray(tr.t).copy()
    keep = slice(0, n_outputs)
    infl = tr.base_influence[keep] if tr.base_influence.size else tr.base_influence
    return dataclasses.replace(
        tr, outputs=list(tr.outputs[:n_outputs]), displacement=tr.displacement[:, keep],
        velocity=tr.velocity[:, keep], acceleration=tr.acceleration[:, keep],
        base_influence=infl)


def recover_frf(plan: RecoveryPlan, H: np.ndarray, omega: np.ndarray, inputs: list[str],
                out: list[Recovered]) -> None:
    r"""Fill ``out[i].frf`` from ``H``, the receptances of :func:`recovery_rows`
    (``n_omega x rows x n_inputs``, plan order):

    .. math::  H_y(\omega) = \sum_i (i\omega)^{p_i} \, (R_{s_i} S) H_x(\omega)

    (:math:`p` = 0, 1, 2 for displacement, velocity, acceleration:
    :data:`substruct.vocabulary.DERIVATIVE_ORDER`)."""
    w = np.asarray(omega, dtype=float)
    row = 0
    for rec, (_, _, spec) in zip(out, plan.entries):
        rows = spec.matrix_read().shape[0]
        y = np.zeros((len(w), rows, H.shape[2]), dtype=complex)
        for s in spec.histories():
            y += (1j * w)[:, None, None] ** DERIVATIVE_ORDER[s] * H[:, row:row + rows]
            row += rows
        rec.frf, rec.omega, rec.inputs = y, w.copy(), list(inputs)
