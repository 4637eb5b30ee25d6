"""The production path of the sparse modes (issue 13): null-space numbers, KKT and
generalized-inverse residual checks that catch a wrong mode, the memory estimate against the
machine, and the two factorizations against each other."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import substruct.analysis.errors as analysis_errors
import substruct.analysis.modes.production as production
import substruct.linalg.factorize as fz
from substruct.analysis.api import modes
from substruct.analysis.checks import modes_agreement
from substruct.analysis.errors import AnalysisInputError, CheckError
from substruct.analysis.modes.krylov import check_inputs, eliminate
from substruct.analysis.modes.checks import generalized_inverse_residual, kkt_residual
from substruct.assembly.interfaces import tie_nodes
from substruct.assembly.stack import Connection, LinearConstraint, PointRef, assemble
from substruct.linalg.memory import factor_entries, require_memory
from substruct.models.discrete import free_free
from substruct.models.solid import BoxGrid, solid_box

E, NU, RHO, L, B, H = 2.1e11, 0.3, 7850.0, 1.0, 0.2, 0.2
FACE = {"box": [[L / 2, 0, 0], [L / 2, B, H]]}


@pytest.fixture(scope="module")
def coupled():
    """Two tied halves of a clamped box, an absorber on a massless boundary coordinate and an
    interpolated multi-point constraint: consistent mass, 60-odd independent rows."""
    a = solid_box("a", BoxGrid((L / 2, B, H), (5, 3, 3)), E, NU, RHO,
                  fixed=[{"box": [[0, 0, 0], [0, B, H]]}])
    b = solid_box("b", BoxGrid((L / 2, B, H), (5, 3, 3), origin=(L / 2, 0, 0)), E, NU, RHO)
    t1 = free_free("t1", 5.0, 5.0 * (2 * np.pi * 150) ** 2)
    cons = tie_nodes(a, b, FACE) + [
        Connection(PointRef("b", {"at": [L, B, H], "component": "y"}), PointRef("t1", "boundary"))]
    mpc = LinearConstraint((
        (PointRef("b", {"at": [0.8, 0.1, 0.2], "component": "z"}), 1.0),
        (PointRef("b", {"at": [0.75, 0.05, 0.0], "component": "z"}), -2.0),
        (PointRef("a", {"at": [0.3, 0.13, 0.2], "component": "x"}), 0.5)), name="mpc")
    return assemble([a, b, t1], cons, [mpc])


def test_production_path_equals_the_full_generalized_inverse_solve(coupled):
    asm = coupled
    prod = modes(asm.M, None, asm.K, asm.A, 8, solver="sparse")
    full = modes(asm.M, None, asm.K, asm.A, 8, solver="sparse", checks=("null-space", "kkt"),
                 full_checks=True)
    assert prod.method == "null-space/sparse" and full.method == "generalized-inverse/sparse"
    assert set(prod.agreement) == {"kkt-residual", "generalized-inverse-residual"}
    assert max(prod.agreement.values()) < 1e-9
    assert set(full.agreement) == {"null-space", "kkt"} and max(full.agreement.values()) < 1e-8
    assert modes_agreement(prod, full) < 1e-9


def test_residual_checks_catch_a_wrong_frequency_and_a_wrong_shape(coupled):
    asm = coupled
    Ms, Ks, As, _ = check_inputs(asm.M, asm.K, asm.A, 6)
    el = eliminate(Ms, As)
    Ak = sp.csr_array(As[el.kept_rows])
    good = modes(asm.M, None, asm.K, asm.A, 6, solver="sparse")
    U, w = good.shapes.real, good.omega
    assert kkt_residual(Ks, Ms, Ak, 1j * w, U) < 1e-10
    assert generalized_inverse_residual(Ks, Ms, Ak, 1j * w, U) < 1e-10
    # a frequency off by 1e-4 relative (2e-4 in omega^2): both figures far above the default
    # tolerance 1e-6 (the KKT one is relative to |K u|, which holds the tie forces too)
    off = w * np.r_[1.0, 1.0, 1.0 + 1e-4, 1.0, 1.0, 1.0]
    assert 1e-5 < kkt_residual(Ks, Ms, Ak, 1j * off, U) < 2e-4
    assert 5e-5 < generalized_inverse_residual(Ks, Ms, Ak, 1j * off, U) < 2e-4
    # a shape that violates the ties: the KKT residual sees it through A u
    bad = U.copy()
    bad[:, 0] += 1e-3 * np.abs(U[:, 0]).max() * (np.arange(U.shape[0]) % 7 == 0)
    assert kkt_residual(Ks, Ms, Ak, 1j * w, bad) > 1e-5
    assert generalized_inverse_residual(Ks, Ms, Ak, 1j * w, bad) > 1e-5


def test_a_check_past_the_tolerance_fails_the_production_path(coupled, monkeypatch):
    asm = coupled
    monkeypatch.setattr(production, "kkt_residual", lambda *a: 3e-4)
    with pytest.raises(CheckError, match="kkt-residual disagrees with null-space/sparse by "
                                         "3.0e-04"):
        modes(asm.M, None, asm.K, asm.A, 4, solver="sparse")


def test_the_generalized_inverse_check_is_skipped_and_said_when_costly(coupled, monkeypatch):
    asm = coupled
    monkeypatch.setattr(production, "generalized_inverse_affordable", lambda M, rows: False)
    res = modes(asm.M, None, asm.K, asm.A, 4, solver="sparse")
    assert list(res.agreement) == ["kkt-residual"]
    assert res.solver.startswith("sparse (generalized-inverse check skipped: ")


def test_a_mass_singular_in_a_combination_skips_the_generalized_inverse_check():
    # q1 - q2 carries no mass (no zero row): the null-space modes need no M_d, the
    # generalized-inverse check does; its factorization failed with an internal error
    M = sp.csr_array(np.array([[1.0, 1, 0], [1, 1, 0], [0, 0, 1]]))
    K = sp.csr_array(np.array([[20.0, -10, 0], [-10, 30, -20], [0, -20, 40]]))
    res = modes(M, None, K, None, 2, solver="sparse")
    L = np.linalg.cholesky(K.toarray())
    mu = np.linalg.eigvalsh(np.linalg.solve(L, np.linalg.solve(L, M.toarray()).T))
    np.testing.assert_allclose(res.omega ** 2, np.sort(1.0 / mu[mu > 1e-12])[:2], rtol=1e-10)
    assert list(res.agreement) == ["kkt-residual"]
    assert res.solver.startswith("sparse (") and ("generalized-inverse check skipped: the "
                                                   "mass is singular on coordinates that have "
                                                   "mass") in res.solver


def test_memory_is_refused_only_past_what_the_machine_has(coupled, monkeypatch):
    asm = coupled
    with pytest.raises(ValueError, match=r"needs about 2 GB; 1 GB are available"):
        require_memory(2e9, "x", available=1e9)
    require_memory(2e9, "x", available=3e9)
    monkeypatch.setattr(analysis_errors, "require_memory",
                        lambda need, what: require_memory(need, what, available=1e6))
    # bad input (a model too large for this machine), typed as such: exit 2, not a bug
    with pytest.raises(AnalysisInputError, match=r"sparse eigensolver: the sparse eigensolve of \d+ "
                       r"coordinates \((PARDISO|CHOLMOD|SuperLU|SuperLU \(METIS\))\) needs about"):
        modes(asm.M, None, asm.K, asm.A, 4, solver="sparse")


def test_the_fill_models_bound_the_measured_fill():
    """The SuperLU model of linalg.memory against SuperLU's own factor of a 3D box (within a
    factor 2 above and never below half of it), CHOLMOD's likewise when it is installed."""
    box = solid_box("b", BoxGrid((2.0, 0.5, 0.5), (16, 5, 5)), E, NU, RHO,
                    fixed=[{"box": [[0, 0, 0], [0, 0.5, 0.5]]}])
    K = sp.csc_array(box.K + 1e-3 * box.M)
    lu = spla.splu(sp.csc_matrix(K), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                   options={"SymmetricMode": True})
    ratio = factor_entries(K, "superlu") / (lu.L.nnz + lu.U.nnz)
    assert 0.5 < ratio < 2.0
    if fz.has_cholmod():
        from sksparse.cholmod import cholesky
        ratio = factor_entries(K, "cholmod") / cholesky(sp.csc_matrix(K)).L().nnz
        assert 0.5 < ratio < 2.5


def test_cholmod_and_superlu_give_the_same_modes(coupled):
    if not fz.has_cholmod():
        pytest.skip("scikit-sparse (CHOLMOD) is not installed: make fast")
    from substruct.analysis.modes.sparse import null_space_modes
    asm = coupled
    a = null_space_modes(asm.M, asm.K, asm.A, 8, factorization="cholmod")
    b = null_space_modes(asm.M, asm.K, asm.A, 8, factorization="superlu")
    assert modes_agreement(a, b) < 1e-10
