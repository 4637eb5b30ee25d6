"""The blocked subspace iteration of AMLS (substruct.linalg.amls_improve) against the textbook
form it replaces: ``W = (K - sigma M)^{-1} M U`` and a full Rayleigh-Ritz after every step,
on whole ``n x p`` arrays.

With more vectors than one column block (``p > SOLVE_COLUMNS``) the blocked form spans the same
subspace (a Cholesky QR between steps instead of a Rayleigh-Ritz changes the basis, not its
span), so the Ritz values agree to round-off of the projected eigenproblem (1e-10 relative,
its condition times eps), the vectors are M-orthonormal (1e-10) and equal the reference's up
to sign on simple eigenvalues.  Only those up to ``lam_max`` come back.  The upper-triangle
projection equals ``W.T @ (A @ W)`` to round-off of the products.

The Chebyshev-shifted steps: their shifts are the roots of ``T_k`` (against NumPy's Chebyshev
series), the blocked shifted form equals the whole-array one, and on AMLS's own Ritz vectors
two shifted steps beat two plain ones in frequency error and residual.

The memory of the rest of AMLS: the reduced eigenproblem dense when many pairs are wanted
(Lanczos otherwise, the same pairs), and the separators' constraint modes kept on disk (the
same modes bit for bit, the scratch directory removed with the reduced model).
"""

from __future__ import annotations

import gc
import tempfile

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp

from substruct.linalg.amls import amls_modes, reduced_eigenpairs, relative_residuals
from substruct.linalg.amls_improve import (
    SOLVE_COLUMNS,
    chebyshev_shifts,
    projection,
    subspace_iteration,
)
from substruct.linalg.amls_reduce import amls_reduce
from substruct.linalg.amls_tree import dissection_tree
from substruct.linalg.factorize import factorizer
from substruct.models.solid import BoxGrid, solid_box


@pytest.fixture(scope="module")
def pencil():
    b = solid_box("b", BoxGrid((4.0, 1.0, 1.0), (16, 4, 4)), 2.1e11, 0.3, 7850.0,
                  fixed=[{"box": [[0, 0, 0], [0, 1, 1]]}])
    K, M = sp.csr_array(b.K), sp.csr_array(b.M)
    lam = sla.eigh(K.toarray(), M.toarray(), eigvals_only=True)
    return K, M, lam


def reference(K, M, U, solve, iterations):
    lam = None
    for _ in range(iterations):
        W = np.asarray(solve(M @ U)).reshape(U.shape)
        kr, mr = W.T @ (K @ W), W.T @ (M @ W)
        lam, rot = sla.eigh((kr + kr.T) / 2, (mr + mr.T) / 2)
        U = W @ rot
    return lam, U


def test_projection_is_the_full_product(pencil):
    K, _, _ = pencil
    W = np.random.default_rng(1).standard_normal((K.shape[0], SOLVE_COLUMNS + 70))
    full = W.T @ (K @ W)
    P = projection(K, W)
    assert np.array_equal(P, P.T)
    assert np.abs(P - full).max() < 1e-12 * np.abs(full).max()


@pytest.mark.parametrize("iterations", [1, 2, 3])
def test_blocked_iteration_equals_the_whole_array_form(pencil, iterations):
    K, M, lam = pencil
    n, p = K.shape[0], SOLVE_COLUMNS + 72          # two column blocks, the second partial
    U0 = np.random.default_rng(0).standard_normal((n, p))
    sigma = -1e-3 * lam[0]
    solve = factorizer("auto")(sp.csc_array(K - sigma * M))
    lam_max = 0.5 * (lam[39] + lam[40])
    ref_lam, ref_U = reference(K, M, U0.copy(), solve, iterations)
    got_lam, got_U = subspace_iteration(K, M, U0.copy(), solve, iterations, lam_max)
    keep = ref_lam <= lam_max
    assert got_lam.size == keep.sum() > 0
    assert np.allclose(got_lam, ref_lam[keep], rtol=1e-10, atol=0)
    assert np.allclose(got_U.T @ (M @ got_U), np.eye(got_lam.size), atol=1e-10)
    simple = np.ones(got_lam.size, dtype=bool)
    close = np.isclose(got_lam[1:], got_lam[:-1], rtol=1e-6)
    simple[1:] &= ~close
    simple[:-1] &= ~close
    R = ref_U[:, keep]
    dots = np.abs(np.einsum("ij,ij->j", got_U, M @ R))[simple]
    assert np.allclose(dots, 1.0, atol=1e-8)
    # Rayleigh-Ritz values: upper bounds of the exact eigenvalues, to the round-off of the
    # dense reference, whose eigenvalues are exact to a few eps times the largest (measured:
    # 10 eps lam_max below on one OpenBLAS kernel, 6 on another); bound 1000 eps lam_max
    floor = 1e3 * np.finfo(float).eps * lam.max()
    assert np.all(got_lam >= lam[:got_lam.size] - floor)


