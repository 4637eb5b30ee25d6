r"""Repeated (degenerate) roots in the modal sum: each cluster of equal roots summed through its
own small first-order pencil instead of a diagonal.

The modal sum of :mod:`substruct.analysis.frf.modal` is the resolvent of the symmetric
first-order pencil of :math:`(\lambda^2 M + \lambda C + K) u = A^T \mu`, :math:`A u = 0`,

.. math::  \mathcal{A} = \begin{bmatrix} -K & 0 \\ 0 & M \end{bmatrix}, \qquad
           \mathcal{B} = \begin{bmatrix} C & M \\ M & 0 \end{bmatrix}, \qquad
           x_r = \begin{bmatrix} u_r \\ \lambda_r u_r \end{bmatrix},

.. math::  (K + s C + s^2 M)^{-1}_A = [I\ 0]\, (s \mathcal{B} - \mathcal{A})^{-1}
           \begin{bmatrix} I \\ 0 \end{bmatrix} = \sum_r \frac{u_r u_r^T}{a_r (s - \lambda_r)}

only if the vectors are bi-orthogonal, :math:`x_r^T \mathcal{B} x_s = a_r \delta_{rs}`.  For
distinct roots they are (complex symmetric pencil); within a repeated root any basis of the
eigenspace is an eigensolver's answer, and the cross terms are of the size of the diagonal
ones (the sum was wrong by 190 % on two identical chains).  Each cluster ``c`` of equal roots
is therefore summed through the pencil projected on its vectors (the cluster spans an
invariant subspace, so the projection is exact),

.. math::  G_B = X_c^T \mathcal{B} X_c, \quad
           (G_B)_{rs} = u_r^T \big( (\lambda_r + \lambda_s) M + C \big) u_s, \qquad
           G_A = X_c^T \mathcal{A} X_c, \quad
           (G_A)_{rs} = \lambda_r \lambda_s u_r^T M u_s - u_r^T K u_s,

.. math::  H_c(s) = U_c (s G_B - G_A)^{-1} U_c^T, \qquad
           \text{coefficient of } s^k \text{ at } 0: \;
           -U_c (G_A^{-1} G_B)^k G_A^{-1} U_c^T ,

which is the diagonal sum when ``G_B``, ``G_A`` are diagonal and is continuous as a repeated
root splits (:func:`root_clusters`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from substruct.linalg.constraints import independent_rows
from substruct.linalg.factorize import factorizer

__all__ = ["CLUSTER_CAP", "Cluster", "root_accuracy", "root_clusters", "cluster_terms",
           "cluster_moment"]

#: The largest cluster tolerance (relative): roots further apart than this are never one cluster,
#: however inaccurate their vectors (a Ritz basis), so that a dense spectrum does not chain into
#: one large block.
CLUSTER_CAP = 1e-4


@dataclass(frozen=True)
class Cluster:
    """Roots summed through their projected pencil (module docstring).

    Attributes:
        index: positions of the cluster's roots in the basis (two or more).
        GB, GA: the ``k x k`` projections :math:`X_c^T \\mathcal{B} X_c`,
            :math:`X_c^T \\mathcal{A} X_c` (complex symmetric).
    """

    index: np.ndarray
    GB: np.ndarray
    GA: np.ndarray


def root_accuracy(M: sp.csr_array, C: sp.csr_array | None, K: sp.csr_array, A: sp.csr_array,
                  lam: np.ndarray, U: np.ndarray, norms: np.ndarray) -> np.ndarray:
    r"""The relative accuracy :math:`\epsilon_r` of each computed root's vector: the mixing with
    a root at relative distance ``g`` that its residual causes is :math:`\epsilon_r / g`.

    .. math::  r_r = P (\lambda_r^2 M + \lambda_r C + K) u_r, \qquad
               \epsilon_r = \frac{\max(\|r_r\|, \epsilon_{mach} \rho_r) \, \|u_r\|}
               {|a_r| \, |\lambda_r|}, \qquad
               \rho_r = \|K u_r\| + |\lambda_r| \|C u_r\| + |\lambda_r|^2 \|M u_r\|

    (``P`` the orthogonal projector on ``null(A)``, which removes the constraint forces
    :math:`A^T \mu`; by the independent rows of ``A``, one sparse factorization of
    :math:`A_k A_k^T`).  Invariant under the scaling of ``u``, of ``M, C, K`` together and of
    time.
    """
    KU, MU = K @ U, (M @ U) * lam[None, :] ** 2
    R = KU + MU
    floor = np.linalg.norm(KU, axis=0) + np.linalg.norm(MU, axis=0)
    if C is not None:
        CU = (C @ U) * lam[None, :]
        R = R + CU
        floor = floor + np.linalg.norm(CU, axis=0)
    if A.shape[0] and A.nnz:
        Ak = sp.csr_array(A[independent_rows(A).keep])
        if Ak.shape[0]:
            solve = factorizer("auto", spd=True)(sp.csc_array(Ak @ Ak.T))
            AR = Ak @ R
            mu = np.asarray(solve(AR.real)).reshape(AR.shape) + \
                1j * np.asarray(solve(AR.imag)).reshape(AR.shape)
            R = R - Ak.T @ mu
    size = np.abs(norms) * np.abs(lam)
    # a residual is never below the rounding of its terms: a vector that the computed root
    # leaves with no residual at all (a critically damped mode, whose double root is split by
    # sqrt(eps)) is no more accurate than that
    rounding = float(np.finfo(float).eps) * floor
    eps = np.maximum(np.linalg.norm(R, axis=0), rounding) * np.linalg.norm(U, axis=0) / \
        np.where(size > 0, size, 1.0)
    return np.where(size > 0, eps, np.inf)


def root_clusters(M: sp.csr_array, C: sp.csr_array | None, K: sp.csr_array, lam: np.ndarray,
                  U: np.ndarray, paired: np.ndarray, accuracy: np.ndarray) -> tuple[Cluster, ...]:
    r"""The clusters of equal roots, with their projected pencils.

    Roots ``r``, ``s`` of the same kind (both standing for a conjugate pair, or both real) are
    one cluster when

    .. math::  |\lambda_r - \lambda_s| \le \tau_{rs} \max(|\lambda_r|, |\lambda_s|), \qquad
               \tau_{rs} = \min\big(\sqrt{\max(\epsilon_r, \epsilon_s, \epsilon_{mach})},
               \ \text{CLUSTER\_CAP}\big)

    (:func:`root_accuracy`; transitively): roots further apart have vectors mixed by at most
    :math:`\epsilon / \tau = \sqrt{\epsilon}`, roots closer are summed exactly whatever basis
    of their (nearly) invariant subspace the eigensolver returned.
    """
    eps = float(np.finfo(float).eps)
    n = lam.size
    parent = np.arange(n)

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = int(parent[i])
        return i

    order = np.argsort(np.abs(lam), kind="stable")
    mag = np.abs(lam)
    for a_pos, r in enumerate(order.tolist()):
        for s in order[a_pos + 1:].tolist():
            top = max(mag[r], mag[s])
            if mag[s] - mag[r] > CLUSTER_CAP * top:
                break
            tau = min(np.sqrt(max(accuracy[r], accuracy[s], eps)), CLUSTER_CAP)
            if paired[r] == paired[s] and abs(lam[r] - lam[s]) <= tau * top:
                parent[find(r)] = find(s)
    roots = np.array([find(i) for i in range(n)], dtype=int)
    out = []
    for g in np.unique(roots):
        idx = np.flatnonzero(roots == g)
        if idx.size < 2:
            continue
        Uc, lc = U[:, idx], lam[idx]
        MU, KU = M @ Uc, K @ Uc
        UMU, UKU = Uc.T @ MU, Uc.T @ KU
        UCU = Uc.T @ (C @ Uc) if C is not None else np.zeros_like(UMU)
        GB = UCU + (lc[:, None] + lc[None, :]) * UMU
        GA = lc[:, None] * lc[None, :] * UMU - UKU
        out.append(Cluster(idx, (GB + GB.T) / 2, (GA + GA.T) / 2))
    return tuple(out)


def cluster_terms(clusters: tuple[Cluster, ...], paired: np.ndarray, P: np.ndarray,
                  Q: np.ndarray, omegas: np.ndarray) -> np.ndarray:
    r""":math:`\sum_c P_c (i\omega G_B - G_A)^{-1} Q_c` + conjugates (paired clusters),
    ``(n_omega, q, p)``; ``P = O U``, ``Q = U^T E``."""
    s = 1j * np.asarray(omegas, dtype=float)
    out = np.zeros((s.size, P.shape[0], Q.shape[1]), dtype=complex)
    for c in clusters:
        Pc, Qc = P[:, c.index], Q[c.index]
        Z = np.linalg.solve(s[:, None, None] * c.GB[None] - c.GA[None],
                            np.broadcast_to(Qc, (s.size,) + Qc.shape))
        out += Pc @ Z  # a product per frequency: the same whatever the other frequencies
        if paired[c.index[0]]:
            Zc = np.linalg.solve(s[:, None, None] * np.conj(c.GB)[None] - np.conj(c.GA)[None],
                                 np.broadcast_to(np.conj(Qc), (s.size,) + Qc.shape))
            out += np.conj(Pc) @ Zc
    return out


def cluster_moment(clusters: tuple[Cluster, ...], paired: np.ndarray, P: np.ndarray,
                   Q: np.ndarray, k: int) -> np.ndarray:
    r"""The coefficient of :math:`s^k` of the clusters' terms about ``s = 0``:
    :math:`-\sum_c P_c (G_A^{-1} G_B)^k G_A^{-1} Q_c` + conjugates."""
    out = np.zeros((P.shape[0], Q.shape[1]), dtype=complex)
    for c in clusters:
        Pc, Qc = P[:, c.index], Q[c.index]
        Y = np.linalg.solve(c.GA, Qc)
        for _ in range(k):
            Y = np.linalg.solve(c.GA, c.GB @ Y)
        term = -Pc @ Y
        out += term
        if paired[c.index[0]]:
            out += np.conj(term)
    return out
