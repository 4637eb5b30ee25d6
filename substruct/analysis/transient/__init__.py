r"""Transient response of a constrained system (the paper's eqs 5 and 10 integrated in time):
:func:`~substruct.analysis.transient.response.transient`, by the generalized-inverse,
null-space or modal form, each checked by the others.

* :mod:`~substruct.analysis.transient.integrators`: Newmark and generalized-alpha steps;
* :mod:`~substruct.analysis.transient.loads`: loads with jumps kept second order;
* :mod:`~substruct.analysis.transient.initial`: initial states and the constrained static start;
* :mod:`~substruct.analysis.transient.base`: ground motion;
* :mod:`~substruct.analysis.transient.modal`: the modal form;
* :mod:`~substruct.analysis.transient.options`: what a run is given (loads, initial conditions,
  outputs, options), each checked once when made;
* :mod:`~substruct.analysis.transient.record`, :mod:`~substruct.analysis.transient.results`:
  what is recorded and returned;
* :mod:`~substruct.analysis.transient.fields`: the stored fields, whole or a block at a time
  into a sink.
"""

from substruct.lazy import lazy_getattr

#: Public name -> the module that defines it (imported on first use, so that importing one
#: module of the package does not import them all).
_LAZY = {
    "InitialConditions": "substruct.analysis.transient.options",
    "LoadHistory": "substruct.analysis.transient.options",
    "TRANSIENT_FORMS": "substruct.analysis.transient.response",
    "Transient": "substruct.analysis.transient.results",
    "TransientOptions": "substruct.analysis.transient.options",
    "TransientOutputs": "substruct.analysis.transient.options",
    "transient": "substruct.analysis.transient.response",
}

__all__ = ["TRANSIENT_FORMS", "InitialConditions", "LoadHistory", "Transient",
           "TransientOptions", "TransientOutputs", "transient"]


__getattr__ = lazy_getattr(__name__, _LAZY)
