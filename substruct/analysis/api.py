r"""The front door from an assembled model to results: coupled modes and receptances, each with
its cross-checks.

:func:`modes` (eqs 23-34) and the one choice of its strategy, :func:`choose_solver`, live in
:mod:`substruct.analysis.modes.eigen` and are named here so that every analysis is reached from one
module.

:func:`receptance_sweep` computes the receptances (eq 15)

.. math::  H[k, i, j] = o_i\, \hat H(\omega_k)\, e_j, \qquad \hat H = G^{-1} D,

by the main formulation and the checks (:func:`substruct.analysis.formulations.coupling.receptance`) and
returns one :class:`~substruct.analysis.results.Receptance`, with the constraint residual
:math:`\max |A \hat q - R F| / \max |H|`.

Both fail with :class:`~substruct.analysis.errors.CheckError` when a check disagrees with the
main formulation by more than ``tolerance`` (:func:`substruct.analysis.checks.require_agreement`),
and with :class:`~substruct.analysis.errors.AnalysisInputError` (or another of
:data:`~substruct.analysis.errors.INPUT_ERRORS`) on input they cannot analyse.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Sequence, cast

import numpy as np
import scipy.sparse as sp

from substruct.analysis.checks import (
    check_methods,
    compliance_scale,
    holds_every_coordinate,
    receptance_difference,
    require_agreement,
)
from substruct.analysis.formulations.coupling import receptance_of
from substruct.analysis.modes.eigen import (
    SOLVERS,
    SPARSE_ABOVE,
    SolverChoice,
    choose_solver,
    modes,
)
from substruct.analysis.frf.stream import FrequencySink, SweepTap, feed
from substruct.analysis.results import DEFAULT_TOLERANCE, Receptance
from substruct.analysis.system import (
    ConstrainedSystem,
    ModesOptions,
    Progress,
    SweepOptions,
)
from substruct.linalg.system import Matrix
from substruct.vocabulary import GENERALIZED_INVERSE

if TYPE_CHECKING:  # the modal sweep's module is imported by the sweeps that need it
    from substruct.analysis.frf.modal import ModalOptions

__all__ = [
    "ConstrainedSystem",
    "ModesOptions",
    "Progress",
    "SweepOptions",
    "SOLVERS",
    "SPARSE_ABOVE",
    "SolverChoice",
    "EXACT_ZERO",
    "choose_solver",
    "modes",
    "receptance_sweep",
    "system_receptance_sweep",
]


#: Frequencies per receptance call in a sweep (progress is reported between calls).
CHUNK = 10
#: Key of :attr:`Receptance.agreement` for a model whose constraints hold every coordinate:
#: ``max |H| / h0`` of the main formulation against the exact zero
#: (:func:`substruct.analysis.checks.compliance_scale`); the receptances are then reported as
#: exactly zero.
EXACT_ZERO = "exact-zero"



def _sweep(system: ConstrainedSystem, omegas: np.ndarray, method: str, inputs: sp.sparray,
           outputs: sp.sparray, progress: Progress | None) -> np.ndarray:
    out = []
    total = len(omegas)
    for start in range(0, total, CHUNK):
        w = omegas[start:start + CHUNK]
        out.append(receptance_of(system, w, method, inputs, outputs))
        if progress is not None:
            progress(min(start + CHUNK, total), total, method)
    if not out:
        return np.zeros((0, outputs.shape[0], inputs.shape[1]), dtype=complex)
    return np.concatenate(out, axis=0)


def receptance_sweep(system: ConstrainedSystem | Matrix, *args: Any,
                     options: SweepOptions | None = None, **kwargs: Any) -> Receptance:
    r"""Receptances of a constrained system at a frequency grid, with their cross-checks and
    constraint residual (eqs 11-15).

    The call is ``receptance_sweep(system, omegas, inputs, outputs, *, options=None)`` with a
    :class:`~substruct.linalg.system.ConstrainedSystem` and
    :class:`~substruct.analysis.system.SweepOptions` (:func:`system_receptance_sweep`, which
    see).

    The compatibility form ``receptance_sweep(K, M, C, A, omegas, inputs, outputs, *, R=None,
    method=..., checks=(), tolerance=1e-6, input_names=None, output_names=None,
    constraint_labels=None, progress=None, what="frf", modal=None, sink=None)`` takes the
    matrices (in the order ``K, M``) and the options loose, as before the system type: it
    builds both and calls :func:`system_receptance_sweep`.

    Examples
    --------
    One unit mass on a unit spring, a second coordinate held by ``q_2 = 0``: at
    ``omega = 1/2`` the receptance is ``1 / (1 - 1/4)``, by eq 15 and checked by KKT.

    >>> import numpy as np
    >>> from substruct.analysis.api import receptance_sweep
    >>> from substruct.analysis.system import ConstrainedSystem, SweepOptions
    >>> s = ConstrainedSystem.of(np.eye(2), None, np.eye(2), [[0.0, 1.0]])
    >>> E = np.array([[1.0], [0.0]])
    >>> res = receptance_sweep(s, [0.5], E, E.T, options=SweepOptions(checks=["kkt"]))
    >>> np.round(res.H.real, 6)
    array([[[1.333333]]])
    >>> bool(res.agreement["kkt"] < 1e-9), bool(res.constraint_residual < 1e-9)
    (True, True)
    """
    if isinstance(system, ConstrainedSystem):
        return system_receptance_sweep(system, *args, options=options, **kwargs)
    if options is not None:
        raise TypeError("receptance_sweep(): options= goes with a ConstrainedSystem; the matrix "
                        "form takes the options as keywords")
    return _compatible_sweep(system, *args, **kwargs)


def _compatible_sweep(K: Matrix, M: Matrix, C: Matrix | None, A: Matrix | None,
                      omegas: Sequence[float] | np.ndarray, inputs: Matrix, outputs: Matrix, *,
                      R: Matrix | None = None, method: str = GENERALIZED_INVERSE,
                      checks: Sequence[str] = (), tolerance: float = DEFAULT_TOLERANCE,
                      input_names: Sequence[str] | None = None,
                      output_names: Sequence[str] | None = None,
                      constraint_labels: Sequence[str] | None = None,
                      progress: Progress | None = None, what: str = "frf",
                      modal: ModalOptions | None = None,
                      sink: FrequencySink | None = None) -> Receptance:
    """The loose-argument form of :func:`receptance_sweep`: options, system, then the call."""
    options = SweepOptions(method=method, checks=checks, tolerance=tolerance,
                           input_names=input_names, output_names=output_names,
                           progress=progress, what=what, modal=modal)
    system = ConstrainedSystem.of(M, C, K, A, R=R, constraint_labels=constraint_labels)
    return system_receptance_sweep(system, omegas, inputs, outputs, options=options, sink=sink)


def system_receptance_sweep(system: ConstrainedSystem, omegas: Sequence[float] | np.ndarray,
                            inputs: Matrix, outputs: Matrix, *,
                            options: SweepOptions | None = None,
                            sink: FrequencySink | None = None) -> Receptance:
    r"""Receptances of a system under ``A q = R F`` at a frequency grid, with their
    cross-checks and constraint residual (eqs 11-15).

    .. math::  H[k, i, j] = o_i\, \hat H(\omega_k)\, e_j, \qquad
               \text{residual} = \frac{\max_k |A \hat H(\omega_k) E - R E|}{\max |H|}

    Args:
        system: ``K``, ``M``, ``C``, the rows ``A`` of any rank and ``R``, which ties the
            constraint to the force (:class:`~substruct.linalg.system.ConstrainedSystem`; its
            constraint labels name the rows in error messages).
        omegas: circular frequencies (rad/s).
        inputs: ``n x p`` generalized forces ``e_j`` (columns).
        outputs: ``q x n`` output rows ``o_i``.
        options: (:class:`~substruct.analysis.system.SweepOptions`, its defaults if ``None``)
            ``method``: the main formulation (``generalized-inverse``, ``null-space``, ``kkt``),
            ``"modal"`` (modal superposition with a residual flexibility, checked by the direct
            ``checks`` at a few frequencies:
            :func:`substruct.analysis.frf.modal.modal_receptance_sweep`) or ``"auto"``
            (:func:`substruct.analysis.frf.modal.frf_method`).
            ``checks``: check formulations (the main one and repeats are skipped).
            ``tolerance``: the largest ``max |H_check - H| / max |H|`` a check may have (when the
            constraints hold every coordinate, ``H`` is exactly zero and the figures are
            ``max |H_check - H| / h0``, with ``h0`` the compliance scale
            :func:`substruct.analysis.checks.compliance_scale`; the main formulation is then
            checked against zero too, as ``agreement["exact-zero"]``).
            ``input_names``, ``output_names``: names of the inputs and outputs (default
            ``"1"``, ...).  ``progress``: called as ``progress(done, total, method)`` during
            the sweeps.  ``what``: how the analysis is named in error messages.  ``modal``:
            options of the modal sweep (:class:`~substruct.analysis.frf.modal.ModalOptions`).
        sink: where the receptances go, a block of frequencies at a time
            (:class:`~substruct.analysis.frf.stream.FrequencySink`, wrapped in a
            :class:`~substruct.analysis.frf.stream.SweepTap` unless it is one); the result's
            ``H`` is then a :class:`~substruct.analysis.frf.stream.StreamedArray` (its summary
            and selections).  The sparse production sweep and the modal sweep compute block by
            block and never hold the whole output; the other formulations send theirs once
            computed.  The checks run on the same numbers either way.

    Raises:
        CheckError: a check disagrees by more than ``tolerance``.
        ConstraintError: a redundant constraint row with an inconsistent ``R``.
        AnalysisInputError: a singular system (e.g. eq 15 at ``omega = 0``).
    """
    from substruct.analysis.frf.modal import frf_method, modal_receptance_sweep
    from substruct.analysis.frf.production import (  # the sweeps' modules: when one runs
        PRODUCTION_SWEEP,
        constraint_residual,
        production_sweep,
        production_sweep_applies,
        sweep_checks,
    )

    opts = options if options is not None else SweepOptions()
    K, M, C, A, R = system.K, system.M, system.C, system.A, system.R
    method = frf_method(opts.method, system.n, R)
    held = holds_every_coordinate(A, R, system.n)
    if held and method == "modal":  # no mode to sum: the direct form gives the exact zero
        method = GENERALIZED_INVERSE
    tap = sink if isinstance(sink, SweepTap) or sink is None else SweepTap(sink)
    if method == "modal":
        return modal_receptance_sweep(system, omegas, inputs, outputs, options=opts, sink=tap)
    checks, tolerance, progress, what = opts.checks, opts.tolerance, opts.progress, opts.what
    n = system.n
    forces = sp.csc_array(inputs, dtype=float)
    out_rows = sp.csr_array(outputs, dtype=float)
    w = np.atleast_1d(np.asarray(omegas, dtype=float))
    m = system.m
    k_out = out_rows.shape[0]
    # no free coordinate: the exact H is zero, every figure is taken against the compliance
    # scale h0 of the problem (analysis/checks.py), the main formulation's rounding included
    floor = compliance_scale(K, M, C, w, forces, out_rows) if held else 0.0
    production = production_sweep_applies(n, R, method) and not held
    if production:  # the outputs only; the constraint residual at the checked frequencies
        H, checked = production_sweep(K, M, C, A, w, forces, out_rows, progress, tap)
        residual = constraint_residual(K, M, C, A, w, forces, checked)
    else:
        # the residual's rows are the system's, equilibrated with their R: its figure is that
        # of D A
        rows = sp.csr_array(sp.vstack([out_rows, A])) if m else out_rows
        full = _sweep(system, w, method, forces, rows, progress)
        scale = max(_largest(full[:, :k_out]), floor)
        residual = 0.0
        if m and full.size:
            RE = (R @ forces).toarray() if R is not None else np.zeros((m, forces.shape[1]))
            residual = float(np.abs(full[:, k_out:] - RE[None]).max() / scale)
        H = _leading_rows(full, k_out)
    agreement = {}
    if production:  # checked at a few frequencies (analysis/frf/production.py)
        agreement = sweep_checks(system, w, forces, out_rows, checked, method, checks)
        method = PRODUCTION_SWEEP
    for check in [] if production else check_methods(method, checks):
        assert H is not None  # computed whole off the production path
        Hc = _sweep(system, w, check, forces, out_rows, progress)
        agreement[check] = receptance_difference(Hc, H, floor)
    if held and H is not None:  # the main formulation against the exact zero
        agreement[EXACT_ZERO] = max((float(np.abs(Hk).max(initial=0.0)) for Hk in H),
                                    default=0.0) / max(floor, 1e-300)
    require_agreement(what, method, agreement, tolerance)
    if held and H is not None:
        H[...] = 0.0
    if tap is not None:
        if H is not None:  # computed whole: sent once checked
            feed(tap, H)
        H = cast(np.ndarray, tap.array())  # its summary and selections (a StreamedArray)
    assert H is not None
    names_in = list(opts.input_names) if opts.input_names is not None else \
        [str(j + 1) for j in range(forces.shape[1])]
    names_out = list(opts.output_names) if opts.output_names is not None else \
        [str(i + 1) for i in range(k_out)]
    return Receptance(method=method, omega=w, H=H, inputs=names_in, outputs=names_out,
                      agreement=agreement, constraint_residual=residual,
                      tolerance=float(tolerance))


def _largest(H: np.ndarray) -> float:
    """``max |H|`` a frequency at a time: no temporary of the size of ``H`` (1,000 x 400 x 400:
    1.3 GB); at least 1e-300."""
    return max(max((float(np.abs(Hk).max(initial=0.0)) for Hk in H), default=0.0), 1e-300)


def _leading_rows(full: np.ndarray, rows: int) -> np.ndarray:
    """``full[:, :rows]`` as a C-contiguous array in ``full``'s own memory (each frequency's
    block moved down in place, no copy of the whole), so that it is written to HDF5 and sent
    between processes without a copy; ``full`` is overwritten."""
    if rows == full.shape[1] or not full.flags.c_contiguous:
        return full if rows == full.shape[1] else np.ascontiguousarray(full[:, :rows])
    flat = full.reshape(-1)
    block = rows * full.shape[2]
    for k in range(full.shape[0]):  # moving down: a block never overwrites one still unread
        flat[k * block:(k + 1) * block] = full[k, :rows].reshape(-1)
    return flat[:full.shape[0] * block].reshape(full.shape[0], rows, full.shape[2])
