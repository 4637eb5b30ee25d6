r"""From a validated case to a :class:`~substruct.run.result.Result`: build, couple, analyse.

Data flows one way (``docs/architecture.md``): :func:`build_model` checks the sizes the
analyses can take and assembles the case (:func:`substruct.builder.model.assemble_case`);
:func:`run_case` computes the coupled modes, the variants (the same assembly with some
constraint rows dropped) and the receptances (:mod:`substruct.run.analyses`).
"""

from __future__ import annotations

from datetime import datetime, timezone
from typing import TYPE_CHECKING, Mapping

import numpy as np
import scipy.sparse as sp

from substruct.analysis.checks import require_finite
from substruct.analysis.events import Phase
from substruct.analysis.frf.stream import FrequencySink
from substruct.analysis.transient.fields import FieldSink
from substruct.analysis.results import Modes
from substruct.builder.model import Model, assemble_case
from substruct.builder.superelements import rigid_body_attrs
from substruct.case.errors import CaseError
from substruct.case.kinds import has_frf_parts
from substruct.case.loader import Case
from substruct.run.analyses import (
    Progress,
    check_dense_modes,
    check_dense_sizes,
    frf_result,
    min_size,
    model_info,
    modes_result,
    rows_receptance,
)
from substruct.run.recovery import (
    recover_frf,
    recover_modes,
    recovery_plan,
    recovery_rows,
    split_recovered,
)
from substruct.run.result import Result
from substruct.substructure import Substructure

if TYPE_CHECKING:
    from substruct.linalg.task_runner import TaskRunner

__all__ = ["Model", "build_model", "run_case", "Progress", "Phase"]


def build_model(case: Case, events: Phase | None = None,
                prebuilt: Mapping[str, Substructure] | None = None) -> Model:
    """Refuse a model too large for the dense analyses it asks for, then assemble it
    (:func:`substruct.builder.model.assemble_case`, with the ``prebuilt`` reduced parts used as
    they are: :func:`substruct.builder.parts.reduced_part`).

    Raises:
        CaseError: a dense analysis too large; ``analysis.modes.count`` larger than the number
            of coordinates of the assembled model (the case layer refuses it when the sizes are
            known from the file; finite elements and solids are sized only once built).
    """
    check_dense_sizes(case, min_size(case))
    if events is not None:
        names = ", ".join(s.name for s in case.substructures)
        events("assembly", f"assembling {case.name}: {len(case.substructures)} "
               f"substructure(s) ({names})", min_size(case))
    # FRF substructures are coupled after the model is built (substruct.run.frf_route)
    if has_frf_parts(case):
        from substruct.builder.frf_parts import assemble_frf_case

        model = assemble_frf_case(case, prebuilt)
    else:
        model = assemble_case(case, prebuilt)
    spec = case.analysis.modes
    if spec is not None and spec.band is None and spec.count > model.assembly.n_dof:
        raise case.error(("analysis", "modes", "count"), f"more modes than the "
                         f"{model.assembly.n_dof} coordinates of the model", spec.count)
    return model


