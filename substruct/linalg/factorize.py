r"""The sparse factorizations, in one registry: ``factorizer(kind)(A)`` is a solve ``b -> A^{-1} b``.

Every shift-invert eigensolve, static condensation and frequency sweep of the package gets its
factorization here, never from ``eigsh(sigma=...)`` itself (DESIGN.md section 6: on 95k
coordinates the factorization ``eigsh`` makes took 279 s and 5.5 GB, SuperLU in symmetric mode
27.6 s, CHOLMOD 13.0 s).

=================  ===========================================================================
kind               matrices and method
=================  ===========================================================================
``"superlu"``      SPD: SuperLU in symmetric mode (``MMD_AT_PLUS_A`` ordering, diagonal pivots,
                   ``diag_pivot_thresh = 0``); otherwise partial pivoting, same ordering
``"cholmod"``      SPD only: supernodal Cholesky (scikit-sparse, when installed)
``"auto"``         CHOLMOD when importable and the matrix is SPD, else ``"superlu"``
``"saddle"``       symmetric indefinite saddle points ``[B, A^T; A, 0]`` (KKT): symmetric mode
                   with threshold pivoting (``diag_pivot_thresh = 0.1``)
``"complex-lu"``   any square matrix, real or complex (the impedances of frequency sweeps):
                   SuperLU with its default ``COLAMD`` ordering and partial pivoting
=================  ===========================================================================

Frequency sweeps of one structure factorize matrices of one sparsity pattern many times:
:func:`fill_ordering` computes a fill-reducing symmetric ordering once and
:func:`complex_symmetric` factorizes each (complex symmetric, not Hermitian) impedance in that
order, so SuperLU skips its ordering step at every frequency.

SuperLU factors real matrices in real arithmetic; a complex right-hand side is solved as its
real and imaginary parts.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

__all__ = [
    "FACTORIZATIONS",
    "KINDS",
    "Factorize",
    "Solve",
    "cholmod",
    "complex_lu",
    "complex_symmetric",
    "factorizer",
    "fill_ordering",
    "has_cholmod",
    "superlu",
    "superlu_saddle",
    "superlu_spd",
]

#: A solve ``b -> A^{-1} b`` (``b`` a vector or an ``n x k`` block).
Solve = Callable[[np.ndarray], np.ndarray]
#: A factorization ``A -> Solve``.
Factorize = Callable[[sp.sparray], Solve]

#: The factorizations of symmetric positive definite matrices a user may choose by name.
FACTORIZATIONS = ("superlu", "cholmod", "auto")
#: Every name :func:`factorizer` accepts.
KINDS = FACTORIZATIONS + ("saddle", "complex-lu")


def _solver(lu: spla.SuperLU, A: sp.spmatrix) -> Solve:
    """``lu.solve``, with a complex right-hand side split when the factors (of ``A``) are
    real."""
    real = not np.iscomplexobj(A.data)

    def solve(b: np.ndarray) -> np.ndarray:
        b = np.asarray(b)
        if real and np.iscomplexobj(b):
            return lu.solve(np.ascontiguousarray(b.real)) + \
                1j * lu.solve(np.ascontiguousarray(b.imag))
        return lu.solve(b)

    return solve


def superlu(A: sp.sparray | sp.spmatrix) -> Solve:
    """SuperLU with the ``MMD_AT_PLUS_A`` ordering and partial pivoting (any square ``A``)."""
    Ac = sp.csc_matrix(A)
    return _solver(spla.splu(Ac, permc_spec="MMD_AT_PLUS_A"), Ac)


def superlu_spd(A: sp.sparray | sp.spmatrix) -> Solve:
    """SuperLU in symmetric mode for symmetric positive definite ``A``: ``MMD_AT_PLUS_A``
    ordering, diagonal pivots (``diag_pivot_thresh=0``, stable for SPD).  Same fill as with
    partial pivoting, 5 times faster on 3D elasticity (30k DOF: 14 s instead of 80 s)."""
    Ac = sp.csc_matrix(A)
    return _solver(spla.splu(Ac, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                             options={"SymmetricMode": True}), Ac)


def superlu_saddle(A: sp.sparray | sp.spmatrix) -> Solve:
    r"""SuperLU of a symmetric saddle-point matrix :math:`[B, A^T; A, 0]`: symmetric mode with
    threshold pivoting (``diag_pivot_thresh=0.1``), diagonal pivots where they are large enough,
    off-diagonal ones for the zero block; 4 times faster than partial pivoting on 3D elasticity
    with ties (10k DOF), same residual."""
    Ac = sp.csc_matrix(A)
    return _solver(spla.splu(Ac, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.1,
                             options={"SymmetricMode": True}), Ac)


def complex_lu(A: sp.sparray | sp.spmatrix) -> Solve:
    r"""SuperLU of a general square matrix, real or complex, with the ``COLAMD`` ordering and
    partial pivoting: the impedance :math:`Z = K - \omega^2 M + i \omega C` of a frequency
    sweep and the bordered systems built on it (not symmetric, not definite)."""
    Ac = sp.csc_matrix(A)
    return _solver(spla.splu(Ac), Ac)


def fill_ordering(pattern: sp.sparray | sp.spmatrix) -> np.ndarray:
    r"""A fill-reducing symmetric ordering of a square sparse matrix: SuperLU's
    ``MMD_AT_PLUS_A`` column permutation (minimum degree on :math:`|A| + |A|^T`), taken from a
    factorization (one a sweep) of a matrix with ``pattern``'s structure and a dominant
    diagonal (unit off-diagonal entries, diagonal the row count, so no pivoting moves it)."""
    P = sp.csc_matrix(abs(sp.csc_matrix(pattern)))
    P = sp.csc_matrix(P + P.T)
    P.data[:] = 1.0
    n = P.shape[0]
    A = sp.csc_matrix(P + sp.diags(np.asarray(P.sum(axis=1)).ravel() + 1.0))
    lu = spla.splu(A, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                   options={"SymmetricMode": True})
    # SuperLU factorizes Pr A Pc with Pc[i, perm_c[i]] = 1: column j of A Pc is column
    # argsort(perm_c)[j] of A, so that is the order A[order][:, order] must take
    order = np.argsort(np.asarray(lu.perm_c, dtype=np.int64))
    return order if order.size == n else np.arange(n)


def complex_symmetric(A: sp.sparray | sp.spmatrix, order: np.ndarray | None = None, *,
                      ordered: bool = False) -> Solve:
    r"""SuperLU of a complex symmetric matrix (the impedance
    :math:`Z = K - \omega^2 M + i \omega C` in a null-space basis) in the symmetric ordering
    ``order`` (:func:`fill_ordering`; computed here if ``None``): ``A[order][:, order]``
    factorized in natural order, symmetric mode, threshold pivoting preferring the diagonal
    (``diag_pivot_thresh = 0.1``, as the saddle-point systems).  ``ordered``: ``A`` is
    already in its order (a sweep permutes its matrices once), nothing is permuted here."""
    Ac = sp.csc_matrix(A)
    if ordered:
        return _solver(spla.splu(Ac, permc_spec="NATURAL", diag_pivot_thresh=0.1,
                                 options={"SymmetricMode": True}), Ac)
    p = fill_ordering(Ac) if order is None else np.asarray(order)
    inner = complex_symmetric(Ac[p][:, p], ordered=True)
    inverse = np.empty_like(p)
    inverse[p] = np.arange(p.size)

    def solve(b: np.ndarray) -> np.ndarray:
        return inner(np.asarray(b)[p])[inverse]

    return solve


def cholmod(A: sp.sparray | sp.spmatrix) -> Solve:
    """CHOLMOD supernodal Cholesky (scikit-sparse), for symmetric positive definite ``A``; a
    complex right-hand side is solved as its real and imaginary parts."""
    from sksparse.cholmod import cholesky  # optional dependency

    factor = cholesky(sp.csc_matrix(A))

    def solve(b: np.ndarray) -> np.ndarray:
        b = np.asarray(b)
        if np.iscomplexobj(b):  # real factors: CHOLMOD refuses a complex right-hand side
            return factor(np.ascontiguousarray(b.real)) + \
                1j * factor(np.ascontiguousarray(b.imag))
        return factor(b)

    return solve


def has_cholmod() -> bool:
    """Whether scikit-sparse's CHOLMOD can be imported."""
    try:
        import sksparse.cholmod  # noqa: F401
    except ImportError:
        return False
    return True


