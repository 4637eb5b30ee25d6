r"""Subspace iteration on the AMLS Ritz vectors with the full factorization, in blocks.

The ``n x p`` Ritz vectors ``U`` (``p`` a few times the wanted number of modes) are the
largest arrays of AMLS; this module keeps them the only ``n x p`` array.  One step is

.. math::  W = (K - \sigma M)^{-1} M U, \qquad
           (W^T K W)\, y = \lambda\, (W^T M W)\, y, \qquad U \leftarrow W y,

which multiplies the error of :math:`\lambda_j` by about
:math:`((\lambda_j - \sigma)/(\lambda_{p+1} - \sigma))^2`, :math:`\lambda_{p+1}` the first
Ritz value left out.  The solves overwrite ``U`` ``SOLVE_COLUMNS`` columns at a time; the projections
are summed by column blocks over the upper triangle only (half the products of the full
``W^T (K W)``); the rotation :math:`W y` is done by row blocks.  Between two steps only the
span matters, so an intermediate step makes :math:`W` ``M``-orthonormal by a Cholesky QR,
:math:`W \leftarrow W R^{-1}`, :math:`R^T R = W^T M W` (one projection, no ``K``-projection,
eigensolve or rotation); the Rayleigh-Ritz is done once, after the last step, for the
eigenpairs up to the wanted one only.

The vectors may be a :class:`~substruct.linalg.column_file.ColumnFile` (blocks of
``SOLVE_COLUMNS`` columns) instead of an array: then every pass reads and writes them a block
of columns at a time (the projections block ``(i, j)`` by block, the rotations by blocks of
the result's columns), and the memory holds a few ``n x SOLVE_COLUMNS`` blocks, not the
``n x p`` vectors.  The same arithmetic up to the order of the sums of the rotations.

**Chebyshev shifts.**  ``k`` plain steps apply :math:`A^k`, :math:`A = (K - \sigma M)^{-1}
M`, which damps an unwanted component of eigenvalue :math:`\theta = 1/(\lambda - \sigma)`
against the wanted mode ``j`` by :math:`(\theta/\theta_j)^k`.  Given an interval
:math:`[0, a]`, :math:`a = 1/(\lambda_u - \sigma)`, that holds the unwanted components which
matter, step ``i`` applies :math:`A - x_i I` instead, the :math:`x_i` the roots of the
Chebyshev polynomial :math:`T_k` mapped onto :math:`[0, a]`,

.. math::  x_i = \tfrac{a}{2}\,\bigl(1 + \cos\tfrac{(2i - 1)\pi}{2k}\bigr), \qquad
           \prod_i (A - x_i I) \propto T_k\!\bigl(\tfrac{2A}{a} - I\bigr),

the polynomial of degree ``k`` least on :math:`[0, a]` (at most 1 in size) for its growth
above it: an unwanted component is damped by :math:`1/T_k(2\theta_j/a - 1)` instead of
:math:`(\theta/\theta_j)^k`.  For a wanted mode at :math:`\lambda_u = 2.25 \lambda_j`, two
steps give 0.043 against :math:`2.25^{-2} = 0.198`.  Each step is one solve per vector and an
``axpy`` (no extra ``n x p`` array), and since :math:`(A - x I)(W R) = ((A - x I) W) R` the
Cholesky QR between steps does not change the filter.  Components above :math:`a`
(unwanted eigenvalues below :math:`\lambda_u`) are amplified, less than the wanted ones
above them: the filter degrades gracefully and never favours an unwanted mode over a wanted
one.  AMLS chooses :math:`\lambda_u` (:func:`substruct.linalg.amls.amls_modes`).

A single step stays the plain one: :math:`T_1` leaves the high-frequency components
(:math:`\theta \to 0`) as large as the wanted ones shrink them, and the residual
:math:`\|K u - \lambda M u\|` weighs them by :math:`K`.  Measured on 500 modes of a
29,400-coordinate box (docs/amls.md): one shifted step lowers the largest frequency error from
7.8e-4 to 4.8e-4 but raises the largest residual from 5.7e-2 to 7.0e-2; two shifted steps
lower both (2.1e-4 to 7.6e-5, 1.9e-2 to 1.2e-2).
"""

from __future__ import annotations

from typing import Callable

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from substruct.linalg.column_file import ColumnFile
from substruct.linalg.factorize import Solve