def test_chebyshev_shifts_are_the_roots_of_t_k():
    """prod (theta - x_i) is T_k(2 theta / a - 1) up to a constant (a = 1/(lam_u - sigma)):
    at most 1 in size on [0, a] relative to |T_k| there, equal to it at 40 points."""
    sigma, lam_u = -2.0, 48.0
    a = 1.0 / (lam_u - sigma)
    assert np.array_equal(chebyshev_shifts(1, sigma, lam_u), [0.0])     # one step: plain
    assert np.array_equal(chebyshev_shifts(3, sigma, None), np.zeros(3))
    theta = np.linspace(0, 3 * a, 40)
    for k in (2, 3, 4):
        x = chebyshev_shifts(k, sigma, lam_u)
        assert np.all(np.diff(x) < 0) and np.all((x > 0) & (x < a))
        p = np.prod([theta - xi for xi in x], axis=0)
        t = np.polynomial.chebyshev.chebval(2 * theta / a - 1, [0] * k + [1])
        assert np.allclose(p * 2 ** (2 * k - 1) / a ** k, t, rtol=1e-12, atol=1e-12)
    with pytest.raises(ValueError, match="lam_unwanted"):
        chebyshev_shifts(2, 1.0, 0.5)


@pytest.mark.parametrize("iterations", [2, 3])
def test_shifted_blocked_iteration_equals_the_whole_array_form(pencil, iterations):
    K, M, lam = pencil
    n, p = K.shape[0], SOLVE_COLUMNS + 72
    U0 = np.random.default_rng(2).standard_normal((n, p))
    sigma = -1e-3 * lam[0]
    solve = factorizer("auto")(sp.csc_array(K - sigma * M))
    lam_max, lam_u = 0.5 * (lam[39] + lam[40]), lam[150]
    U = U0.copy()
    for x in chebyshev_shifts(iterations, sigma, lam_u):
        U = np.asarray(solve(M @ U)).reshape(U.shape) - x * U
        U = np.linalg.qr(U)[0]                      # the span only
    kr, mr = U.T @ (K @ U), U.T @ (M @ U)
    ref = sla.eigh((kr + kr.T) / 2, (mr + mr.T) / 2, eigvals_only=True)
    got, V = subspace_iteration(K, M, U0.copy(), solve, iterations, lam_max, sigma=sigma,
                                lam_unwanted=lam_u)
    keep = ref <= lam_max
    assert got.size == keep.sum() > 0
    assert np.allclose(got, ref[keep], rtol=1e-10, atol=0)
    assert np.allclose(V.T @ (M @ V), np.eye(got.size), atol=1e-10)