def factorizer(kind: str | Factorize = "auto", spd: bool = True) -> Factorize:
    """A factorization ``A -> (b -> A^{-1} b)`` by name, or the callable given.

    Args:
        kind: one of :data:`KINDS` (see the module docstring) or a callable.
        spd: for ``"superlu"``, ``"cholmod"`` and ``"auto"``: whether the matrices will be
            symmetric positive definite (CHOLMOD needs it; SuperLU then pivots on the diagonal).

    Raises:
        ValueError: an unknown name, ``"cholmod"`` without scikit-sparse or for a matrix that is
            not SPD.
    """
    if callable(kind):
        return kind
    if kind == "superlu":
        return superlu_spd if spd else superlu
    if kind == "cholmod":
        if not spd:
            raise ValueError("CHOLMOD needs a symmetric positive definite matrix; the "
                             "saddle-point (KKT) systems need 'superlu'")
        if not has_cholmod():
            raise ValueError("factorization 'cholmod' needs scikit-sparse (pip install "
                             "scikit-sparse, with libsuitesparse-dev)")
        return cholmod
    if kind == "auto":
        if spd:
            return cholmod if has_cholmod() else superlu_spd
        return superlu
    if kind == "saddle":
        return superlu_saddle
    if kind == "complex-lu":
        return complex_lu
    raise ValueError(f"unknown factorization {kind!r}; expected one of "
                     f"{', '.join(FACTORIZATIONS)} or a callable")
