r"""The invariant subspace of a cluster of roots whose eigenvectors are (nearly) parallel: a
defective root (a critically damped mode, ``zeta = 1``: the double root ``-omega`` has one
eigenvector) or two roots split by less than the accuracy of their vectors.

The modal sum of a cluster (:mod:`substruct.analysis.frf.clusters`) is exact on any basis
:math:`X_c` of the cluster's invariant subspace of the symmetric first-order pencil

.. math::  \mathcal{A} = \begin{bmatrix} -K & 0 \\ 0 & M \end{bmatrix}, \qquad
           \mathcal{B} = \begin{bmatrix} C & M \\ M & 0 \end{bmatrix}, \qquad
           x = \begin{bmatrix} u \\ v \end{bmatrix},

.. math::  G_B = X_c^T \mathcal{B} X_c = U^T C U + U^T M V + V^T M U, \qquad
           G_A = X_c^T \mathcal{A} X_c = V^T M V - U^T K U ,

but the eigenvectors of a defective root span only part of it (a Jordan block of order 2 has
one eigenvector :math:`x_0` and a principal vector :math:`x_1`,
:math:`(\mathcal{A} - \lambda_0 \mathcal{B}) x_1 = \mathcal{B} x_0`), and ``G_B`` on them is
singular.  The subspace itself is well conditioned when the cluster is apart from the other
roots, and block inverse iteration about a shift :math:`\sigma` beside the cluster finds it,

.. math::  (\mathcal{A} - \sigma \mathcal{B})\, Y = \mathcal{B} X :\qquad
           Q(\sigma)\, Y_u - A^T \mu = -(C X_u + M X_v + \sigma M X_u), \quad A Y_u = 0,
           \quad Y_v = \sigma Y_u + X_u ,

:math:`Q(\sigma) = \sigma^2 M + \sigma C + K` (one sparse factorization of the constrained
:math:`Q(\sigma)`, a back-substitution per column and step), each step orthonormalized; it
converges by :math:`|\lambda_0 - \sigma| / |\lambda_{other} - \sigma|` a step, whatever the
Jordan structure inside the cluster.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from substruct.analysis.errors import AnalysisInputError
from substruct.analysis.frf.clusters import CLUSTER_CAP, Cluster
from substruct.linalg.constraints import independent_rows
from substruct.linalg.factorize import factorizer

__all__ = ["PARALLEL", "SHIFT", "cluster_subspace", "complete_clusters"]

#: A cluster's state vectors (columns at unit norm) whose smallest singular value is below this
#: fraction of the largest are nearly parallel: their invariant subspace is found again.
PARALLEL = 1e-2
#: The shift of the inverse iteration, this fraction of ``|lambda_0|`` beside the cluster.
SHIFT = 1e-3
#: Most steps of the inverse iteration, and the change of the subspace that ends it.
STEPS, SETTLED = 60, 1e-13


def _orthonormal(X: np.ndarray, k: int) -> np.ndarray:
    """The ``k`` leading left singular vectors of ``X`` (an orthonormal basis of its span)."""
    W, _, _ = np.linalg.svd(X, full_matrices=False)
    return np.asarray(W[:, :k])


def _kkt_solver(M: sp.csr_array, C: sp.csr_array | None, K: sp.csr_array, A: sp.csr_array,
                sigma: complex) -> Callable[[np.ndarray], np.ndarray]:
    """``rhs -> y``: the solution of ``Q(sigma) y - A^T mu = rhs``, ``A y = 0`` (the
    independent rows of ``A``, scaled to the size of ``Q``)."""
    n = K.shape[0]
    Q = sp.csr_array(K, dtype=complex) + sigma * sigma * M + \
        (sigma * C if C is not None else 0)
    Ak = A[independent_rows(A).keep] if A.shape[0] and A.nnz else sp.csr_array((0, n))
    m = Ak.shape[0]
    if m:
        beta = max(float(spla.norm(Q)), 1e-300) / max(float(spla.norm(Ak)), 1e-300)
        big = sp.block_array([[Q, beta * Ak.T], [beta * Ak, None]], format="csc")
    else:
        big = sp.csc_array(Q)
    solve = factorizer("complex-lu")(sp.csc_array(big, dtype=complex))

    def kkt(rhs: np.ndarray) -> np.ndarray:
        b = np.vstack([rhs, np.zeros((m, rhs.shape[1]), dtype=complex)])
        y = np.asarray(solve(b)).reshape(b.shape)
        y = y + np.asarray(solve(b - big @ y)).reshape(b.shape)  # one refinement step
        return y[:n]

    return kkt


def cluster_subspace(M: sp.csr_array, C: sp.csr_array | None, K: sp.csr_array,
                     A: sp.csr_array, lam: np.ndarray, U: np.ndarray, what: str
                     ) -> tuple[np.ndarray, np.ndarray]:
    r"""``(X_u, X_v)``: a basis (orthonormal with ``v`` in units of ``|lambda_0|``) of the invariant
    subspace of the ``k`` roots ``lam`` (vectors ``U``, any of them possibly parallel), by block
    inverse iteration about :math:`\sigma = \lambda_0 (1 + \text{SHIFT})`,
    :math:`\lambda_0` their mean (module docstring).

    The start is the span of the computed state vectors :math:`[u_r; \lambda_r u_r]` completed
    by :math:`[u_r; 0]` where they are parallel.

    Raises:
        AnalysisInputError: the iteration does not settle on ``k`` roots of the cluster (a
            root too close to the cluster's, or a zero root); ``what`` names the cluster.
    """
    k = lam.size
    lam0 = complex(np.mean(lam))
    scale = abs(lam0)
    if scale == 0.0:
        raise AnalysisInputError(f"{what}: a repeated zero root has no modal expansion")
    X = np.vstack([U, U * (lam / scale)[None, :]])
    X = X / np.maximum(np.linalg.norm(X, axis=0), 1e-300)[None, :]
    sv = np.linalg.svd(X, compute_uv=False)
    r = int(np.sum(sv > 1e-8 * sv[0]))
    start = np.hstack([_orthonormal(X, r), np.vstack([U, np.zeros_like(U)])])
    X = _orthonormal(start, k)
    sigma = lam0 * (1 + SHIFT)
    kkt = _kkt_solver(M, C, K, A, sigma)
    change = np.inf
    for _ in range(STEPS):
        Xu, Xv = X[:U.shape[0]], X[U.shape[0]:] * scale
        Yu = kkt(-(C @ Xu if C is not None else 0) - M @ Xv - sigma * (M @ Xu))
        Y = np.vstack([Yu, (sigma * Yu + Xu) / scale])
        Y = _orthonormal(Y, k)
        change = float(np.linalg.norm(Y - X @ (X.conj().T @ Y), 2))
        X = Y
        if change <= SETTLED:
            break
    Xu, Xv = X[:U.shape[0]], X[U.shape[0]:] * scale
    GB, GA = projections(M, C, K, Xu, Xv)
    ritz = np.linalg.eigvals(np.linalg.solve(GB, GA)) if np.all(np.isfinite(GB)) else lam
    if change > 1e3 * SETTLED or np.abs(ritz - lam0).max(initial=0.0) > CLUSTER_CAP * scale:
        raise AnalysisInputError(
            f"{what}: the invariant subspace of the repeated root {lam0:.6g} was not found "
            f"(subspace change {change:.1e}); the modal sum cannot represent it: use a direct "
            f"method")
    return Xu, Xv


def projections(M: sp.csr_array, C: sp.csr_array | None, K: sp.csr_array, Xu: np.ndarray,
                Xv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r""":math:`G_B = X^T \mathcal{B} X`, :math:`G_A = X^T \mathcal{A} X` on the state vectors
    ``X = [Xu; Xv]`` (module docstring), symmetrized."""
    MU, MV = M @ Xu, M @ Xv
    GB = Xu.T @ MV + Xv.T @ MU + (Xu.T @ (C @ Xu) if C is not None else 0)
    GA = Xv.T @ MV - Xu.T @ (K @ Xu)
    return (GB + GB.T) / 2, (GA + GA.T) / 2


def complete_clusters(M: sp.csr_array, C: sp.csr_array | None, K: sp.csr_array,
                      A: sp.csr_array, lam: np.ndarray, U: np.ndarray,
                      clusters: tuple[Cluster, ...]) -> tuple[np.ndarray, tuple[Cluster, ...]]:
    r"""The shapes and clusters with every cluster of nearly parallel vectors (smallest singular
    value of its unit state vectors below :data:`PARALLEL` of the largest) on a basis of its
    invariant subspace (:func:`cluster_subspace`): its columns of ``U`` replaced by the
    ``u`` parts of that basis, its ``G_B``, ``G_A`` by :func:`projections`.  The other
    clusters and ``U`` elsewhere are returned as they are.

    Raises:
        AnalysisInputError: an invariant subspace not found (:func:`cluster_subspace`).
    """
    out = []
    shapes = U
    for c in clusters:
        lc, Uc = lam[c.index], U[:, c.index]
        X = np.vstack([Uc, Uc * lc[None, :] / max(float(np.abs(lc).max()), 1e-300)])
        X = X / np.maximum(np.linalg.norm(X, axis=0), 1e-300)[None, :]
        sv = np.linalg.svd(X, compute_uv=False)
        if sv[-1] >= PARALLEL * sv[0]:
            out.append(c)
            continue
        what = f"modal receptance, {c.index.size} roots at {complex(np.mean(lc)):.6g}"
        Xu, Xv = cluster_subspace(M, C, K, A, lc, Uc, what)
        if shapes is U:
            shapes = U.copy()
        shapes[:, c.index] = Xu
        GB, GA = projections(M, C, K, Xu, Xv)
        out.append(Cluster(c.index, GB, GA))
    return shapes, tuple(out)
