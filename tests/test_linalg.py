"""substruct.linalg: equilibration, rank and consistency, null-space bases, factorizations.

Every decision on a constraint row must be the same whatever the row's scale (``c a_i`` for
``c = 1e-300 .. 1e300``), answers are checked against closed forms, and every factorization of
the registry solves its kind of system to rounding.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import substruct.linalg as la
from substruct.linalg import factorize as fz

from tolerances import backward_bound, row_scale

TINY, HUGE = 1e-300, 1e300


def test_the_plain_two_norm_of_a_tiny_row_underflows():
    """The trap the equilibration avoids: ``sqrt(sum a^2)`` of ``1e-300`` is 0."""
    assert np.linalg.norm([TINY, 0.0]) == 0.0


@pytest.mark.parametrize("sparse", [False, True])
def test_rows_are_scaled_to_unit_norm_by_powers_of_two(sparse):
    A = np.array([[TINY, 0, 0], [0, 3.0, -4.0], [HUGE, HUGE, 0], [1.0, -1.0, 0]])
    b = np.array([2 * TINY, 5.0, HUGE, 0.0])
    eq = la.equilibrate(sp.csr_array(A) if sparse else A, b)
    As = eq.A.toarray() if sparse else eq.A
    norms = np.linalg.norm(As, axis=1)
    assert np.all((norms >= 2**-0.5) & (norms <= 2**0.5))
    # powers of two: the scaled entries carry the bits of the originals (1 - 1 stays exact)
    d = np.ldexp(1.0, -eq.scale.exponent)
    assert np.array_equal(As, A * d[:, None]) and np.array_equal(eq.b, b * d)
    assert As[3, 0] == -As[3, 1]
    np.testing.assert_allclose(eq.scale.norms, [TINY, 5.0, np.sqrt(2) * HUGE, np.sqrt(2)])
    # the same solutions: row i of A x = b holds exactly when it holds for D A x = D b (here
    # x = (2, 1, -1/2) satisfies the first two rows and not the others)
    x = np.array([2.0, 1.0, -0.5])
    # (products and sums of these entries are exact, so any BLAS gives the same hits)
    hit = np.isclose(A @ x, b, rtol=1e-15, atol=0)
    assert hit.tolist() == [True, True, False, False]
    assert np.isclose(As @ x, eq.b, rtol=1e-15, atol=0).tolist() == hit.tolist()


def test_a_zero_row_is_refused_with_its_name():
    A = sp.csr_array(np.array([[1.0, 2.0], [0.0, 0.0], [0.0, 0.0]]))
    with pytest.raises(la.ZeroRowError, match="'tie' .* 1 more") as info:
        la.equilibrate(A, labels=["a", "tie", "b"])
    assert info.value.rows == [1, 2]
    kept = la.row_scale(A, keep_zero=True)
    assert kept.exponent.tolist()[1:] == [0, 0] and kept.norms[1] == 0.0


@pytest.mark.parametrize("scale", [1.0, 1e-8, TINY, HUGE])
def test_rank_and_redundancy_do_not_depend_on_the_scale_of_a_row(scale):
    """Rows: q1 - q2, q2 - q3, scale (q1 - q3) (redundant: the sum of the first two), q4."""
    A = np.array([[1.0, -1, 0, 0], [0, 1, -1, 0], [scale, 0, -scale, 0], [0, 0, 0, 2.0]])
    rows = la.independent_rows(A)
    assert rows.rank == 3 and rows.dropped.size == 1
    # W A_keep reproduces A_dropped to the backward error of the factorization that found W:
    # c k eps |W| |A_keep| (k = 4 columns), row by row
    W, keep = rows.combination, A[rows.keep]
    bound = backward_bound(A.shape[1]) * (abs(W) @ abs(keep)).max(axis=1, keepdims=True)
    assert np.all(abs(W @ keep - A[rows.dropped]) <= bound)
    # consistent right-hand sides (those of x = (3, 2, 0, 1)) pass; a change of 1e-6 relative
    # on any of the three dependent rows is caught, on the tiny row as on the others; the
    # independent row q4 may have any right-hand side
    x = np.array([3.0, 2.0, 0.0, 1.0])
    b = A @ x
    la.check_consistent(A, b, rows)
    odd = b.copy()
    odd[3] += 1.0
    la.check_consistent(A, odd, rows)
    for i in range(3):
        bad = b.copy()
        bad[i] += 1e-6 * abs(A[i]).max() * 3
        with pytest.raises(la.ConstraintError, match="inconsistent"):
            la.check_consistent(A, bad, rows, labels=["r0", "r1", "r2", "r3"])


def test_mass_scaled_columns():
    M = sp.diags_array([1.0, 4.0, 0.0, 1.0])
    c = la.mass_column_scale(M)
    mean = 2.0  # of the coordinates with mass
    np.testing.assert_allclose(c, np.sqrt(mean / np.array([1.0, 4.0, mean, 1.0])))
    np.testing.assert_array_equal(la.mass_column_scale(np.eye(3) * 7.0), np.ones(3))
    np.testing.assert_array_equal(la.massless_coordinates(M), [False, False, True, False])
    # a row that is dependent in the mass metric only to 1e-12 is still independent
    A = np.array([[1.0, 0, 0, 0], [1.0, 1e-13, 0, 0]])
    assert la.independent_rows(A).rank == 1
    assert la.independent_rows(A, col_scale=np.array([1.0, 1e4, 1, 1])).rank == 2


def test_particular_solution_is_the_minimum_norm_one():
    A = np.array([[TINY, TINY, 0.0], [0.0, 0.0, 2.0], [0.0, 0.0, 4.0]])
    rhs = np.array([2 * TINY, 6.0, 12.0])
    x = la.particular_solution(A, rhs).ravel()
    # the equilibrated independent rows have condition number sqrt(2): the error of the
    # minimum-norm solution is a few c n eps relative, on the tiny row as on the others
    np.testing.assert_allclose(x, [1.0, 1.0, 3.0], rtol=backward_bound(3))


@pytest.mark.parametrize("scale", [1.0, TINY])
def test_dense_null_space_basis(scale):
    A = np.array([[scale, 0, 0, 0], [0, 1.0, -1.0, 0], [0, 2.0, -2.0, 0]])
    N = la.null_space_basis(A)
    assert N.shape == (4, 2)
    n = A.shape[1]
    np.testing.assert_allclose(N.T @ N, np.eye(2), atol=backward_bound(n))
    # each row's residual is bounded by its own scale (an SVD of the equilibrated rows is
    # backward stable row by row): the row of 1e-300 is held to 1e-300 x c n eps, the unit
    # rows to c n eps x their norm, whatever the kernel's order of summation
    bound = backward_bound(n) * row_scale(A)[:, None]
    assert np.all(abs(A @ N) <= bound), (abs(A @ N), bound)
    # null(A) = span{(0, 1, 1, 0), (0, 0, 0, 1)}
    P = N @ N.T
    ref = np.array([[0, 1, 1, 0], [0, 0, 0, np.sqrt(2)]]).T / np.sqrt(2)
    np.testing.assert_allclose(P, ref @ ref.T, atol=backward_bound(n))


@pytest.mark.parametrize("scale", [1.0, 1e-8, TINY])
def test_master_slave_eliminates_a_tiny_row_like_a_unit_one(scale):
    A = sp.csr_array(np.array([[scale, 0, 0, 0, 0], [0, 1.0, -1.0, 0, 0],
                               [0, 0, 0, 0, 0], [0, 2.0, -2.0, 0, 0]]))
    el = la.master_slave(A)
    assert el.rank == 2 and el.slaves[0] == 0
    assert el.dropped_rows.tolist() == [2, 3]  # the empty row and the redundant one
    assert abs(A @ el.T).max() == 0.0


def test_master_slave_with_column_scale_keeps_unit_masters():
    rng = np.random.default_rng(3)
    A = sp.random_array((4, 12), density=0.4, random_state=rng, format="csr")
    c = np.exp(rng.normal(size=12))
    el = la.master_slave(A, col_scale=c)
    assert el.rank == 4
    # T = [I; -A_s^-1 A_m] (permuted): A T is the residual of the slave solve, bounded by
    # c n eps cond(A_s) |A| |T|
    T = el.T.toarray()
    cond = np.linalg.cond(A.toarray()[:, el.slaves])
    bound = backward_bound(12) * cond * (abs(A.toarray()) @ abs(T)).max()
    assert abs(A @ el.T).max() <= bound
    np.testing.assert_array_equal(el.T[el.masters].toarray(), np.eye(8))


def test_pinv_sym_with_a_rank():
    S = np.diag([1.0, 1e-12, 0.0])
    # by a relative cut the 1e-12 is taken for zero; by the rank decided elsewhere it is not
    np.testing.assert_allclose(la.pinv_sym(S), np.diag([1.0, 0, 0]))
    np.testing.assert_allclose(la.pinv_sym(S, rank=2), np.diag([1.0, 1e12, 0]), rtol=1e-12)
    # a rank above what S holds does not invert its rounding
    np.testing.assert_allclose(la.pinv_sym(S, rank=3), np.diag([1.0, 1e12, 0]), rtol=1e-12)


def test_spectral_norm_closed_forms():
    assert la.spectral_norm(np.diag([3.0, -4.0])) == pytest.approx(4.0, rel=backward_bound(2))
    big = sp.diags_array(np.linspace(1.0, 7.0, 500)).tocsr()  # > 400 rows: Lanczos
    assert la.spectral_norm(big) == pytest.approx(7.0, rel=1e-6)
    assert la.spectral_norm(sp.csr_array((0, 5))) == 1.0


def laplacian(n: int) -> sp.csc_array:
    return sp.csc_array(sp.diags_array([-np.ones(n - 1), 2 * np.ones(n), -np.ones(n - 1)],
                                       offsets=[-1, 0, 1]))


@pytest.mark.parametrize("kind", ["superlu", "auto"])
def test_spd_factorizations_solve(kind):
    K = laplacian(50)
    x = np.linspace(0.0, 1.0, 50)
    solve = la.factorizer(kind)(K)
    np.testing.assert_allclose(solve(K @ x), x, atol=1e-12)
    # complex right-hand side on real factors
    np.testing.assert_allclose(solve(K @ (x + 2j * x)), x + 2j * x, atol=1e-12)


def test_saddle_and_complex_factorizations_solve():
    n = 30
    K = laplacian(n)
    A = sp.csr_array(([1.0, -1.0], ([0, 0], [3, 17])), shape=(1, n))
    big = sp.block_array([[K, A.T], [A, None]], format="csc")
    x = np.r_[np.sin(np.arange(n)), 0.5]
    np.testing.assert_allclose(la.factorizer("saddle")(big)(big @ x), x, atol=1e-12)
    Z = sp.csc_array(K - 0.3 * sp.eye_array(n) + 0.1j * sp.eye_array(n))
    z = np.exp(1j * np.arange(n))
    np.testing.assert_allclose(la.factorizer("complex-lu")(Z)(Z @ z), z, atol=1e-12)
    np.testing.assert_allclose(la.factorizer("superlu", spd=False)(Z)(Z @ z), z, atol=1e-12)


def test_factorizer_names(monkeypatch):
    mine = fz.superlu
    assert la.factorizer(mine) is mine
    assert la.factorizer("superlu") is fz.superlu_spd
    monkeypatch.setattr(fz, "has_cholmod", lambda: False)
    with pytest.raises(ValueError, match="unknown factorization 'mumps'"):
        la.factorizer("mumps")
    with pytest.raises(ValueError, match="needs scikit-sparse"):
        la.factorizer("cholmod")


def test_fill_ordering_gives_superlu_its_own_fill():
    """A matrix taken in :func:`fill_ordering`'s order and factorized in natural order fills as
    much as SuperLU's own ``MMD_AT_PLUS_A`` run on it (the order is the inverse of ``perm_c``:
    taking ``perm_c`` itself gave six times the fill on a 3D mesh), and
    :func:`complex_symmetric` solves in it."""
    from skfem import MeshHex

    from substruct.linalg.factorize import complex_symmetric, fill_ordering
    from substruct.models.elasticity import elasticity_matrices

    mesh = MeshHex.init_tensor(*(np.linspace(0, 1, 9),) * 3)
    _, K, M = elasticity_matrices(mesh, 1, 1.0, 0.5, 1.0, 1.0)
    Z = sp.csc_matrix(K - 3.0 * M + 0.5j * M)
    p = fill_ordering(abs(K) + abs(M))
    ordered = spla.splu(sp.csc_matrix(Z[p][:, p]), permc_spec="NATURAL", diag_pivot_thresh=0.1,
                        options={"SymmetricMode": True})
    own = spla.splu(Z, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.1,
                    options={"SymmetricMode": True})
    assert ordered.L.nnz + ordered.U.nnz <= 1.05 * (own.L.nnz + own.U.nnz)
    b = np.random.default_rng(0).standard_normal(Z.shape[0])
    x = complex_symmetric(Z, p)(b)
    assert np.abs(Z @ x - b).max() < 1e-10 * np.abs(b).max()
