"""Sparse coupled modes of damped models (``damped_sparse_modes``) against the dense path.

Non-proportional damping (discrete dashpots beside Rayleigh damping), massless coordinates,
constraints, over-damped roots and rigid-body motions: the lowest roots of the sparse
null-space and Lagrange (KKT) pencils equal those of the dense ``coupled_modes`` to 1e-9
(measured: 2e-15 to 7e-13), and a small damped solid case gives the same frequencies and
damping ratios with ``solver: dense`` and ``solver: sparse`` (measured: 6.4e-13).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from substruct.case.loader import parse_case
from substruct.analysis import api
from substruct.analysis.modes.dense import coupled_modes
from substruct.run.runner import build_model, run_case
from substruct.analysis.modes.damped import damped_sparse_modes
from substruct.analysis.modes.sparse import sparse_coupled_modes

sys.path.insert(0, str(Path(__file__).resolve().parent))
from test_solid_cases import small_case  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
FORMULATIONS = ("null-space", "kkt")


def chain(rng, n=40, n_massless=3, m=4, grounded=True, absolute=True):
    """A chain of ``n`` springs (grounded at its start or free-free), Rayleigh damping plus two
    discrete dashpots, ``n_massless`` massless coordinates (one of them tied, one with a
    dashpot to ground: a real root ``-k/c``), ``m`` random two-coordinate ties (plain node
    ties ``u_a = u_b`` when free-free, which keep the rigid-body motion).  ``absolute=False``
    leaves out the damping that acts on a rigid-body motion (``0.2 M``, the ground dashpot)."""
    d = 1 + rng.random(n)
    main = np.r_[d[:-1] + d[1:], d[-1]]
    if not grounded:
        main[0] -= d[0]
    K = 1e3 * sp.diags_array([-d[1:], main, -d[1:]], offsets=[-1, 0, 1]).toarray()
    M = np.diag(0.5 + rng.random(n))
    massless = rng.choice(np.arange(2, n - 1), n_massless, replace=False)
    M[massless, massless] = 0.0
    C = 1e-3 * K + (0.2 * M if absolute else 0.0)
    for a, b, c in [(5, n - 10, 8.0), (12, n - 20, 3.0)]:
        C[np.ix_([a, b], [a, b])] += c * np.array([[1.0, -1.0], [-1.0, 1.0]])
    C[massless[1], massless[1]] += 2.0 if absolute else 0.0
    A = np.zeros((m, n))
    for i in range(m):
        a, b = rng.choice(n, 2, replace=False)
        A[i, a], A[i, b] = 1.0, -rng.random() - 0.5 if grounded else -1.0
    A[0, :] = 0.0
    A[0, massless[0]], A[0, (massless[0] + 7) % n] = 1.0, -1.0
    return M, C, K, A


def relative(a, b):
    return float(np.max(np.abs(a - b) / np.abs(b)))


@pytest.mark.parametrize("formulation", FORMULATIONS)
@pytest.mark.parametrize("seed", range(4))
def test_random_damped_chains_match_the_dense_path(seed, formulation):
    M, C, K, A = chain(np.random.default_rng(seed))
    ref = coupled_modes(M, C, K, A, "null-space", 8)
    got = damped_sparse_modes(*(sp.csr_array(X) for X in (M, C, K, A)), 8,
                              formulation=formulation)
    assert got.method == f"{formulation}/sparse" and len(got) == 8
    assert relative(got.eigenvalues, ref.eigenvalues) < 1e-9
    np.testing.assert_allclose(got.omega, ref.omega, rtol=1e-9)
    np.testing.assert_allclose(got.damping_ratio, ref.damping_ratio, rtol=1e-9, atol=1e-12)
    assert got.residual.max() < 1e-12
    assert np.all(got.eigenvalues.imag >= 0) and got.shapes.dtype == complex
    # the same vectors, normalized alike (largest entry real positive, u^H M u = 1)
    for j in range(8):
        u, v = ref.shapes[:, j], got.shapes[:, j]
        assert np.abs(u - v).max() < 1e-7 * np.abs(u).max()


def test_the_real_root_of_a_massless_dashpot_and_the_dispatch():
    """All the roots of a small chain, the real ``-k/c`` of the massless dashpot among them,
    through ``sparse_coupled_modes`` with ``C`` (the three method names)."""
    M, C, K, A = chain(np.random.default_rng(7), n=30)
    ref = coupled_modes(M, C, K, A, "kkt")
    assert np.any(ref.eigenvalues.imag == 0)
    k = len(ref) - 2
    for method in ("null-space", "generalized-inverse", "kkt"):
        got = sparse_coupled_modes(sp.csr_array(M), sp.csr_array(K), sp.csr_array(A), k,
                                   method=method, C=sp.csr_array(C))
        assert got.method == f"{method}/sparse"
        assert relative(got.eigenvalues, ref.eigenvalues[:k]) < 1e-9
        np.testing.assert_array_equal(got.eigenvalues.imag == 0, ref.eigenvalues[:k].imag == 0)


@pytest.mark.parametrize("absolute", [True, False], ids=["damped", "undamped"])
@pytest.mark.parametrize("formulation", FORMULATIONS)
def test_rigid_body_motion_of_a_free_free_damped_chain(formulation, absolute):
    """Free-free: the rigid-body motion is one entry ``lambda = 0`` as in the dense path.
    Damped by ``0.2 M`` and a dashpot to ground, it has a decay root besides (``-0.25``);
    undamped (relative dashpots and ``1e-3 K`` only), its double zero root, which Arnoldi
    splits by ``sqrt(eps)``, is still one entry."""
    M, C, K, A = chain(np.random.default_rng(3), grounded=False, absolute=absolute)
    ref = coupled_modes(M, C, K, A, "null-space", 6)
    got = damped_sparse_modes(*(sp.csr_array(X) for X in (M, C, K, A)), 6,
                              formulation=formulation)
    assert ref.eigenvalues[0] == 0 and got.eigenvalues[0] == 0
    assert (ref.eigenvalues[1].imag == 0) == absolute
    assert relative(got.eigenvalues[1:], ref.eigenvalues[1:]) < 1e-9
    np.testing.assert_allclose(got.damping_ratio, ref.damping_ratio, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("formulation", FORMULATIONS)
def test_heavily_damped_two_dof_system_with_over_damped_roots(formulation):
    """Two masses, a heavy dashpot on the first: two real roots (damping ratio 1, one entry
    each) and one lightly damped complex pair, ordered by ``|lambda|`` as the dense path."""
    M = np.diag([1.0, 2.0])
    K = np.array([[3e3, -1e3], [-1e3, 1e3]])
    C = np.array([[400.0, 0.0], [0.0, 0.5]])
    ref = coupled_modes(M, C, K, None, "null-space")
    assert np.sum(ref.eigenvalues.imag == 0) == 2 and len(ref) == 3
    got = damped_sparse_modes(sp.csr_array(M), sp.csr_array(C), sp.csr_array(K), None, 3,
                              formulation=formulation)
    assert relative(got.eigenvalues, ref.eigenvalues) < 1e-9
    np.testing.assert_array_equal(got.damping_ratio[ref.eigenvalues.imag == 0], 1.0)
    np.testing.assert_array_equal(got.eigenvalues.imag == 0, ref.eigenvalues.imag == 0)


def test_a_damped_solid_case_dense_and_sparse():
    """Two tied boxes, a damped tuned absorber, Rayleigh damping on the left box and a
    multi-point constraint: the sparse solver (checks null-space and kkt) gives the dense
    frequencies and damping ratios; the KKT and generalized-inverse residuals check it."""
    text = small_case(damping=10).replace(
        "    fixed: [xmin]\n", "    fixed: [xmin]\n    damping: {rayleigh: [2.0, 1.0e-6]}\n")
    assert "rayleigh" in text

    def modes(solver):
        return run_case(parse_case(text.replace("solver: auto", f"solver: {solver}"),
                                   "small.yaml", ROOT)).modes

    dense, sparse = modes("dense"), modes("sparse")
    assert sparse.method == "null-space/sparse" and len(sparse.spurious) == 0
    assert set(sparse.agreement) == {"kkt-residual", "generalized-inverse-residual"}
    np.testing.assert_allclose(sparse.omega, dense.omega, rtol=1e-8)
    np.testing.assert_allclose(sparse.damping_ratio, dense.damping_ratio, rtol=1e-8)
    assert sparse.damping_ratio.min() > 1e-4  # non-proportionally damped, every mode
    # the generalized-inverse residual carries the round-off of M_d^-1 K u (the stiff part):
    # about eps (omega_max / omega)^2
    assert sparse.agreement["kkt-residual"] < 1e-9 and sparse.residual.max() < 1e-12
    assert sparse.agreement["generalized-inverse-residual"] < 1e-8
    for j in range(len(dense.omega)):
        u, v = dense.shapes[:, j], sparse.shapes[:, j]
        assert np.abs(u - v).max() < 1e-6 * np.abs(u).max()


def test_auto_solves_a_large_damped_model_sparse():
    """A damped rod of 440 coordinates with a damped absorber: ``solver: auto`` takes the
    sparse path (it refused damped models before): the null-space form computes, the KKT and
    generalized-inverse residuals check; a full KKT eigensolve agrees with it."""
    text = """\
name: rod_case
substructures:
  - name: rod
    type: rod
    length: 200
    EA: 6.0e6
    m: 1.0
    discretization: {method: fe, elements: 440}
  - {name: a, type: fixed-free, mass: 1, stiffness: 3000, damping: 5}
connections:
  - [rod@100, a]
analysis:
  modes: {count: 5, check: [null-space, kkt]}
"""
    case = parse_case(text, "rod.yaml", ROOT)
    modes = run_case(case).modes
    assert modes.method == "null-space/sparse" and len(modes.omega) == 5
    assert modes.solver == "sparse-damped" and np.any(modes.damping_ratio > 0)
    assert set(modes.agreement) == {"kkt-residual", "generalized-inverse-residual"}
    assert max(modes.agreement.values()) < 1e-8
    asm = build_model(case).assembly
    full = api.modes(asm.M, asm.C, asm.K, asm.A, 5, method="null-space", checks=("kkt",),
                     full_checks=True)
    assert full.agreement["kkt"] < 1e-9
    np.testing.assert_allclose(full.eigenvalues, modes.eigenvalues, rtol=1e-9)
