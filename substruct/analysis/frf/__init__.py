r"""Receptances (frequency response functions) of constrained systems beyond one dense solve
per frequency (the paper's eqs 11-15):

* the sparse sweep of the null-space form with band solves (:mod:`~substruct.analysis.frf.sparse`)
  and the production path that checks it at a few frequencies
  (:mod:`~substruct.analysis.frf.production`);
* modal superposition with a residual flexibility (:mod:`~substruct.analysis.frf.modal`);
* coupling and decoupling of parts known only by receptances, LM-FBS and the
  generalized-inverse form (:mod:`~substruct.analysis.frf.coupling`);
* mobility and accelerance from receptance (:mod:`~substruct.analysis.frf.quantity`).

The front door of a receptance sweep is :func:`substruct.analysis.api.receptance_sweep`.
"""

from substruct.lazy import lazy_getattr

#: Public name -> the module that defines it (imported on first use, so that importing one
#: module of the package does not import them all).
_LAZY = {
    "FrfPart": "substruct.analysis.frf.coupling",
    "ModalOptions": "substruct.analysis.frf.modal",
    "as_quantity": "substruct.analysis.frf.quantity",
    "couple": "substruct.analysis.frf.coupling",
    "decouple": "substruct.analysis.frf.coupling",
    "frf_method": "substruct.analysis.frf.modal",
    "lm_fbs": "substruct.analysis.frf.coupling",
    "modal_receptance_sweep": "substruct.analysis.frf.modal",
    "quantity_factor": "substruct.analysis.frf.quantity",
}

__all__ = ["FrfPart", "ModalOptions", "as_quantity", "couple", "decouple", "frf_method",
           "lm_fbs", "modal_receptance_sweep", "quantity_factor"]


__getattr__ = lazy_getattr(__name__, _LAZY)
