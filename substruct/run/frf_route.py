r"""The analysis route of a case with FRF substructures (``type: frf``): the model's
receptances at the coordinates the coupling needs, then LM-FBS with the FRF parts,
for the outputs and inputs asked for only.

.. math::  Y_c = Y - Y B^T (B Y B^T)^{-1} B Y, \qquad
           Y = \operatorname{diag}(Y_{model}, Y_{frf_1}, \dots)  \qquad \text{(eq 15 with } A = B)

``Y_model`` is :func:`substruct.run.analyses.frf_result` of the finite-element part of the case
(:func:`substruct.builder.frf_parts.split_frf_case`: direct or modal, with its own checks),
square on the model's points joined to the FRF parts and asked for; an assembly of FRF parts
only has none, and its parts are put on the grid of ``analysis.frf`` (equal, or interpolated
with ``interpolate: linear``).  A part with ``decouple: true`` enters as ``-Y_R`` (decoupling).
The coupled receptance
(:func:`substruct.analysis.frf.coupling_selected.couple_selected`: only the outputs x inputs
asked for and the interface are formed) is checked by the generalized-inverse form at a sample
of frequencies (every frequency of grids up to 32, else 32 spread evenly, first and last
included); its ``constraint_residual`` is the interface compatibility of the coupled responses
to the inputs asked for, at every frequency, :math:`\max |B Y_c[:, i]| / \max |Y_c|` (over
the whole coupled receptance when every coordinate is an input).  A decoupling forms the whole
coupled receptance (its generalized inverse is the method) and takes the outputs x inputs
once.

A singular interface receptance (connections that repeat each other) is bad input, exit 2
(the coupling's :class:`~substruct.analysis.errors.AnalysisInputError`; the frequency is found
by :func:`singular_interface`); any other error of the coupling is an internal error.
"""

from __future__ import annotations

import dataclasses
from typing import Callable

import numpy as np

from substruct.analysis.api import Progress
from substruct.analysis.checks import require_agreement
from substruct.analysis.errors import AnalysisInputError, CheckError
from substruct.analysis.frf.coupling import (
    boolean_rows,
    common_grid,
    generalized_inverse_fbs,
    stack,
)
from substruct.analysis.frf.coupling_selected import couple_selected
from substruct.analysis.frf.quantity import as_quantity, quantity_factor
from substruct.analysis.frf.stream import FrequencySink, StreamedArray, SweepTap
from substruct.analysis.results import Receptance
from substruct.builder.frf_parts import MODEL_PART, FrfPart, split_frf_case
from substruct.builder.model import Model
from substruct.case.fields import parse_point
from substruct.case.loader import Case
from substruct.linalg.task_runner import TaskRunner
from substruct.run.analyses import frf_result
from substruct.vocabulary import GENERALIZED_INVERSE

__all__ = ["coupled_frf_result", "decouple_parts", "singular_interface", "ANALYSIS_GRID"]

#: The name of the empty part that carries the analysis grid of an FRF-only assembly (the
#: grid the FRF parts are compared with, or interpolated onto).
ANALYSIS_GRID = "analysis.frf.omega"


def decouple_parts(parts: list[FrfPart], pairs: list[tuple[str, str]]
                   ) -> tuple[np.ndarray, np.ndarray, list[str]]:
    r"""Coupling with a removed part (``decouple: true``, its receptance already negated):

    .. math::  Y_c = Y - Y B^T (B Y B^T)^{+} B Y, \qquad Y = \operatorname{diag}(\dots, -Y_R)

    With the extended interface (every coordinate of ``R`` joined) ``B Y B^T`` has the rank
    of the true interface only, so the generalized inverse is the method, not the check (the
    LM-FBS solve of a rank-deficient matrix is not an answer); the compatibility residual is
    what is reported.  Returns ``(omega, Y_c, labels)``.
    """
    w, same = common_grid(parts)
    Y, labels = stack(same)
    return w, generalized_inverse_fbs(Y, boolean_rows(labels, pairs)), labels


def singular_interface(parts: list[FrfPart], pairs: list[tuple[str, str]]) -> float | None:
    r"""The first frequency at which the interface receptance :math:`B Y B^T` of the coupling
    (eq 15 with ``A = B``) is singular (its LU factorization breaks down, as in
    :func:`~substruct.analysis.frf.coupling.lm_fbs`), or ``None`` if it is regular at every
    frequency.  The grids and labels were checked when the case was split
    (:func:`~substruct.builder.frf_parts.split_frf_case`)."""
    w, same = common_grid(parts)
    Y, labels = stack(same)
    B = boolean_rows(labels, pairs)
    for k in range(len(w)):
        try:
            np.linalg.solve(B @ Y[k] @ B.T, np.eye(B.shape[0]))
        except np.linalg.LinAlgError:
            return float(w[k])
    return None


