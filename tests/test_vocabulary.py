"""The words shared by the case file and the analyses are defined once (substruct.vocabulary):
the schema accepts exactly them, and each analysis table is keyed by exactly them."""

from typing import get_args

import pytest

from substruct import vocabulary as v
from substruct.analysis.frf.modal import RESIDUAL_ORDER
from substruct.analysis.frf.quantity import QUANTITY_POWER
from substruct.analysis.modes.eigen import SOLVERS
from substruct.case.analysis import FrfAnalysis, ModalFrf, ModesAnalysis
from substruct.case.substructures import RodSpec
from substruct.case.transient import TransientAnalysis
from substruct.models.rod_parts import SUPPORTS


def accepted(model, field):
    """The words a schema field accepts (a Literal, or a list of one)."""
    annotation = model.model_fields[field].annotation
    args = get_args(annotation)
    if args and not isinstance(args[0], str):  # list[Literal[...]]
        args = get_args(args[0])
    return set(args)


@pytest.mark.parametrize("model, field, words", [
    (ModesAnalysis, "method", v.FORMULATIONS),
    (ModesAnalysis, "check", v.FORMULATIONS),
    (ModesAnalysis, "solver", v.SOLVERS),
    (FrfAnalysis, "method", v.FRF_METHODS),
    (FrfAnalysis, "check", v.FORMULATIONS),
    (FrfAnalysis, "quantity", v.QUANTITIES),
    (ModalFrf, "residual", v.RESIDUALS),
    (TransientAnalysis, "method", v.TRANSIENT_FORMS),
    (TransientAnalysis, "check", v.TRANSIENT_FORMS),
    (TransientAnalysis, "integrator", v.INTEGRATORS),
])
def test_the_schema_accepts_the_vocabulary(model, field, words):
    assert accepted(model, field) == set(words)


def test_the_analysis_tables_are_keyed_by_the_vocabulary():
    assert set(RESIDUAL_ORDER) == set(v.RESIDUALS)
    assert set(QUANTITY_POWER) == set(v.QUANTITIES)
    assert SOLVERS == v.SOLVERS
    assert set(v.FORMULATIONS) == {v.GENERALIZED_INVERSE, v.NULL_SPACE, v.KKT}
    assert set(v.FRF_METHODS) == {*v.FORMULATIONS, v.MODAL, "auto"}
    assert set(accepted(RodSpec, "support")) == set(SUPPORTS)


def test_defaults_are_the_vocabulary_defaults():
    assert ModesAnalysis.model_fields["tolerance"].default == v.DEFAULT_TOLERANCE
    assert TransientAnalysis.model_fields["tolerance"].default == v.DEFAULT_TOLERANCE
    assert ModesAnalysis.model_fields["method"].default == v.GENERALIZED_INVERSE
