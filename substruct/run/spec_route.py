r"""The specification analyses of a case: ``analysis.random``, ``analysis.srs`` and the
loss factors of ``analysis.frf``, a thin adapter to :mod:`substruct.analysis.frf.random`,
:mod:`substruct.analysis.frf.base_drive`, :mod:`substruct.analysis.frf.structural` and
:mod:`substruct.analysis.transient.srs`.

* loss factors: ``eta`` on all of ``K``, or ``eta_s`` on the block ``K_s`` of substructure
  ``s``: :math:`Z = \sum_s K_s (1 + i \eta_s) + i \omega C - \omega^2 M`
  (:func:`~substruct.analysis.frf.structural.hysteretic_sweep`);
* random: :math:`S_y = H S_f H^H`, :math:`\sigma = \sqrt{\int S_{ii} df}`, ``H`` the
  receptance to the force points, or per base acceleration
  (:func:`~substruct.analysis.frf.base_drive.base_drive_sweep`, ``A q = E g``), times
  :math:`(i \omega)^p` for velocity (``p = 1``) or acceleration (``p = 2``); the input PSDs are
  log-log interpolated (:func:`~substruct.analysis.frf.random.interpolate_psd`), several
  forces or several named ``bases`` (one column of ``E`` each) uncorrelated (a diagonal
  :math:`S_f`) or correlated pair by pair by ``cross``
  (:func:`~substruct.case.random_cross.cross_matrix`, checked Hermitian positive semidefinite
  at every frequency); with ``method: modal`` the receptances are summed over the coupled
  modes (:func:`~substruct.analysis.frf.modal.modal_receptance_sweep`, the AMLS basis with
  ``modal.solver: amls``), per base acceleration in relative coordinates
  (:func:`~substruct.analysis.frf.base_modal.modal_base_drive_sweep`);
* srs: Smallwood's filter on each output's absolute acceleration, sampled every recorded step.

Input the analyses cannot take becomes a :class:`~substruct.case.loader.CaseError` naming the
field (exit 2); a check beyond the tolerance stays a
:class:`~substruct.analysis.errors.CheckError` (exit 1).
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
import scipy.sparse as sp

from substruct.analysis.api import Progress, SweepOptions, receptance_sweep
from substruct.analysis.errors import INPUT_ERRORS, CheckError
from substruct.analysis.frf.base_drive import base_drive_sweep
from substruct.analysis.frf.base_modal import modal_base_drive_sweep
from substruct.analysis.frf.psd_resolution import RMS_QUADRATURE_TOLERANCE, quadrature_error
from substruct.analysis.frf.quantity import as_quantity
from substruct.analysis.frf.random import (
    check_spectral_matrix,
    interpolate_psd,
    response_psd,
    rms,
)
from substruct.analysis.frf.structural import LossFactor, hysteretic_sweep
from substruct.analysis.results import Receptance
from substruct.analysis.transient.results import Transient
from substruct.analysis.transient.srs import MAX_FN_DT, srs
from substruct.builder.frf_parts import has_frf_parts
from substruct.builder.model import Model
from substruct.case.spec_analysis import LossFactorSpec
from substruct.case.fields import gigabytes, memory_limit
from substruct.case.loader import Case
from substruct.case.random_cross import cross_matrix
from substruct.linalg.task_runner import TaskRunner
from substruct.run.modal_options import modal_options
from substruct.run.spec_results import RandomResponse, ShockSpectra
from substruct.vocabulary import DERIVATIVE_ORDER

__all__ = ["loss_parts", "loss_frf_result", "loss_rows_receptance", "grounding_column", "base_columns", "sweep_kw",
           "random_result", "check_resolution", "srs_result"]



def loss_parts(case: Case, model: Model, spec: LossFactorSpec, loc: tuple) -> list[LossFactor]:
    r"""The :class:`~substruct.analysis.frf.structural.LossFactor` list of a ``loss_factor``
    field: ``eta`` on all of ``K``, or ``eta_s`` on :math:`K_s = P_s K P_s` (:math:`P_s` the
    0/1 diagonal of substructure ``s``'s stacked coordinates).

    Raises:
        CaseError: a name that is no substructure of the model.
    """
    asm = model.assembly
    if not isinstance(spec, dict):
        return [LossFactor(float(spec), sp.csr_array(asm.K))]
    names = [s.name for s in asm.substructures]
    parts = []
    for name, eta in spec.items():
        if name not in names:
            raise case.error((*loc, name), f"not a substructure of the model (one of "
                             f"{', '.join(names)})", name)
        mask = np.zeros(asm.n_dof)
        mask[asm.block(name)] = 1.0
        P = sp.diags_array(mask)
        parts.append(LossFactor(float(eta), sp.csr_array(P @ sp.csr_array(asm.K) @ P)))
    return parts


def sweep_kw(spec, inputs: Sequence[str], outputs: Sequence[str]) -> dict:
    """The keywords of a receptance sweep: a spec's ``method``, ``check`` and ``tolerance``,
    and the input and output names."""
    return dict(method=spec.method, checks=spec.check, tolerance=spec.tolerance,
                input_names=list(inputs), output_names=list(outputs))


def loss_frf_result(case: Case, model: Model, progress: Progress | None = None) -> Receptance:
    """The receptances of ``analysis.frf`` with its ``loss_factor``
    (:func:`~substruct.analysis.frf.structural.hysteretic_sweep`, one frequency at a time).

    Raises:
        CaseError: FRF substructures in the case, an unknown substructure, a frequency <= 0.
        CheckError: a check beyond ``analysis.frf.tolerance``.
    """
    spec = case.analysis.frf
    if spec is None or spec.loss_factor is None:
        raise TypeError(f"case {case.name!r} asks for no receptances with a loss factor")
    loc = ("analysis", "frf", "loss_factor")
    if has_frf_parts(case):
        raise case.error(loc, "not taken with FRF substructures (type: frf), whose "
                         "receptances are measured as they are", spec.loss_factor)
    asm = model.assembly
    parts = loss_parts(case, model, spec.loss_factor, loc)
    inputs = sp.csc_array(asm.rows([model.points[p] for p in spec.inputs]).T)
    outputs = asm.rows([model.points[p] for p in spec.outputs])
    try:
        H = hysteretic_sweep(asm.K, asm.M, asm.C, asm.A, spec.omegas(), inputs, outputs,
                             parts, R=asm.R, **sweep_kw(spec, spec.inputs, spec.outputs))
    except INPUT_ERRORS as err:
        raise case.error(("analysis", "frf"), " ".join(str(err).split())) from None
    except CheckError as err:
        raise CheckError(f"{err}; to accept it, raise analysis.frf.tolerance") from None
    return as_quantity(H, spec.quantity)


def loss_rows_receptance(case: Case, model: Model, rows: sp.csr_array,
                         omegas: np.ndarray) -> np.ndarray:
    r"""The receptances of the output rows ``rows`` (on the coupled coordinates) to the inputs
    of ``analysis.frf`` at ``omegas`` with its ``loss_factor``, without checks (the recovery
    rows of superelements, :func:`substruct.run.recovery.recover_frf`):

    .. math::  H_R[k, :, j] = \text{rows}\,[\textstyle\sum_s K_s (1 + i \eta_s)
               + i\omega_k C - \omega_k^2 M]^{-1}_{A q = R F} e_j

    (``n_omega x m x n_inputs``, complex).

    Raises:
        CaseError: at ``analysis.frf``, for input the solver cannot take.
    """
    spec = case.analysis.frf
    if spec is None or spec.loss_factor is None:
        raise TypeError(f"case {case.name!r} asks for no receptances with a loss factor")
    asm = model.assembly
    parts = loss_parts(case, model, spec.loss_factor, ("analysis", "frf", "loss_factor"))
    inputs = sp.csc_array(asm.rows([model.points[p] for p in spec.inputs]).T)
    try:
        H = hysteretic_sweep(asm.K, asm.M, asm.C, asm.A, np.asarray(omegas, dtype=float),
                             inputs, sp.csr_array(rows), parts, R=asm.R, method=spec.method,
                             input_names=list(spec.inputs), what="frf (recovery)")
    except INPUT_ERRORS as err:
        raise case.error(("analysis", "frf"), " ".join(str(err).split())) from None
    return np.asarray(H.H)


def grounding_column(case: Case, model: Model, points: Sequence[str], loc: tuple
                     ) -> np.ndarray:
    """``E`` (``m x 1``): the coefficient ``c`` of each constraint row ``A_k = c r(p)`` that
    grounds a point ``p`` of ``points`` alone (``c u(p) = c g`` moves it with the base).

    Raises:
        CaseError: a point that no constraint row holds alone.
    """
    asm = model.assembly
    A = sp.csr_array(asm.A)
    E = np.zeros((A.shape[0], 1))
    for i, p in enumerate(points):
        r = asm.row(model.points[p]).toarray().ravel()
        rr = float(r @ r)
        found = False
        for k in np.flatnonzero(np.abs(A @ r) > 0.0):
            row = A[[k]].toarray().ravel()
            c = float(row @ r) / rr if rr else 0.0
            if c and np.abs(row - c * r).max() <= 1e-12 * np.abs(row).max():
                E[k, 0], found = c, True
        if not found:
            raise case.error((*loc, i), "not a grounded support: no active constraint holds "
                             "this point alone (add one with terms: {point: 1})", p)
    return E


def base_columns(case: Case, model: Model, supports: Sequence[Sequence[str]], loc: tuple,
                 single: bool) -> np.ndarray:
    """``E`` (``m x p``) of ``A q = E g``: column ``j`` the :func:`grounding_column` of base
    input ``j``'s supports (``loc`` + ``base`` if ``single``, else ``bases[j]``).

    Raises:
        CaseError: a point that no constraint row holds alone, or a support moved by two
            inputs (each grounded row follows one input).
    """
    where = [(*loc, "base", "at")] if single else \
        [(*loc, "bases", k, "at") for k in range(len(supports))]
    E = np.hstack([grounding_column(case, model, at, w) for at, w in zip(supports, where)])
    shared = np.flatnonzero(np.count_nonzero(E, axis=1) > 1)
    if len(shared):
        j = int(np.flatnonzero(E[shared[0]])[1])
        raise case.error(where[j], "a support that another base input already moves "
                         "(each grounded row follows one input)", list(supports[j]))
    return E


def random_result(case: Case, model: Model, tasks: TaskRunner | None = None
                  ) -> RandomResponse:
    """The response PSDs and RMS values of ``analysis.random`` (module docstring); with
    ``method: modal`` and ``modal.solver: amls``, the AMLS basis's tree levels run through
    ``tasks`` (:class:`~substruct.linalg.task_runner.TaskRunner`; ``None``: in this process).

    Raises:
        CaseError: an unknown substructure of ``loss_factor``, a base point not grounded,
            input the sweep cannot take (a mechanism with the supports held), correlations
            ``cross`` whose cross-spectral matrix is not positive semidefinite.
        CheckError: a check beyond ``analysis.random.tolerance``.
    """
    spec = case.analysis.random
    if spec is None:
        raise TypeError(f"case {case.name!r} asks for no random response")
    loc = ("analysis", "random")
    asm = model.assembly
    f = spec.hertz()
    w = 2 * np.pi * f
    parts = loss_parts(case, model, spec.loss_factor, (*loc, "loss_factor")) \
        if spec.loss_factor is not None else []
    outputs = asm.rows([model.points[p] for p in spec.outputs])
    bases = spec.base_inputs()
    tables = [b.psd for b in bases] if bases else [ld.psd for ld in spec.forces]
    names = spec.input_names()
    columns = [t.columns() for t in tables]
    S_in = np.column_stack([interpolate_psd(list(ft), list(st), f) for ft, st in columns])
    if not np.any(S_in > 0):     # one input of several may be 0 there, not all of them
        where = (*loc, "base", "psd") if spec.base is not None else \
            (*loc, "bases" if bases else "forces", 0, "psd")
        rows = tables[0].rows
        every = "every input PSD is" if len(tables) > 1 else "the input PSD is"
        raise case.error(where, f"{every} 0 on the whole frequency grid ({f[0]:g}-{f[-1]:g} "
                         f"Hz; this table spans {rows[0][0]:g}-{rows[-1][0]:g} Hz)",
                         rows if len(rows) <= 4 else [list(rows[0]), "...", list(rows[-1])])
    S = cross_matrix(names, spec.cross, S_in)
    if spec.cross:
        try:
            check_spectral_matrix(S, f=f)
        except ValueError as err:
            raise case.error((*loc, "cross"), str(err).replace(
                "a cross-spectral", "the input cross-spectral"),
                [list(c.between) for c in spec.cross]) from None
    modal = spec.method == "modal"
    options = SweepOptions(**sweep_kw(spec, names, spec.outputs), what="random",
                           modal=modal_options(spec.modal, tasks) if modal else None)
    try:
        if bases and modal:
            E = base_columns(case, model, [b.at for b in bases], loc, spec.base is not None)
            rec = modal_base_drive_sweep(asm.K, asm.M, asm.C, asm.A, w, E, outputs,
                                         per="acceleration", options=options)
        elif modal:
            inputs = sp.csc_array(asm.rows([model.points[p] for p in names]).T)
            rec = receptance_sweep(asm.system, w, inputs, outputs, options=options)
        elif bases:
            E = base_columns(case, model, [b.at for b in bases], loc, spec.base is not None)
            rec = base_drive_sweep(asm.K, asm.M, asm.C, asm.A, w, E, outputs,
                                   per="acceleration", loss=parts, options=options)
        else:
            inputs = sp.csc_array(asm.rows([model.points[p] for p in names]).T)
            rec = hysteretic_sweep(asm.K, asm.M, asm.C, asm.A, w, inputs, outputs, parts,
                                   R=asm.R, **sweep_kw(spec, names, spec.outputs))
    except INPUT_ERRORS as err:
        raise case.error(loc, " ".join(str(err).split())) from None
    except CheckError as err:
        raise CheckError(f"{err}; to accept it, raise analysis.random.tolerance") from None
    H = rec.H * ((1j * w) ** DERIVATIVE_ORDER[spec.quantity])[:, None, None]
    Sy = response_psd(H, S)
    auto = np.real(np.einsum("kii->ki", Sy))
    check_resolution(f, auto, list(spec.outputs), spec.rms_tolerance)
    return RandomResponse(f=f, outputs=list(spec.outputs), inputs=list(names),
                          quantity=spec.quantity, input_psd=S_in, psd=Sy, rms=rms(f, auto),
                          input_csd=S if spec.cross else None,
                          method=rec.method, agreement=dict(rec.agreement),
                          tolerance=spec.tolerance, base=bool(bases))


def check_resolution(f: np.ndarray, auto: np.ndarray, outputs: list[str],
                     tolerance: float = RMS_QUADRATURE_TOLERANCE) -> None:
    """Refuse RMS values whose grid steps over a resonance: the trapezoid rule's estimated
    error (:func:`~substruct.analysis.frf.psd_resolution.quadrature_error`) above
    ``tolerance`` (``analysis.random.rms_tolerance``) of a mean square.

    Raises:
        CheckError: the first output whose estimate is beyond it.
    """
    for name, q in zip(outputs, quadrature_error(f, auto)):
        if min(q.error, 1.0) > tolerance:      # rms_tolerance: 1 accepts any grid
            err = "more than 100 %" if not np.isfinite(q.error) else f"{q.error:.1e}"
            width = ("a peak stepped over" if not q.gamma > 0 else
                     f"half-power half-width {q.gamma:.3g} Hz")
            raise CheckError(
                f"analysis.random.frequencies: the grid does not resolve the response PSD of "
                f"{name} near {q.f0:.4g} Hz ({width}, grid step {q.step:.3g} Hz there): the "
                f"trapezoid rule's estimated error of its mean square is {err}, beyond "
                f"analysis.random.rms_tolerance = {tolerance:g}; give the grid a step no "
                f"larger than the half-width there (more frequencies, or a list of them), "
                f"or raise rms_tolerance to accept it")


def srs_result(case: Case, tr: Transient) -> ShockSpectra | None:
    """The shock response spectra of ``analysis.srs`` of the transient ``tr``'s absolute output
    accelerations (``None`` if a history is not finite: the run refuses it then).

    Raises:
        CaseError: a frequency above ``0.1 / dt`` of the recorded histories (10 samples a
            period), fewer than two recorded samples, or a lowest frequency whose period of
            residual response would not fit in memory.
    """
    spec = case.analysis.srs
    if spec is None:
        raise TypeError(f"case {case.name!r} asks for no shock response spectrum")
    fn = spec.frequencies.grid()
    if len(tr.t) < 2:
        raise case.error(("analysis", "srs"), "a history of at least two samples is needed",
                         len(tr.t))
    dt = float(tr.t[1] - tr.t[0])
    if float(fn.max()) * dt > MAX_FN_DT:
        raise case.error(("analysis", "srs", "frequencies", "stop"),
                         f"above {MAX_FN_DT / dt:.4g} Hz, 0.1 / the recorded step "
                         f"({dt:g} s: 10 samples a period)", float(fn.max()))
    samples = len(tr.t) + np.ceil(1.0 / (float(fn.min()) * dt))   # + one period of rest
    need = 8.0 * 6 * samples        # the padded history, a filter's output and state
    if need > memory_limit():
        raise case.error(("analysis", "srs", "frequencies", "start"),
                         f"the residual response is followed for one period of the lowest "
                         f"frequency, {samples:.3g} samples of {dt:g} s: about "
                         f"{gigabytes(need)} of memory, more than this machine has available",
                         float(fn.min()))
    outs = list(spec.outputs) if spec.outputs is not None else list(tr.outputs)
    acc = np.asarray(tr.acceleration)
    if not np.all(np.isfinite(acc)):
        return None
    cols = [tr.outputs.index(p) for p in outs]
    spectra = [srs(acc[:, j], dt, fn, spec.zeta()) for j in cols]
    return ShockSpectra(fn=fn, zeta=spec.zeta(), outputs=outs,
                        pos=np.array([s.pos for s in spectra]),
                        neg=np.array([s.neg for s in spectra]),
                        maxabs=np.array([s.maxabs for s in spectra]),
                        pv=np.array([s.pv for s in spectra]), dt=dt)