__all__ = ["SOLVE_COLUMNS", "ROWS", "Vectors", "chebyshev_shifts", "columns", "filter_steps",
           "projection", "ritz_pairs", "subspace_iteration"]

#: ``n x p`` vectors: in memory, or in a file read and written by blocks of columns.
Vectors = np.ndarray | ColumnFile

#: Columns of an ``n x p`` block of vectors handled at once (solves, sparse products,
#: residuals): the temporaries are ``n x SOLVE_COLUMNS``, not ``n x p``.
SOLVE_COLUMNS = 128

#: Rows of an ``n x p`` block rotated at once.
ROWS = 4096


def columns(W: Vectors, a: int, b: int) -> np.ndarray:
    """A new C-ordered array of the columns ``a:b`` of ``W`` (of a file: ``a`` the first column
    of one of its blocks, which must be ``SOLVE_COLUMNS`` wide, and ``b`` that block's end)."""
    if isinstance(W, ColumnFile):
        if W.width != SOLVE_COLUMNS:
            raise ValueError(f"a column file of blocks of {SOLVE_COLUMNS} columns is needed, "
                             f"got {W.width}")
        return W.read(a)
    return np.ascontiguousarray(W[:, a:b])


def _put(W: Vectors, a: int, block: np.ndarray) -> None:
    if isinstance(W, ColumnFile):
        W.write(a, block)
    else:
        W[:, a:a + block.shape[1]] = block


def projection(A: sp.csr_array, W: Vectors) -> np.ndarray:
    r""":math:`W^T A W` for a symmetric sparse ``A``, summed by blocks of ``SOLVE_COLUMNS`` columns
    over the upper triangle (block ``j``: :math:`W_{:, :j+c}^T (A W_{:, j:j+c})`), then
    mirrored: half the dense products of ``W.T @ (A @ W)`` and an ``n x SOLVE_COLUMNS`` temporary
    (from a file: the products of block ``i <= j`` one at a time, each block read again)."""
    p = W.shape[1]
    out = np.empty((p, p))
    for j in range(0, p, SOLVE_COLUMNS):
        e = min(j + SOLVE_COLUMNS, p)
        Wj = columns(W, j, e)
        AW = A @ Wj
        if isinstance(W, ColumnFile):
            for i in range(0, j, SOLVE_COLUMNS):
                out[i:i + SOLVE_COLUMNS, j:e] = columns(W, i, i + SOLVE_COLUMNS).T @ AW
            out[j:e, j:e] = Wj.T @ AW
        else:
            out[:e, j:e] = W[:, :e].T @ AW
    upper = np.triu(out)
    return upper + np.triu(upper, 1).T


def _rotate(W: np.ndarray, R: np.ndarray, out: np.ndarray) -> None:
    """``out = W @ R`` by row blocks (``out`` may be ``W`` itself when ``R`` is square)."""
    for i in range(0, W.shape[0], ROWS):
        out[i:i + ROWS] = W[i:i + ROWS] @ R


def _rotate_columns(W: ColumnFile, R: np.ndarray, out: Vectors, upper: bool = False) -> None:
    """``out = W @ R`` by blocks of ``out``'s columns, each the sum of the products of ``W``'s
    blocks; with ``upper`` (``R`` upper triangular, ``out`` may be ``W``) only the blocks at
    or above the diagonal, the last block first, so that each is written after every block it
    needs was read."""
    p, k = R.shape
    starts = range(0, k, SOLVE_COLUMNS)
    for j in reversed(starts) if upper else starts:
        e = min(j + SOLVE_COLUMNS, k)
        acc = np.zeros((W.shape[0], e - j))
        for i in range(0, e if upper else p, SOLVE_COLUMNS):
            acc += columns(W, i, i + SOLVE_COLUMNS) @ R[i:i + SOLVE_COLUMNS, j:e]
        _put(out, j, acc)


def _orthonormalize(M: sp.csr_array, W: Vectors) -> None:
    r"""``W`` made ``M``-orthonormal in place, same span: Cholesky QR of the column-scaled
    ``W`` (:math:`G = W^T M W = R^T R`, :math:`W \leftarrow W R^{-1}`)."""
    G = projection(M, W)
    s = 1.0 / np.sqrt(np.diag(G))
    R = sla.cholesky(G * s[:, None] * s[None, :])
    T = s[:, None] * sla.solve_triangular(R, np.eye(R.shape[0]))
    if isinstance(W, ColumnFile):
        _rotate_columns(W, T, W, upper=True)
    else:
        _rotate(W, T, W)


