r"""From a validated case to a :class:`~substruct.run.result.Result`: build, couple, analyse.

Data flows one way (``docs/architecture.md``): :func:`build_model` checks the sizes the
analyses can take and assembles the case (:func:`substruct.builder.model.assemble_case`);
:func:`run_case` computes the coupled modes, the variants (the same assembly with some
constraint rows dropped) and the receptances (:mod:`substruct.run.analyses`).
"""

from __future__ import annotations

from datetime import datetime, timezone
from typing import Mapping

import scipy.sparse as sp

from substruct.analysis.events import Phase
from substruct.builder.frf_parts import assemble_frf_case, has_frf_parts
from substruct.builder.model import Model, assemble_case
from substruct.case.loader import Case
from substruct.run.analyses import (
    Progress,
    check_dense_modes,
    check_dense_sizes,
    frf_result,
    min_size,
    model_info,
    modes_result,
)
from substruct.run.result import Result
from substruct.substructure import Substructure

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
    model = assemble_frf_case(case, prebuilt) if has_frf_parts(case) else \
        assemble_case(case, prebuilt)
    spec = case.analysis.modes
    if spec is not None and spec.count > model.assembly.n_dof:
        raise case.error(("analysis", "modes", "count"), f"more modes than the "
                         f"{model.assembly.n_dof} coordinates of the model", spec.count)
    return model


def run_case(case: Case, progress: Progress | None = None, model: Model | None = None,
             events: Phase | None = None) -> Result:
    """Run the analyses of a case.

    Args:
        case: a validated case (:func:`substruct.load_case`).
        progress: called as ``progress(done, total, label)`` during frequency sweeps.
        model: the case's model if already built (:func:`build_model`).
        events: called as each phase starts, ``events(kind, what, size)``
            (:class:`substruct.analysis.events.Phase`): assembly, each eigen solve, each
            receptance sweep.

    Returns:
        The :class:`~substruct.run.result.Result`: modes (physical modes ascending, spurious
        roots set aside, agreement with the check formulations, the solver that ran),
        variants, receptances, model data.

    Raises:
        CaseError: input that cannot be analysed (see :func:`build_model`; inconsistent
            constraints; a model too large for the dense eigenproblem).
        CheckError: a check formulation disagrees with the main one by more than the
            case's ``tolerance`` (nothing is returned, so nothing is written).
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
             "case_file": case.source, "overrides": "\n".join(case.overrides)}
    result = Result(case_name=case.name, case_yaml=case.text, model=model_info(model),
                    attrs={k: v for k, v in attrs.items() if v})
    if case.output.matrices:
        result.model.matrices = {"M": sp.csr_array(asm.M), "K": sp.csr_array(asm.K),
                                 "C": sp.csr_array(asm.C)}
    spec = case.analysis.modes
    if spec is not None:
        result.modes = modes_result(case, asm, asm.A, ("analysis", "modes"), events=events)
        labels = list(asm.constraint_labels)
        for i, variant in enumerate(spec.variants):
            keep = [r for r, lab in enumerate(labels) if lab not in variant.drop]
            A = sp.csr_array(asm.A[keep]) if keep else sp.csr_array((0, asm.n_dof))
            result.variants[variant.name] = modes_result(
                case, asm, A, ("analysis", "modes", "variants", i),
                what=f"modes (variant {variant.name})", events=events)
    frf = case.analysis.frf
    if frf is not None:
        if events is not None:
            n_omega = len(frf.omega.grid())
            events("sweep", f"receptances: {n_omega} frequencies, {len(frf.outputs)} output(s) "
                   f"x {len(frf.inputs)} input(s), {asm.n_dof} coordinates", n_omega)
        if has_frf_parts(case):
            from substruct.run.frf_route import coupled_frf_result  # only for FRF parts

            result.frf = coupled_frf_result(case, model, progress)
        else:
            result.frf = frf_result(case, model, progress)
    if case.analysis.transient is not None:
        if events is not None:
            events("sweep", f"transient: {case.analysis.transient.steps} steps, "
                   f"{asm.n_dof} coordinates", case.analysis.transient.steps)
        from substruct.run.transient_run import transient_result  # only for a transient

        result.transient = transient_result(case, model)
    return result
