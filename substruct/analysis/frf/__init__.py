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

from substruct.analysis.frf.coupling import FrfPart, couple, decouple, lm_fbs
from substruct.analysis.frf.modal import ModalOptions, frf_method, modal_receptance_sweep
from substruct.analysis.frf.quantity import as_quantity, quantity_factor

__all__ = ["FrfPart", "ModalOptions", "as_quantity", "couple", "decouple", "frf_method",
           "lm_fbs", "modal_receptance_sweep", "quantity_factor"]
