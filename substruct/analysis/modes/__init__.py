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

from substruct.analysis.modes.eigen import (
    SOLVERS,
    SPARSE_ABOVE,
    SolverChoice,
    choose_solver,
    modes,
)
from substruct.analysis.modes.mac import mac_matrix, pair_modes

__all__ = ["SOLVERS", "SPARSE_ABOVE", "SolverChoice", "choose_solver", "mac_matrix", "modes",
           "pair_modes"]
