r"""The analyses a case asks for, on its model: a thin adapter from ``case.analysis`` to
:mod:`substruct.analysis.api`.

* ``analysis.modes``: :func:`substruct.analysis.api.modes` (eqs 28-34) on the model's
  :class:`~substruct.analysis.system.ConstrainedSystem` with the case's method, checks, solver
  and tolerance (:class:`~substruct.analysis.system.ModesOptions`), for the model and for each
  variant (some constraint rows left out);
* ``analysis.frf``: :func:`substruct.analysis.api.receptance_sweep` (eqs 11-15) on
  ``Assembly.system`` with :class:`~substruct.analysis.system.SweepOptions`, at the case's
  points,

  .. math::  H[k, i, j] = o_i \, \hat H(\omega_k)\, e_j, \qquad e_j = r(p_j)^T, \; o_i = r(p_i)

  (a unit force at point ``p_j`` is the generalized force ``r(p_j)^T``).

Input the analyses cannot take (:data:`~substruct.analysis.errors.INPUT_ERRORS`: an
:class:`~substruct.analysis.errors.AnalysisInputError`, an inconsistent or empty constraint row)
becomes a :class:`~substruct.case.loader.CaseError` naming the field (exit 2); a check that
disagrees beyond the tolerance stays a :class:`~substruct.analysis.errors.CheckError` (exit 1),
its message closed by the case field that sets the tolerance.  Any other exception, a plain
``ValueError`` included, is left to be reported as an internal error: a bug is never passed off
as bad input.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp

from substruct.analysis.api import (
    ConstrainedSystem,
    ModesOptions,
    Progress,
    SweepOptions,
    modes,
    receptance_sweep,
)
from substruct.analysis.errors import INPUT_ERRORS, CheckError
from substruct.analysis.events import Phase
from substruct.analysis.frf.quantity import as_quantity, quantity_factor
from substruct.analysis.frf.stream import FrequencySink, SweepTap
from substruct.analysis.results import Modes, Receptance
from substruct.assembly.stack import Assembly
from substruct.builder.model import Model
from substruct.case.fields import gigabytes
from substruct.case.loader import Case, FiniteElements
from substruct.run.result import ModelInfo

if TYPE_CHECKING:  # the modal and AMLS routes' modules are imported by the cases that use them
    from substruct.analysis.frf.modal import ModalOptions
    from substruct.linalg.task_runner import TaskRunner

__all__ = ["Progress", "modes_result", "frf_result", "rows_receptance", "in_place_quantity",
           "model_info",
           "check_dense_sizes",
           "check_dense_modes", "min_size", "DENSE_MODES_LIMIT", "DENSE_FRF_LIMIT"]

#: Largest number of stacked coordinates for the dense coupled eigenproblem.
DENSE_MODES_LIMIT = 2500
#: Largest number of coordinates for the dense null-space receptance check.
DENSE_FRF_LIMIT = 4000


def modes_result(case: Case, asm: Assembly, A: sp.csr_array, loc: tuple,
                 what: str = "modes", events: Phase | None = None,
                 tasks: TaskRunner | None = None) -> Modes:
    """The coupled modes of ``asm`` under the rows ``A`` as ``case.analysis.modes`` asks
    (:func:`substruct.analysis.api.modes`); ``events`` is told as each eigen solve starts;
    ``tasks`` runs the blocks of an AMLS reduction (``None``: in this process).

    Raises:
        CaseError: at ``loc``, for input the solver cannot take.
        CheckError: a check disagrees by more than ``analysis.modes.tolerance``.
    """
    spec = case.analysis.modes
    if spec is None:
        raise TypeError(f"case {case.name!r} asks for no modes")
    try:
        system = ConstrainedSystem.of(asm.M, asm.C, asm.K, A,
                                      coordinate_labels=asm.dof_labels or None)
        options = ModesOptions(method=spec.method, checks=spec.check, solver=spec.solver,
                               tolerance=spec.tolerance, what=what, events=events)
        if spec.solver == "amls":
            return _amls(case, system, options, tasks)
        if spec.band is None:
            return modes(system, spec.count, options=options)
        return _in_band(case, system, options)
    except INPUT_ERRORS as err:
        raise case.error(loc, " ".join(str(err).split())) from None
    except CheckError as err:
        raise CheckError(f"{err}; to accept it, raise analysis.modes.tolerance") from None


def _amls(case: Case, system: ConstrainedSystem, options: ModesOptions,
          tasks: TaskRunner | None = None) -> Modes:
    """``solver: amls``: with a band that has a ``max``, every mode below it by one AMLS run,
    then those in the band, ``count`` at most; otherwise the lowest ``count`` (a band's
    ``min`` by :func:`_in_band`)."""
    from substruct.analysis.modes.amls import AmlsOptions

    spec = case.analysis.modes
    assert spec is not None
    block = spec.amls
    top = spec.band.max if spec.band is not None else None
    amls = AmlsOptions(**({} if block is None else block.model_dump()), omega_max=top,
                       tasks=tasks)
    options = dataclasses.replace(options, amls=amls)
    if spec.band is None:
        return modes(system, spec.count, options=options)
    if top is None:
        return _in_band(case, system, options)
    res = modes(system, None, options=options)
    idx = np.flatnonzero(res.omega >= spec.band.min * (1 - 1e-12))[:spec.count]
    return dataclasses.replace(res, eigenvalues=res.eigenvalues[idx], omega=res.omega[idx],
                               damping_ratio=res.damping_ratio[idx], shapes=res.shapes[:, idx],
                               residual=res.residual[idx])


def _in_band(case: Case, system: ConstrainedSystem, options: ModesOptions) -> Modes:
    """The modes in ``analysis.modes.band``, ``count`` at most: the lowest ``k`` modes are
    computed with ``k`` doubling (from ``min(count, 16)``) until ``count`` of them are in the
    band, one is above it, or every coordinate has its mode; then those in the band are kept
    (a relative margin of 1e-12 at its ends)."""
    spec = case.analysis.modes
    assert spec is not None and spec.band is not None
    lo, hi = spec.band.min, spec.band.max
    top = system.K.shape[0]
    k = min(spec.count, 16, top)
    while True:
        res = modes(system, k, options=options)
        keep = res.omega >= lo * (1 - 1e-12)
        if hi is not None:
            keep &= res.omega <= hi * (1 + 1e-12)
        above = hi is not None and bool(np.any(res.omega > hi * (1 + 1e-12)))
        if keep.sum() >= spec.count or above or len(res) < k or k >= top:
            break
        k = min(2 * k, top)
    idx = np.flatnonzero(keep)[:spec.count]
    return dataclasses.replace(res, eigenvalues=res.eigenvalues[idx], omega=res.omega[idx],
                               damping_ratio=res.damping_ratio[idx], shapes=res.shapes[:, idx],
                               residual=res.residual[idx])


def min_size(case: Case) -> int:
    """A lower bound of the number of stacked coordinates, known before building."""
    total = 0
    for spec in case.substructures:
        n = spec.n_dof() if hasattr(spec, "n_dof") else None
        disc = getattr(spec, "discretization", None)
        if n is None and isinstance(disc, FiniteElements):
            n = max(disc.elements * disc.order - 1, 1)  # nodes less at most two supports
        total += n or 0
    return total


def check_dense_sizes(case: Case, N: int, at_least: bool = True) -> None:
    """Refuse dense eigenproblems (and dense receptance checks) too large for the memory.

    ``solver: auto`` is dense only up to :data:`substruct.analysis.api.SPARSE_ABOVE`
    coordinates, so only ``solver: dense`` can ask for a dense eigenproblem this large.
    """
    size = f"at least {N}" if at_least else f"{N}"
    modes_spec = case.analysis.modes
    if modes_spec is not None and N > DENSE_MODES_LIMIT and modes_spec.solver == "dense":
        need = 8 * 8 * (2 * N) ** 2  # dense state-space pencil, eigenvectors, workspace
        raise case.error(("analysis", "modes"), f"the coupled eigenproblem is dense and the "
                         f"model has {size} coordinates (about {gigabytes(need)}); at most "
                         f"{DENSE_MODES_LIMIT}: reduce the large substructures "
                         f"(reduce: {{modes: ...}}), or solver: sparse", N)
    frf = case.analysis.frf
    if frf is not None and "null-space" in (frf.method, *frf.check) and N > DENSE_FRF_LIMIT:
        raise case.error(("analysis", "frf", "check"), f"the null-space receptance is dense: "
                         f"{size} coordinates need about {gigabytes(16 * N * N * 3)}; at most "
                         f"{DENSE_FRF_LIMIT}: use kkt", N)


def check_dense_modes(case: Case, asm: Assembly) -> None:
    """:func:`check_dense_sizes` with the exact number of coordinates of the built model."""
    check_dense_sizes(case, asm.n_dof, at_least=False)


def frf_result(case: Case, model: Model, progress: Progress | None,
               sink: FrequencySink | None = None, tasks: TaskRunner | None = None
               ) -> Receptance:
    """The receptances ``case.analysis.frf`` asks for, at its points
    (:func:`substruct.analysis.api.receptance_sweep`).

    Given a ``sink``, the receptances go to it a block of frequencies at a time as they are
    computed, already as ``analysis.frf.quantity`` (a
    :class:`~substruct.analysis.frf.stream.SweepTap` converts each block after keeping the
    checked frequencies), and the result's ``H`` is their summary and selections.  The tree
    levels of an AMLS basis (``modal.solver: amls``) run through ``tasks``
    (:class:`~substruct.linalg.task_runner.TaskRunner`; ``None``: in this process).

    Raises:
        CaseError: at ``analysis.frf``, for input the solver cannot take (an inconsistent
            force-tied constraint, a singular system).
        CheckError: a check disagrees by more than ``analysis.frf.tolerance``.
    """
    spec = case.analysis.frf
    if spec is None:
        raise TypeError(f"case {case.name!r} asks for no receptances")
    asm = model.assembly
    inputs = sp.csc_array(asm.rows([model.points[p] for p in spec.inputs]).T)
    outputs = asm.rows([model.points[p] for p in spec.outputs])
    try:
        options = SweepOptions(method=spec.method, checks=spec.check, tolerance=spec.tolerance,
                               input_names=spec.inputs, output_names=spec.outputs,
                               progress=progress, modal=_modal_options(case, tasks))
        w = spec.omegas()
        if sink is None:
            return in_place_quantity(receptance_sweep(asm.system, w, inputs, outputs,
                                                      options=options), spec.quantity)
        factor = None if spec.quantity == "receptance" else \
            quantity_factor(np.asarray(w, dtype=float), spec.quantity)
        tap = SweepTap(sink, None if factor is None else
                       lambda start, count: factor[start:start + count])
        res = receptance_sweep(asm.system, w, inputs, outputs, options=options, sink=tap)
        return dataclasses.replace(res, quantity=spec.quantity)
    except INPUT_ERRORS as err:
        raise case.error(("analysis", "frf"), " ".join(str(err).split())) from None
    except CheckError as err:
        raise CheckError(f"{err}; to accept it, raise analysis.frf.tolerance") from None


def _modal_options(case: Case, tasks: TaskRunner | None) -> ModalOptions:
    from substruct.run.modal_options import modal_options

    spec = case.analysis.frf
    assert spec is not None
    return modal_options(spec.modal, tasks)


def rows_receptance(case: Case, model: Model, rows: sp.csr_array,
                    omegas: np.ndarray, tasks: TaskRunner | None = None) -> np.ndarray:
    r"""The receptances of the output rows ``rows`` (``m x n``, on the coupled coordinates)
    to the inputs of ``case.analysis.frf`` at ``omegas``, by its method and without checks:

    .. math::  H_R[k, i, j] = \text{rows}_i \, \hat H(\omega_k)\, e_j

    (a second sweep at the frequencies of the first; ``n_omega x m x n_inputs``, complex),
    an AMLS basis's tree levels run through ``tasks`` (``None``: in this process).

    Raises:
        CaseError: at ``analysis.frf``, for input the solver cannot take.
    """
    spec = case.analysis.frf
    if spec is None:
        raise TypeError(f"case {case.name!r} asks for no receptances")
    asm = model.assembly
    inputs = sp.csc_array(asm.rows([model.points[p] for p in spec.inputs]).T)
    try:
        options = SweepOptions(method=spec.method, input_names=spec.inputs,
                               what="frf (recovery)", modal=_modal_options(case, tasks))
        res = receptance_sweep(asm.system, np.asarray(omegas, dtype=float), inputs,
                               sp.csr_array(rows), options=options)
    except INPUT_ERRORS as err:
        raise case.error(("analysis", "frf"), " ".join(str(err).split())) from None
    return np.asarray(res.H)


def in_place_quantity(frf: Receptance, quantity: str) -> Receptance:
    r"""``frf`` (receptances just computed, held nowhere else) as ``quantity``:
    :func:`~substruct.analysis.frf.quantity.as_quantity` with ``H`` multiplied in place,

    .. math::  H[k] \leftarrow (i \omega_k)^p H[k]

    the same numbers without a second array of the size of the output (2.56 GB for 1,000
    frequencies x 400 x 400).  A read-only ``H`` is converted by ``as_quantity``.

    Raises:
        ValueError: an unknown quantity, or ``frf`` already converted.
    """
    if quantity == "receptance" or not (isinstance(frf.H, np.ndarray) and
                                        frf.H.flags.writeable and frf.H.dtype.kind == "c"):
        return as_quantity(frf, quantity)
    if frf.quantity != "receptance":
        raise ValueError(f"the responses are already {frf.quantity}")
    np.multiply(frf.H, quantity_factor(frf.omega, quantity)[:, None, None], out=frf.H)
    return dataclasses.replace(frf, quantity=quantity)


def model_info(model: Model) -> ModelInfo:
    """The assembled model as plain data (:class:`~substruct.run.result.ModelInfo`)."""
    asm = model.assembly
    return ModelInfo(dof_labels=list(asm.dof_labels),
                     substructure_names=[s.name for s in asm.substructures],
                     substructure_kinds=[s.kind for s in asm.substructures],
                     offsets=np.asarray(asm.offsets), A=sp.csr_array(asm.A), b=np.asarray(asm.b),
                     R=sp.csr_array(asm.R), constraint_labels=list(asm.constraint_labels),
                     drawings=model.drawings)
