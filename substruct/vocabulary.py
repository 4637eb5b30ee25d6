r"""The names and defaults that the case file and the analyses share, defined once.

A case names its formulations, solvers, integrators and residual corrections with these words;
the analyses accept the same words.  Each vocabulary is one ``Literal`` type, which the case
schema validates against, and the tuple of its words (``typing.get_args`` of the type), which
the analyses check against, so the two cannot disagree.

=====================  ======================================================================
vocabulary             words
=====================  ======================================================================
:data:`FormulationName`    the three independent formulations of a constrained system: the
                       generalized inverse (eqs 5, 10, 15), null-space elimination and
                       Lagrange multipliers (KKT)
:data:`TransientForm`  the forms of a transient run: generalized inverse, null space, modal
:data:`FrfMethod`      a receptance sweep: a formulation, ``modal`` or ``auto``
:data:`Solver`         the eigensolver strategy: ``auto``, ``dense``, ``sparse``,
                       ``amls`` (automated multilevel substructuring)
:data:`Integrator`     ``newmark`` (average acceleration), ``generalized-alpha``
:data:`Residual`       the residual flexibility of a modal receptance
:data:`Quantity`       receptance, mobility (``i omega H``), accelerance (``-omega^2 H``)
:data:`Support`        the supports of a rod's two ends
=====================  ======================================================================

Examples
--------
>>> from substruct.vocabulary import FORMULATIONS, GENERALIZED_INVERSE
>>> FORMULATIONS
('generalized-inverse', 'null-space', 'kkt')
>>> GENERALIZED_INVERSE in FORMULATIONS
True
"""

from __future__ import annotations

from typing import Final, Literal, get_args

__all__ = [
    "DEFAULT_TOLERANCE",
    "DERIVATIVE_ORDER",
    "FORMULATIONS",
    "FRF_METHODS",
    "FormulationName",
    "FrfMethod",
    "GENERALIZED_INVERSE",
    "INTEGRATORS",
    "Integrator",
    "KKT",
    "MODAL",
    "NULL_SPACE",
    "QUANTITIES",
    "Quantity",
    "RESIDUALS",
    "Residual",
    "SOLVERS",
    "SUPPORTS",
    "Solver",
    "Support",
    "TRANSIENT_FORMS",
    "TransientForm",
]

#: The generalized-inverse formulation (the paper's eqs 5, 10, 15).
GENERALIZED_INVERSE: Final = "generalized-inverse"
#: Null-space elimination ``q = N p + q_p``, ``A N = 0``.
NULL_SPACE: Final = "null-space"
#: Lagrange multipliers: the bordered (KKT) system ``[[Z, A^T], [A, 0]]``.
KKT: Final = "kkt"
#: Modal superposition (a receptance sweep or a transient run on the coupled modes).
MODAL: Final = "modal"

#: The three independent formulations of a constrained system.
FormulationName = Literal["generalized-inverse", "null-space", "kkt"]
FORMULATIONS: tuple[FormulationName, ...] = get_args(FormulationName)

#: The forms of a transient run.
TransientForm = Literal["generalized-inverse", "null-space", "modal"]
TRANSIENT_FORMS: tuple[TransientForm, ...] = get_args(TransientForm)

#: The main method of a receptance sweep.
FrfMethod = Literal["generalized-inverse", "null-space", "kkt", "modal", "auto"]
FRF_METHODS: tuple[FrfMethod, ...] = get_args(FrfMethod)

#: The eigensolver strategy.
Solver = Literal["auto", "dense", "sparse", "amls"]
SOLVERS: tuple[Solver, ...] = get_args(Solver)

#: The time integrators.
Integrator = Literal["newmark", "generalized-alpha"]
INTEGRATORS: tuple[Integrator, ...] = get_args(Integrator)

#: The residual flexibility of a modal receptance.
Residual = Literal["second-order", "static", "none"]
RESIDUALS: tuple[Residual, ...] = get_args(Residual)

#: The supports of a rod's ends (at ``x = 0``, then ``x = L``).
Support = Literal["fixed-free", "fixed-fixed", "free-free", "free-fixed"]
SUPPORTS: tuple[Support, ...] = get_args(Support)

#: What a receptance is shown as.
Quantity = Literal["receptance", "mobility", "accelerance"]
QUANTITIES: tuple[Quantity, ...] = get_args(Quantity)

#: The order of the time derivative of each response history (the power of the root
#: :math:`\lambda` of a mode, or of :math:`i \omega` of a receptance, that turns a
#: displacement into it).
DERIVATIVE_ORDER: Final = {"displacement": 0, "velocity": 1, "acceleration": 2}

#: The default relative tolerance of every cross-check.
DEFAULT_TOLERANCE: Final = 1e-6