@pytest.mark.parametrize("iterations", [1, 3])
def test_iteration_from_a_column_file_equals_the_array_form(pencil, iterations, tmp_path):
    """The Ritz vectors in a :class:`ColumnFile` (read and written by blocks of columns: the
    projections block by block, the Cholesky QR's triangular rotation in place from the last
    block, the Ritz rotation by blocks of the result) against the same vectors in memory,
    three column blocks, the last partial: the projections to round-off of the products,
    the same Ritz values (1e-10, the projected eigenproblem's round-off from random vectors;
    measured 5e-12 with three steps, 0 with one) and the same vectors (up to sign, 1e-8, on
    simple eigenvalues)."""
    from substruct.linalg.column_file import ColumnFile

    K, M, lam = pencil
    n, p = K.shape[0], 2 * SOLVE_COLUMNS + 40
    U0 = np.random.default_rng(3).standard_normal((n, p))
    W = ColumnFile(str(tmp_path / "w"), (n, p), SOLVE_COLUMNS)
    for j in range(0, p, SOLVE_COLUMNS):
        W.write(j, U0[:, j:j + SOLVE_COLUMNS])
    assert np.array_equal(W.read(2 * SOLVE_COLUMNS), U0[:, 2 * SOLVE_COLUMNS:])
    with pytest.raises(IndexError, match="no block of 128 columns starts at column 5"):
        W.read(5)
    with pytest.raises(ValueError, match="shape"):
        W.write(0, U0[:, :5])
    full = U0.T @ (K @ U0)
    assert np.abs(projection(K, W) - full).max() < 1e-12 * np.abs(full).max()
    sigma = -1e-3 * lam[0]
    solve = factorizer("auto")(sp.csc_array(K - sigma * M))
    lam_max, lam_u = 0.5 * (lam[59] + lam[60]), lam[200]
    mem, U = subspace_iteration(K, M, U0.copy(), solve, iterations, lam_max, sigma=sigma,
                                lam_unwanted=lam_u)
    got, V = subspace_iteration(K, M, W, solve, iterations, lam_max, sigma=sigma,
                                lam_unwanted=lam_u)
    assert got.size == mem.size > 40
    assert np.allclose(got, mem, rtol=1e-10, atol=0)
    simple = np.ones(got.size, dtype=bool)
    close = np.isclose(got[1:], got[:-1], rtol=1e-6)
    simple[1:] &= ~close
    simple[:-1] &= ~close
    dots = np.abs(np.einsum("ij,ij->j", V, M @ U))[simple]
    assert simple.sum() > 20 and np.allclose(dots, 1.0, atol=1e-8)
    W.close()


def test_chebyshev_steps_improve_the_amls_ritz_values(pencil):
    """On AMLS's own Ritz vectors (cut-off 2, those up to 1.2 x the wanted frequency), two
    Chebyshev-shifted steps on [0, 1/(lam_u - sigma)], lam_u between the Ritz bound and the
    cut-off as amls_modes takes it, against two plain steps: smaller frequency errors, and
    residuals no larger."""
    K, M, lam = pencil
    lam_w = 0.5 * (lam[59] + lam[60])
    bound, lam_c = 1.2 ** 2 * lam_w, 4.0 * lam_w
    red = amls_reduce(K, M, dissection_tree(K, 100), lam_c)
    _, Y = reduced_eigenpairs(red, bound)
    U0 = red.expand(Y)
    sigma = -1e-3 * lam_w
    solve = factorizer("auto")(sp.csc_array(K - sigma * M))
    out = {}
    for name, lam_u in (("plain", None), ("chebyshev", np.sqrt(bound * lam_c))):
        got, V = subspace_iteration(K, M, U0.copy(), solve, 2, lam_w, sigma=sigma,
                                    lam_unwanted=lam_u)
        assert got.size == 60
        out[name] = (np.max(got / lam[:60] - 1), relative_residuals(K, M, got, V).max())
    (e_plain, r_plain), (e_cheb, r_cheb) = out["plain"], out["chebyshev"]
    # measured: largest error 3.9e-4 against 8.6e-4, residual 1.5e-2 against 2.4e-2
    assert e_cheb < 0.6 * e_plain, out
    assert r_cheb <= r_plain, out


@pytest.mark.parametrize("wanted", [20, 60])
def test_reduced_eigenpairs_by_lanczos_equal_the_dense_ones(pencil, monkeypatch, wanted):
    """The reduced pencil's pairs below a bound by Lanczos on its standard form (forced: every
    size, every fraction) and by the dense MRRR solver (the default at this size): the same
    eigenvalues to 1e-10 and the same vectors up to sign (the wanted ones are simple)."""
    from substruct.linalg import amls

    K, M, lam = pencil
    lam_w = 0.5 * (lam[wanted - 1] + lam[wanted])
    red = amls_reduce(K, M, dissection_tree(K, 100), 9.0 * lam_w)
    dense, Yd = reduced_eigenpairs(red, lam_w)
    monkeypatch.setattr(amls, "DENSE_REDUCED", 0)
    monkeypatch.setattr(amls, "LANCZOS_FRACTION", np.inf)
    lanczos, Yl = reduced_eigenpairs(red, lam_w)
    assert dense.size == lanczos.size >= wanted - 2
    assert np.allclose(lanczos, dense, rtol=1e-10, atol=0)
    assert np.allclose(np.abs(np.sum(Yd * (red.M @ Yl), axis=0)), 1.0, atol=1e-8)