def chebyshev_shifts(iterations: int, sigma: float, lam_unwanted: float | None
                     ) -> np.ndarray:
    r"""The shifts :math:`x_i` of the ``iterations`` steps (module docstring), descending; all
    zero (plain subspace iteration) when ``lam_unwanted`` (:math:`\lambda_u`) is ``None`` or for
    a single step."""
    if lam_unwanted is None or iterations == 1:
        return np.zeros(iterations)
    if not lam_unwanted > sigma:
        raise ValueError(f"lam_unwanted must exceed the shift {sigma!r}, got {lam_unwanted!r}")
    a = 1.0 / (lam_unwanted - sigma)
    i = np.arange(1, iterations + 1)
    return 0.5 * a * (1.0 + np.cos((2 * i - 1) * np.pi / (2 * iterations)))


def filter_steps(M: sp.csr_array, W: Vectors, solve: Solve, shifts: np.ndarray,
                 say: Callable[[str], None] | None = None) -> None:
    r"""The steps of the subspace iteration on the ``n x p`` vectors ``W``, in place: step
    ``i`` is :math:`W \leftarrow (K - \sigma M)^{-1} M W - x_i W` (``solve``:
    :math:`(K - \sigma M)^{-1}`; ``shifts``: the :math:`x_i`, :func:`chebyshev_shifts`), the
    steps kept apart by a Cholesky QR; the span is what counts."""
    p = W.shape[1]
    for it, x in enumerate(shifts):
        if it:
            _orthonormalize(M, W)
        for j in range(0, p, SOLVE_COLUMNS):
            Wj = columns(W, j, j + SOLVE_COLUMNS)
            Y = np.asarray(solve(M @ Wj)).reshape(Wj.shape)
            if x:
                Y -= x * Wj
            _put(W, j, Y)
        if say is not None:
            say(f"AMLS subspace iteration {it + 1}: {p} vectors")


def subspace_iteration(K: sp.csr_array, M: sp.csr_array, U: Vectors, solve: Solve,
                       iterations: int, lam_max: float,
                       say: Callable[[str], None] | None = None,
                       sigma: float = 0.0, lam_unwanted: float | None = None
                       ) -> tuple[np.ndarray, np.ndarray]:
    r"""``iterations`` (>= 1) steps of subspace iteration on the ``n x p`` vectors ``U``
    (module docstring; :func:`filter_steps`; ``solve``: :math:`(K - \sigma M)^{-1}`), then the
    Rayleigh-Ritz eigenpairs with :math:`\lambda \le` ``lam_max`` (:func:`ritz_pairs`).  ``U``
    is overwritten.  With ``lam_unwanted`` (:math:`\lambda_u`; ``sigma``: the shift ``solve``
    was factorized with) the steps are Chebyshev-shifted (:func:`chebyshev_shifts`).  (A caller
    that can free the factorization between the two calls them one after the other.)"""
    filter_steps(M, U, solve, chebyshev_shifts(iterations, sigma, lam_unwanted), say)
    return ritz_pairs(K, M, U, lam_max)


def ritz_pairs(K: sp.csr_array, M: sp.csr_array, W: Vectors, lam_max: float,
               allocate: Callable[[tuple[int, int]], np.ndarray] = np.empty
               ) -> tuple[np.ndarray, np.ndarray]:
    r"""The Rayleigh-Ritz eigenpairs of ``(K, M)`` on the span of ``W`` with
    :math:`\lambda \le` ``lam_max``, ascending, ``M``-orthonormal; the memory is ``W``, the
    ``n x k`` result (made by ``allocate``: on disk for modes larger than the memory) and
    ``n x SOLVE_COLUMNS`` temporaries."""
    n = W.shape[0]
    Mp = projection(M, W)
    s = 1.0 / np.sqrt(np.diag(Mp))    # unit columns: W's scale by about 1 / lambda_j
    lam, rot = sla.eigh(projection(K, W) * s[:, None] * s[None, :],
                        Mp * s[:, None] * s[None, :], overwrite_a=True, overwrite_b=True,
                        subset_by_value=(-np.inf, lam_max), driver="gvx")
    out = allocate((n, lam.size))
    if isinstance(W, ColumnFile):
        _rotate_columns(W, s[:, None] * rot, out)
    else:
        _rotate(W, s[:, None] * rot, out)
    return lam, out
