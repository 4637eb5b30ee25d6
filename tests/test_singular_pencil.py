"""A motion with neither mass nor stiffness (a singular pencil) in the sparse eigensolvers.

``K - sigma M`` with ``sigma < 0`` is singular exactly when some ``z`` has ``K z = M z = 0``.
A factorization need not fail on it (SuperLU pivots on round-off), and shift-invert Lanczos
then adds a huge multiple of ``z`` to every mode shape, unseen by the residual and the mass
normalization.  What is asserted:

* :func:`substruct.linalg.definite.numerically_singular` separates the singular pencils (an
  exact zero row, a floating massless spring, the torsion of a free bar whose mass is lumped on
  its translations) from regular ones on the edge (a free-free body, whose rigid motions leave
  ``B`` only ``|sigma| M``, 1e-9 of the stiffness's scale) with every backend;
* the free bar of CBARs with point masses only, from bulk data, is refused by the dense, sparse
  and AMLS solvers alike;
* the null-space and generalized-inverse solvers refuse it with the one "singular model" error,
  and a CHOLMOD/PARDISO "not positive definite" fallback warning is not printed beside it.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import scipy.sparse as sp

from substruct.analysis.errors import AnalysisInputError
from substruct.analysis.modes.sparse import generalized_inverse_modes, null_space_modes
from substruct.linalg.backends import available_backends
from substruct.linalg.definite import SINGULAR_ROUNDOFF, numerically_singular
from substruct.linalg.factorize import factorizer
from substruct.case.errors import CaseError
from test_amls_massless import lumped_bar as lumped_bar_bulk, modes_of

BACKENDS = [b for b in ("superlu", "cholmod", "pardiso") if b in available_backends("spd")]


def chain(n: int, free: bool) -> tuple[sp.csr_array, sp.csr_array]:
    """``n`` unit masses joined by unit springs, the first one grounded unless ``free``."""
    K = sp.diags_array([-np.ones(n - 1), 2 * np.ones(n), -np.ones(n - 1)], offsets=[-1, 0, 1])
    K = sp.lil_array(K)
    K[n - 1, n - 1] = 1.0
    if free:
        K[0, 0] = 1.0
    return sp.csr_array(K), sp.csr_array(sp.eye_array(n))


def with_floating_link(K: sp.csr_array, M: sp.csr_array, k: float = 3.0
                       ) -> tuple[sp.csr_array, sp.csr_array]:
    """Two massless coordinates joined by a spring ``k`` and to nothing else: ``z = [1, 1]``
    has ``K z = M z = 0``."""
    link = sp.csr_array(k * np.array([[1.0, -1.0], [-1.0, 1.0]]))
    return (sp.csr_array(sp.block_diag([K, link])),
            sp.csr_array(sp.block_diag([M, sp.csr_array((2, 2))])))


def lumped_bar(elements: int, free: bool = True) -> tuple[sp.csr_array, sp.csr_array]:
    """A bar in torsion and axial stretching: per node the axial displacement (with the node's
    mass) and the twist (massless: the mass is lumped on the translations)."""
    n = elements + 1
    Ka, _ = chain(n, free)
    # GJ / L graded along the bar on the twists (its rigid twist is no longer exact in
    # floating point: the singular pivot is round-off, not zero), EA / L on the stretching
    Kt = contrast(0.7 * Ka, Ka, 3.0)[0]
    K = sp.csr_array(sp.block_diag([Ka, Kt]))
    M = sp.csr_array(sp.block_diag([sp.eye_array(n), sp.csr_array((n, n))]))
    return K, M


def contrast(K: sp.csr_array, M: sp.csr_array, ratio: float
             ) -> tuple[sp.csr_array, sp.csr_array]:
    """``D K D`` with ``D`` graded geometrically over ``ratio``: stiffnesses (and the rigid
    motion's shape ``D^-1 1``) spread over ``ratio^2``, still semidefinite."""
    D = sp.diags_array(np.geomspace(1.0, ratio, K.shape[0]))
    return sp.csr_array(D @ K @ D), M


def shifted(K: sp.csr_array, M: sp.csr_array, factor: float = 1e-9) -> sp.csc_array:
    sigma = -factor * K.diagonal().sum() / M.diagonal().sum()
    return sp.csc_array(K - sigma * M)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("model", ["zero row", "floating link", "free lumped bar"])
def test_singular_pencils_are_found(model, backend):
    K, M = {"zero row": lambda: with_floating_link(*chain(30, False), k=0.0),
            "floating link": lambda: with_floating_link(*chain(30, False)),
            "free lumped bar": lambda: lumped_bar(30)}[model]()
    B = shifted(K, M)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            solve = factorizer(backend)(B)
        except Exception:   # the backend saw it (CHOLMOD's, PARDISO's errors): nothing to probe
            return
    assert numerically_singular(B, solve)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("model", ["grounded", "free-free", "free-free, stiff contrast",
                                   "held lumped bar"])
def test_regular_pencils_pass_even_with_rigid_motions(model, backend):
    K, M = {"grounded": lambda: chain(200, False),
            "free-free": lambda: chain(200, True),
            "free-free, stiff contrast": lambda: contrast(*chain(200, True), 1e4),
            "held lumped bar": lambda: lumped_bar(30, free=False)}[model]()
    B = shifted(K, M)
    assert not numerically_singular(B, factorizer(backend)(B))


def test_the_margin_of_a_free_body_over_round_off():
    """A free-free chain's rigid motion at the default shift: its Rayleigh quotient is many
    round-offs above the threshold (its ``|sigma| x^T M x`` is 1e-9 of the stiffness's scale,
    ``eps`` is 2.2e-16)."""
    K, M = chain(200, True)
    B = shifted(K, M)
    solve = factorizer("superlu")(B)
    x = solve(solve(np.random.default_rng(0).standard_normal(200)))
    ratio = (x @ (B @ x)) / (np.abs(x) @ (abs(B) @ np.abs(x))) / np.finfo(float).eps
    assert ratio > 100 * SINGULAR_ROUNDOFF


@pytest.mark.parametrize("solver", ["dense", "sparse", "amls"])
def test_a_free_bar_with_lumped_mass_is_refused_by_every_solver(tmp_path, solver):
    """Nastran bulk data: a free bar of CBARs with CONM2 point masses only (no rotary
    inertia).  Its rigid twist about its own axis has neither mass nor stiffness.  Before,
    the dense and AMLS solvers refused it and the sparse one returned five rigid modes
    through a factorization on a round-off pivot: the same model, another answer by size."""
    bulk = tmp_path / "bar.bdf"
    bulk.write_text(lumped_bar_bulk(clamped=False))
    with pytest.raises(CaseError, match="singular model: a motion with no mass"):
        modes_of(tmp_path, bulk, "{count: 12, solver: %s}" % solver)


@pytest.mark.parametrize("solver", [null_space_modes, generalized_inverse_modes])
@pytest.mark.parametrize("model", ["floating link", "free lumped bar"])
def test_the_sparse_solvers_refuse_it_in_one_error(solver, model):
    K, M = (with_floating_link(*chain(30, False)) if model == "floating link"
            else lumped_bar(30))
    with warnings.catch_warnings():
        warnings.simplefilter("error")     # no fallback warning beside the refusal
        with pytest.raises(AnalysisInputError, match="singular model: a motion with no mass"):
            solver(M, K, None, 4)


def test_a_constraint_that_holds_the_motion_makes_it_regular():
    """The floating link tied to the chain's last mass: the pencil on null(A) is regular and
    both solvers agree with each other."""
    K, M = with_floating_link(*chain(30, False))
    A = sp.csr_array(([1.0, -1.0], ([0, 0], [29, 30])), shape=(1, 32))
    a = null_space_modes(M, K, A, 4)
    b = generalized_inverse_modes(M, K, A, 4)
    assert np.allclose(a.omega, b.omega, rtol=1e-10)
