r"""The three independent formulations of a constrained system ``M q'' + C q' + K q = F``,
``A q = b + R F``: generalized inverse (the paper's eqs 5, 10, 15), null-space elimination
``q = N p + q_p`` and Lagrange multipliers (the KKT system).

* :mod:`~substruct.analysis.formulations.projection`: the projection of eq 5,
  ``M^-1/2 (A M^-1/2)^+ = M^-1 A^T (A M^-1 A^T)^+``, and the semidefinite mass split of
  eqs 6-10;
* :mod:`~substruct.analysis.formulations.receptance`: one frequency sweep per formulation
  (eq 15 by a bordered solve; null space; KKT);
* :mod:`~substruct.analysis.formulations.forms`: each formulation as an object
  (:class:`~substruct.analysis.formulations.forms.Formulation`: ``receptance``,
  ``dense_modes``, ``residual``) and the registry :func:`formulation` the analyses dispatch
  through;
* :mod:`~substruct.analysis.formulations.coupling`: the receptance of a constrained system by
  any of them, the paper's ``G`` and ``D`` as printed, and their agreement.

The names of the formulations are :data:`substruct.vocabulary.FORMULATIONS`; the analyses of
:mod:`substruct.analysis.modes`, :mod:`substruct.analysis.frf` and
:mod:`substruct.analysis.transient` take one of them as their main formulation and the others
as checks, so that each result is checked by a formulation that shares no code with it.
"""

from substruct.lazy import lazy_getattr

#: Public name -> the module that defines it (imported on first use, so that importing one
#: module of the package does not import them all).
_LAZY = {
    "FORMULATIONS": "substruct.analysis.formulations.coupling",
    "Formulation": "substruct.analysis.formulations.forms",
    "GENERALIZED_INVERSE_FORM": "substruct.analysis.formulations.forms",
    "KKT_FORM": "substruct.analysis.formulations.forms",
    "MassSplit": "substruct.analysis.formulations.projection",
    "NULL_SPACE_FORM": "substruct.analysis.formulations.forms",
    "constrained_acceleration": "substruct.analysis.formulations.projection",
    "constraint_gain": "substruct.analysis.formulations.projection",
    "formulation": "substruct.analysis.formulations.forms",
    "paper_G_D": "substruct.analysis.formulations.coupling",
    "projected_inverse": "substruct.analysis.formulations.projection",
    "receptance": "substruct.analysis.formulations.coupling",
    "receptance_agreement": "substruct.analysis.formulations.coupling",
    "receptance_unconstrained": "substruct.analysis.formulations.coupling",
    "split_mass": "substruct.analysis.formulations.projection",
}

__all__ = [
    "FORMULATIONS",
    "Formulation",
    "GENERALIZED_INVERSE_FORM",
    "KKT_FORM",
    "NULL_SPACE_FORM",
    "formulation",
    "MassSplit",
    "constrained_acceleration",
    "constraint_gain",
    "paper_G_D",
    "projected_inverse",
    "receptance",
    "receptance_agreement",
    "receptance_unconstrained",
    "split_mass",
]


__getattr__ = lazy_getattr(__name__, _LAZY)
