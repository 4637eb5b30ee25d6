"""The ``Examples`` sections of the public entry points run as doctests (as scipy's do), and the
formulation objects keep the meaning the cross-checks rely on."""

from __future__ import annotations

import doctest
import importlib

import numpy as np
import pytest

from substruct.analysis.formulations.forms import REGISTRY, formulation
from substruct.linalg.system import ConstrainedSystem
from substruct.vocabulary import FORMULATIONS

MODULES = [
    "substruct.vocabulary",
    "substruct.linalg.system",
    "substruct.analysis.system",
    "substruct.analysis.api",
    "substruct.analysis.modes.eigen",
    "substruct.analysis.formulations.forms",
]


@pytest.mark.parametrize("name", MODULES)
def test_examples_run(name):
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 0, f"{name} has no example"
    assert result.failed == 0


def test_registry_is_the_vocabulary():
    assert tuple(REGISTRY) == FORMULATIONS
    assert [formulation(n).name for n in FORMULATIONS] == list(FORMULATIONS)


def _tied_chain(k1=1e6):
    """Three unit masses, springs ``k1``, 1, 1 in a chain from the ground, a redundant tie
    ``q_2 = q_3`` written twice at scales 1 and 1e-9, and a force-tied row ``q_1 = 1e-3 F_1``."""
    K = np.array([[k1 + 1, -1, 0], [-1, 2, -1], [0, -1, 1]])
    A = np.array([[0, 1.0, -1.0], [0, 1e-9, -1e-9], [1.0, 0, 0]])
    R = np.zeros((3, 3))
    R[2, 0] = 1e-3
    return ConstrainedSystem.of(np.eye(3), 0.01 * K, K, A, R=R)


@pytest.mark.parametrize("name", FORMULATIONS)
def test_each_formulation_owns_a_residual_that_judges_every_answer(name):
    """Each formulation's residual is at rounding level (1e-12: cond ~ 1e6, eps 2e-16) for the
    answer of every formulation, and above 1e-3 for a wrong one (one coordinate moved by a
    tenth of the response, on springs of one size: the figure is then of order 0.1)."""
    system = _tied_chain()
    E = np.eye(3)[:, :2]
    w = 0.7
    for source in FORMULATIONS:
        q = formulation(source).receptance(system, np.array([w]), E, np.eye(3))[0]
        assert formulation(name).residual(system, w, q, E) < 1e-12, source
    mild = _tied_chain(1.0)
    q = formulation(name).receptance(mild, np.array([w]), E, np.eye(3))[0]
    assert formulation(name).residual(mild, w, q, E) < 1e-12
    q[1] += 0.1 * np.abs(q).max()
    assert formulation(name).residual(mild, w, q, E) > 1e-3


def test_system_rows_equilibrated_once_exactly():
    """Equilibrating an equilibrated system changes no bit (powers of two)."""
    system = _tied_chain()
    again = ConstrainedSystem.of(system.M, system.C, system.K, system.A, system.b, system.R)
    assert (again.A != system.A).nnz == 0 and np.all(again.row_scale == 1.0)
    assert system.independent.rank == 2


def test_shapes_refused():
    with pytest.raises(ValueError, match="A must have 2 columns"):
        ConstrainedSystem.of(np.eye(2), None, np.eye(2), np.ones((1, 3)))
    with pytest.raises(ValueError, match="R must be 1 x 2"):
        ConstrainedSystem.of(np.eye(2), None, np.eye(2), np.ones((1, 2)), R=np.ones((2, 2)))