def test_reduced_eigenpairs_choose_dense_when_many_pairs_are_wanted(pencil, monkeypatch):
    """Above DENSE_REDUCED, a bound asking for LANCZOS_FRACTION of the reduced size or more
    goes to the dense solver (Lanczos on it would be slower): eigsh is not called."""
    from substruct.linalg import amls

    K, M, lam = pencil
    lam_w = 0.5 * (lam[59] + lam[60])
    red = amls_reduce(K, M, dissection_tree(K, 100), 4.0 * lam_w)
    assert 2 * np.sum(red.lam <= lam_w) >= amls.LANCZOS_FRACTION * red.size
    monkeypatch.setattr(amls, "DENSE_REDUCED", 0)

    def refuse(*args, **kwargs):
        raise AssertionError("Lanczos called")

    monkeypatch.setattr(amls.spla, "eigsh", refuse)
    got, _ = reduced_eigenpairs(red, lam_w)
    # Rayleigh-Ritz values: upper bounds of the exact ones, within AMLS's error at cut-off 2
    exact = lam[:got.size]
    assert got.size >= 55 and np.all(got >= exact * (1 - 1e-12))
    assert np.allclose(got, exact, rtol=0.1)


def test_constraint_modes_kept_on_disk_give_the_same_modes(pencil, monkeypatch, tmp_path):
    """Every separator's constraint modes and every condensation written to a scratch file
    and read back as a memory map (``SPILL_BYTES`` 0; a 10^6-coordinate solid keeps 13 GB of
    constraint modes): the same modes bit for bit, each condensation's file removed once its
    parent has read it, the scratch directory gone with the reduced model."""
    import substruct.linalg.amls_reduce as reduce_module

    K, M, lam = pencil
    w = float(np.sqrt(0.5 * (lam[19] + lam[20])))
    memory = amls_modes(K, M, w, cutoff=3.0, leaf_size=60, iterations=1)
    monkeypatch.setattr(reduce_module, "SPILL_BYTES", 0)
    monkeypatch.setenv("TMPDIR", str(tmp_path))
    tempfile.tempdir = None                 # the temporary directory read again from TMPDIR
    try:
        disk = amls_modes(K, M, w, cutoff=3.0, leaf_size=60, iterations=1)
        root = dissection_tree(K, 60)
        red = reduce_module.amls_reduce(K, M, root, (3.0 * w) ** 2)
        blocks = root.postorder()
        separators = sum(1 for b in blocks if not b.is_leaf and b.dofs.size)
        # the constraint modes, and the two condensations of every block but the root
        assert red.scratch is not None and red.scratch.count == separators + 2 * (len(blocks) - 1)
        assert any(isinstance(b.Psi, np.memmap) for b in red.blocks)
        (directory,) = tmp_path.iterdir()
        assert len(list(directory.iterdir())) == separators   # condensations read: removed
        del red
        gc.collect()
        assert not list(tmp_path.iterdir())  # removed with the model
    finally:
        tempfile.tempdir = None
    assert np.array_equal(memory.lam, disk.lam) and np.array_equal(memory.U, disk.U)
    assert not list(tmp_path.iterdir())


