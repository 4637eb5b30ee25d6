r"""Coupled modes of a constrained system (the paper's eqs 23-34): the one entry point
:func:`~substruct.analysis.modes.eigen.modes` and its choice of strategy.

* dense (:mod:`~substruct.analysis.modes.dense`): the three formulations on full matrices,
  the spurious roots of eqs 30 and 34 set aside (:mod:`~substruct.analysis.modes.roots`,
  :mod:`~substruct.analysis.modes.pencil`);
* sparse undamped (:mod:`~substruct.analysis.modes.sparse`) and damped
  (:mod:`~substruct.analysis.modes.damped`) shift-invert Lanczos, with the elimination and
  Krylov sizes of :mod:`~substruct.analysis.modes.krylov`;
* the production path (:mod:`~substruct.analysis.modes.production`): the null-space form
  computes, the others check by residuals (:mod:`~substruct.analysis.modes.checks`);
* the modal assurance criterion (:mod:`~substruct.analysis.modes.mac`).
"""

from substruct.lazy import lazy_getattr

#: Public name -> the module that defines it (imported on first use, so that importing one
#: module of the package does not import them all).
_LAZY = {
    "SOLVERS": "substruct.analysis.modes.eigen",
    "SPARSE_ABOVE": "substruct.analysis.modes.eigen",
    "SolverChoice": "substruct.analysis.modes.eigen",
    "choose_solver": "substruct.analysis.modes.eigen",
    "mac_matrix": "substruct.analysis.modes.mac",
    "modes": "substruct.analysis.modes.eigen",
    "pair_modes": "substruct.analysis.modes.mac",
}

__all__ = ["SOLVERS", "SPARSE_ABOVE", "SolverChoice", "choose_solver", "mac_matrix", "modes",
           "pair_modes"]


__getattr__ = lazy_getattr(__name__, _LAZY)