def coupled_frf_result(case: Case, model: Model, progress: Progress | None = None,
                       sink: FrequencySink | None = None, tasks: TaskRunner | None = None
                       ) -> Receptance:
    """The receptances ``case.analysis.frf`` asks for, of the model coupled with the case's
    FRF substructures (``model`` is the finite-element part, built from
    :func:`substruct.builder.frf_parts.split_frf_case`'s ``model_case``).

    Given a ``sink`` (a coupling, not a decoupling), the coupled receptances go to it a block
    of frequencies at a time as they are computed and checked, already as
    ``analysis.frf.quantity`` (a :class:`~substruct.analysis.frf.stream.SweepTap` converts
    each block), and the result's ``H`` is their summary and selections
    (:class:`~substruct.analysis.frf.stream.StreamedArray`), as
    :func:`substruct.run.analyses.frf_result` does; the model's AMLS basis (``modal.solver:
    amls``), if any, is reduced through ``tasks`` (``None``: in this process).

    Raises:
        CaseError: grids that differ without ``interpolate: linear``, a singular interface.
        CheckError: the generalized-inverse form disagrees by more than
            ``analysis.frf.tolerance`` (or a check of the model's receptances does).
    """
    spec = case.analysis.frf
    if spec is None:
        raise TypeError(f"case {case.name!r} asks for no receptances")
    split = split_frf_case(case)
    checks: dict[str, float] = {}
    if split.model_case is None:  # FRF parts only: the analysis grid is the reference
        w = spec.omegas()
        first = FrfPart(ANALYSIS_GRID, w, [], np.zeros((len(w), 0, 0), dtype=complex))
        fe_method = ""
    else:
        fe = frf_result(split.model_case, model, progress, tasks=tasks)
        first = FrfPart(MODEL_PART, fe.omega, list(split.model_points), fe.H)
        checks.update({f"{MODEL_PART} {k}": v for k, v in fe.agreement.items()})
        fe_method = f" ({MODEL_PART}: {fe.method})"
    frf_names = {p.name for p in split.parts}

    def stacked(point: str) -> str:
        return point if parse_point(point)[0] in frf_names else f"{MODEL_PART}@{point}"

    pairs = [(stacked(a), stacked(b)) for a, b in split.pairs]
    decoupling = any(p.decouple for p in split.parts)
    outputs = [stacked(p) for p in spec.outputs]
    inputs = [stacked(p) for p in spec.inputs]
    if decoupling:
        w, Yc, labels = decouple_parts([first, *split.parts], pairs)
        where = {lab: i for i, lab in enumerate(labels)}
        rows = np.array([where[p] for p in outputs], dtype=int)
        cols = np.array([where[p] for p in inputs], dtype=int)
        H: np.ndarray | StreamedArray | None = Yc[:, rows[:, None], cols[None, :]]
        scale = max(float(np.abs(Yc).max(initial=0.0)), 1e-300)
        B = boolean_rows(labels, pairs)
        residual = float(np.abs(B @ Yc).max(initial=0.0) / scale) if len(pairs) else 0.0
        del Yc
    else:
        try:
            tap = None if sink is None else SweepTap(sink, _factor(first.omega, spec.quantity))
            got = couple_selected([first, *split.parts], pairs, outputs, inputs, sink=tap)
        except AnalysisInputError:  # the interface receptance is singular
            at = singular_interface([first, *split.parts], pairs)
            at_text = "" if at is None else f" at omega = {at:g} rad/s"
            raise case.error(("connections",), f"the interface receptance B Y B^T is singular"
                             f"{at_text}: connections that repeat each other, or "
                             f"receptances of zero at the interface", [list(p) for p in split.pairs]
                             ) from None
        w, residual, agreement = got.omega, got.residual, got.agreement
        H = tap.array() if tap is not None else got.H
        checks = {GENERALIZED_INVERSE: agreement, **checks}
        try:
            require_agreement("frf (lm-fbs)", "lm-fbs", {GENERALIZED_INVERSE: agreement},
                              spec.tolerance)
        except CheckError as err:
            raise CheckError(f"{err}; to accept it, raise analysis.frf.tolerance") from None
    how = "generalized-inverse decoupling" if decoupling else "lm-fbs"
    coupled = Receptance(method=f"{how}{fe_method}", omega=w, H=H,  # type: ignore[arg-type]
                         inputs=list(spec.inputs), outputs=list(spec.outputs), agreement=checks,
                         constraint_residual=residual, tolerance=spec.tolerance)
    if not decoupling and sink is not None:  # the tap converted each block
        return dataclasses.replace(coupled, quantity=spec.quantity)
    return as_quantity(coupled, spec.quantity)


def _factor(w: np.ndarray, quantity: str) -> Callable[[int, int], np.ndarray] | None:
    """The tap's factor a block: ``(i omega)^p`` of its frequencies, or ``None`` for
    receptances."""
    if quantity == "receptance":
        return None
    f = quantity_factor(np.asarray(w, dtype=float), quantity)
    return lambda start, count: f[start:start + count]
