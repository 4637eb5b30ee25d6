"""The modal block of a case's receptance analyses (``modal:`` of ``analysis.frf`` and
``analysis.random``) as the options of the modal sweep."""

from __future__ import annotations

from substruct.analysis.frf.modal import ModalOptions
from substruct.analysis.modes.amls import AmlsOptions
from substruct.case.modal_spec import AmlsSpec, ModalFrf
from substruct.linalg.task_runner import TaskRunner

__all__ = ["amls_options", "modal_options"]


def amls_options(solver: str, block: AmlsSpec | None,
                 tasks: TaskRunner | None = None) -> AmlsOptions | None:
    """:class:`~substruct.analysis.modes.amls.AmlsOptions` of a modal block's ``amls:``
    (its defaults if ``None``) for ``solver: amls``, its tree levels run through ``tasks``
    (``None``: in this process); ``None`` for the other solvers."""
    if solver != "amls":
        return None
    return AmlsOptions(**({} if block is None else block.model_dump()), tasks=tasks)


def modal_options(block: ModalFrf | None, tasks: TaskRunner | None = None) -> ModalOptions:
    """:class:`~substruct.analysis.frf.modal.ModalOptions` of a case's ``modal`` block (its
    defaults if ``None``): the roots kept, the residual, the check frequencies, the
    eigensolver and, with ``solver: amls``, the reduction, whose tree levels run through
    ``tasks`` (``None``: in this process)."""
    b = block if block is not None else ModalFrf()
    return ModalOptions(b.count, b.cutoff, b.residual, b.check_frequencies, b.solver,
                        amls_options(b.solver, b.amls, tasks))
