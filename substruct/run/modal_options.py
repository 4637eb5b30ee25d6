"""The modal block of a case's receptance analyses (``modal:`` of ``analysis.frf`` and
``analysis.random``) as the options of the modal sweep."""

from __future__ import annotations

from substruct.analysis.frf.modal import ModalOptions
from substruct.analysis.modes.amls import AmlsOptions
from substruct.case.modal_spec import ModalFrf

__all__ = ["modal_options"]


def modal_options(block: ModalFrf | None) -> ModalOptions:
    """:class:`~substruct.analysis.frf.modal.ModalOptions` of a case's ``modal`` block (its
    defaults if ``None``): the roots kept, the residual, the check frequencies, the
    eigensolver and, with ``solver: amls``, the reduction."""
    b = block if block is not None else ModalFrf()
    return ModalOptions(b.count, b.cutoff, b.residual, b.check_frequencies, b.solver,
                        AmlsOptions(**b.amls.model_dump()) if b.amls is not None else None)