def test_ritz_vectors_iterated_from_a_file_give_the_same_modes(pencil, monkeypatch, tmp_path):
    """The Ritz vectors of the subspace iteration written to a column file (``RITZ_ON_DISK``
    0; from 64 MB on, so that the iteration holds the factorization and a few blocks, not
    the ``n x p`` vectors beside it): the same modes as from memory (eigenvalues to 1e-12,
    one span, the same residuals), the file removed when the modes are made."""
    import substruct.linalg.amls as amls_module

    K, M, lam = pencil
    w = float(np.sqrt(0.5 * (lam[39] + lam[40])))
    memory = amls_modes(K, M, w, cutoff=3.0, leaf_size=60, iterations=2, ritz_ratio=1.5)
    monkeypatch.setattr(amls_module, "RITZ_ON_DISK", 0)
    monkeypatch.setenv("TMPDIR", str(tmp_path))
    tempfile.tempdir = None
    try:
        disk = amls_modes(K, M, w, cutoff=3.0, leaf_size=60, iterations=2, ritz_ratio=1.5)
        assert not isinstance(disk.U, np.memmap) and disk.lam.size == memory.lam.size > 30
        assert np.allclose(memory.lam, disk.lam, rtol=1e-12, atol=0)
        overlap = np.linalg.svd(disk.U.T @ (M @ memory.U), compute_uv=False)
        assert np.abs(overlap - 1).max() < 1e-10
        assert np.allclose(memory.residual, disk.residual, rtol=1e-6, atol=1e-14)
        gc.collect()
        assert all(not list(d.iterdir()) for d in tmp_path.iterdir())
    finally:
        tempfile.tempdir = None


@pytest.mark.parametrize("iterations", [0, 2])
def test_mode_shapes_made_on_disk_are_the_same(pencil, monkeypatch, tmp_path, iterations):
    """Mode shapes larger than the memory (2,000 modes of 2 x 10^6 coordinates are 32 GB)
    are expanded into a column-major file a block of columns at a time and improved there
    (``MODES_ON_DISK`` 0, blocks of 16 columns): the same modes (eigenvalues to round-off,
    the same span: the square cross-section's bending pairs are degenerate, so a pair's
    vectors may turn within it by the round-off of products of other widths), and nothing
    left in the temporary directory once they are collected."""
    import substruct.linalg.amls as amls_module

    K, M, lam = pencil
    w = float(np.sqrt(0.5 * (lam[39] + lam[40])))
    memory = amls_modes(K, M, w, cutoff=3.0, leaf_size=60, iterations=iterations)
    assert memory.lam.size > 16 and not isinstance(memory.U, np.memmap)
    monkeypatch.setattr(amls_module, "MODES_ON_DISK", 0.0)
    monkeypatch.setattr(amls_module, "EXPAND_MEMORY", 0.0)
    monkeypatch.setenv("TMPDIR", str(tmp_path))
    tempfile.tempdir = None
    try:
        disk = amls_modes(K, M, w, cutoff=3.0, leaf_size=60, iterations=iterations)
        assert isinstance(disk.U, np.memmap) and disk.U.flags.f_contiguous
        assert np.allclose(memory.lam, disk.lam, rtol=1e-12, atol=0)
        overlap = np.linalg.svd(disk.U.T @ (M @ memory.U), compute_uv=False)
        assert np.abs(overlap - 1).max() < 1e-10        # M-orthonormal, one span
        assert np.allclose(memory.residual, disk.residual, rtol=1e-6, atol=1e-14)
        del disk
        gc.collect()
        assert not list(tmp_path.iterdir())
    finally:
        tempfile.tempdir = None


def test_subdomain_expansions_in_batches_give_the_same_modes(pencil, monkeypatch):
    """The subdomains' expansions sent in batches of about ``EXPAND_BATCH`` bytes (0: one
    subdomain a batch; all at once, their inputs and results were 3.4 GB beside the 2.4 GB
    vectors of a 297,714-coordinate solid): the same modes bit for bit, each subdomain's
    expansion being its own task either way."""
    import substruct.linalg.amls_reduce as reduce_module

    K, M, lam = pencil
    w = float(np.sqrt(0.5 * (lam[19] + lam[20])))
    whole = amls_modes(K, M, w, cutoff=3.0, leaf_size=60, iterations=1)
    monkeypatch.setattr(reduce_module, "EXPAND_BATCH", 0)
    batched = amls_modes(K, M, w, cutoff=3.0, leaf_size=60, iterations=1)
    assert np.array_equal(whole.lam, batched.lam) and np.array_equal(whole.U, batched.U)