def run_case(case: Case, progress: Progress | None = None, model: Model | None = None,
             events: Phase | None = None, frf_sink: FrequencySink | None = None,
             tasks: TaskRunner | None = None, field_sink: FieldSink | None = None) -> Result:
    """Run the analyses of a case.

    Args:
        case: a validated case (:func:`substruct.load_case`).
        progress: called as ``progress(done, total, label)`` during frequency sweeps.
        model: the case's model if already built (:func:`build_model`).
        events: called as each phase starts, ``events(kind, what, size)``
            (:class:`substruct.analysis.events.Phase`): assembly, each eigen solve, each
            receptance sweep.
        frf_sink: where the receptances of a finite-element model go as they are computed, a
            block of frequencies at a time (:func:`substruct.run.analyses.frf_result`; the
            result file of ``substruct run``); the other receptance routes (FRF parts,
            virtual points, loss factor) compute theirs whole.
        field_sink: where the fields a transient run stores (``field_every``) go as they
            are recorded, a block of instants at a time (the result file of
            ``substruct run``); ``None``: kept whole.
        tasks: where the blocks of an AMLS reduction run (:class:`substruct.linalg.
            task_runner.TaskRunner`; ``None``: in this process): the modes' (``analysis.modes.
            solver: amls``) and the AMLS bases of the modal receptance, the random response
            and the modal transient (``modal.solver: amls``), and a virtual-point Monte
            Carlo study's samples.

    Returns:
        The :class:`~substruct.run.result.Result`: modes (physical modes ascending, spurious
        roots set aside, agreement with the check formulations, the solver that ran),
        variants, receptances, model data.

    Raises:
        CaseError: input that cannot be analysed (see :func:`build_model`; inconsistent
            constraints; a model too large for the dense eigenproblem).
        CheckError: a check formulation disagrees with the main one by more than the
            case's ``tolerance``, or a result holds ``inf`` or ``NaN`` (an overflow); nothing
            is returned, so nothing is written.
    """
    from substruct import __version__

    model = build_model(case, events) if model is None else model
    asm = model.assembly
    check_dense_modes(case, asm)
    if events is not None:
        events("assembly", f"model: {asm.n_dof} coordinates, {asm.A.shape[0]} constraint "
               f"row(s), {sp.csr_array(asm.K).nnz} stiffness nonzeros", asm.n_dof)
    attrs = {"substruct_version": __version__,
             "created": datetime.now(timezone.utc).isoformat(timespec="seconds"),
             "units": case.units, "description": case.description.strip(),
             "case_file": case.source, "overrides": "\n".join(case.overrides),
             **rigid_body_attrs(asm.substructures)}
    result = Result(case_name=case.name, case_yaml=case.text, model=model_info(model),
                    attrs={k: v for k, v in attrs.items() if v})
    if case.output.matrices:
        result.model.matrices = {"M": sp.csr_array(asm.M), "K": sp.csr_array(asm.K),
                                 "C": sp.csr_array(asm.C)}
    plan = recovery_plan(case, asm)
    _refuse_unrecovered_receptances(case, bool(plan))
    spec = case.analysis.modes
    if spec is not None:
        result.modes = modes_result(case, asm, asm.A, ("analysis", "modes"), events=events,
                                    tasks=tasks)
        labels = list(asm.constraint_labels)
        for i, variant in enumerate(spec.variants):
            keep = [r for r, lab in enumerate(labels) if lab not in variant.drop]
            A = sp.csr_array(asm.A[keep]) if keep else sp.csr_array((0, asm.n_dof))
            result.variants[variant.name] = modes_result(
                case, asm, A, ("analysis", "modes", "variants", i),
                what=f"modes (variant {variant.name})", events=events, tasks=tasks)
    frf = case.analysis.frf
    if frf is not None:
        from substruct.run.frf_route import coupled_frf_result  # the routes: when used
        from substruct.run.spec_route import loss_frf_result
        from substruct.run.vp_route import has_virtual_points, vp_frf_result

        # TPA and SEMM read the whole receptance back: the sweep is kept in memory for them
        testlab = case.analysis.tpa is not None or case.analysis.semm is not None
        if events is not None:
            n_omega = len(frf.omega.grid())
            events("sweep", f"receptances: {n_omega} frequencies, {len(frf.outputs)} output(s) "
                   f"x {len(frf.inputs)} input(s), {asm.n_dof} coordinates", n_omega)
        if has_virtual_points(case):
            result.frf, result.virtual_points, result.monte_carlo = vp_frf_result(
                case, model, progress, tasks)
            from substruct.case.channel_geometry import case_channels  # when used
            result.channels = case_channels(case)
        elif frf.loss_factor is not None:
            result.frf = loss_frf_result(case, model, progress)
        else:
            route = coupled_frf_result if has_frf_parts(case) else frf_result
            result.frf = route(case, model, progress, None if testlab else frf_sink, tasks)
        if testlab:
            from substruct.run.testlab_route import semm_result, tpa_result  # when used
            if case.analysis.tpa is not None:
                result.tpa = tpa_result(case, result.frf)
            if case.analysis.semm is not None:
                result.semm = semm_result(case, result.frf)
    result.recovery = plan.empty()
    if plan and result.modes is not None:
        recover_modes(plan, result.modes, result.recovery)
    if plan and frf is not None and not has_virtual_points(case):
        # a second sweep of the recovery rows at the same frequencies (the first streams)
        omegas = np.asarray(frf.omegas(), dtype=float)
        rec_rows = recovery_rows(plan, asm.n_dof)
        if events is not None:
            events("sweep", f"recovered receptances: {len(omegas)} frequencies, "
                   f"{rec_rows.shape[0]} row(s)", len(omegas))
        got: tuple[np.ndarray, np.ndarray] | None
        if has_frf_parts(case):  # coupled by LM-FBS, the rows as outputs of the FE part
            from substruct.run.recovery_frf_parts import frf_parts_rows_receptance

            got = frf_parts_rows_receptance(case, model, rec_rows)
        else:
            from substruct.run.spec_route import loss_rows_receptance

            with np.errstate(over="ignore", invalid="ignore"):
                got = omegas, (rows_receptance(case, model, rec_rows, omegas, tasks)
                               if frf.loss_factor is None else
                               loss_rows_receptance(case, model, rec_rows, omegas))
        if got is not None:
            recover_frf(plan, got[1], got[0], list(frf.inputs), result.recovery)
    if case.analysis.transient is not None:
        from substruct.run.transient_run import transient_result

        if events is not None:
            events("sweep", f"transient: {case.analysis.transient.steps} steps, "
                   f"{asm.n_dof} coordinates", case.analysis.transient.steps)
        rows = recovery_rows(plan, asm.n_dof)
        names = [f"{r.title}@{lab}" for r, (_, _, spec) in zip(result.recovery, plan.entries)
                 for _s in spec.histories() for lab in r.labels]
        # an overflow of the histories is refused below in one line, not warned about first
        with np.errstate(over="ignore", invalid="ignore"):
            tr = transient_result(case, model, rows, names, field_sink, tasks)
        result.transient = split_recovered(plan, tr, len(case.analysis.transient.outputs),
                                           result.recovery) if plan else tr
    # specification analyses (substruct.run.spec_route)
    if case.analysis.random is not None:
        from substruct.run.spec_route import random_result

        result.random = random_result(case, model, tasks)
        require_finite("random", psd=result.random.psd)
    if case.analysis.base_frf is not None:
        from substruct.run.base_frf_route import base_frf_result

        result.base_frf = base_frf_result(case, model)
        require_finite("base_frf", transmissibility=result.base_frf.T)
    if case.analysis.srs is not None and result.transient is not None:
        from substruct.run.spec_route import srs_result

        result.srs = srs_result(case, result.transient)
    _require_finite_result(result)
    return result


def _refuse_unrecovered_receptances(case: Case, recovers: bool) -> None:
    """Refuse, before anything runs, a case whose receptances the recovery cannot follow:
    recovery rows with virtual points or with a part removed by decoupling."""
    frf = case.analysis.frf
    if not recovers or frf is None:
        return
    from substruct.run.vp_route import has_virtual_points  # the route: when used

    why = ("virtual points" if has_virtual_points(case) else
           "a decoupled part" if any(getattr(s, "decouple", False)
                                     for s in case.substructures) else None)
    if why is not None:
        raise CaseError(case.source, "analysis.frf",
                        f"receptances are not recovered (recovery:) in a case with {why}; "
                        "drop analysis.frf or the recovery block", why)


def _require_finite_modes(what: str, modes: Modes) -> None:
    require_finite(what, eigenvalues=modes.eigenvalues, shapes=modes.shapes)


def _require_finite_result(result: Result) -> None:
    """Refuse a result holding ``inf`` or ``NaN`` (an overflow) with one line
    (:func:`substruct.analysis.checks.require_finite`): never a table of ``inf``."""
    if result.modes is not None:
        _require_finite_modes("modes", result.modes)
    for name, variant in result.variants.items():
        _require_finite_modes(f"modes (variant {name})", variant)
    if result.frf is not None:
        require_finite("frf", H=result.frf.H)
    tr = result.transient
    if tr is not None:
        require_finite("transient", displacement=tr.displacement, velocity=tr.velocity,
                       acceleration=tr.acceleration, constraint_forces=tr.constraint_forces,
                       energy=tr.energy)
    for rec in result.recovery:
        require_finite(f"recovery {rec.title}", modes=rec.modes, history=rec.history,
                       frf=rec.frf)
