r"""The residual flexibility of the modal receptance (:mod:`substruct.analysis.frf.modal`): the
constrained static flexibility and its Taylor moments, which stand for the roots left out.

.. math::  H(\omega) \approx \sum_{r \le N} T_r(\omega)
           + \sum_{k \le o} s^k \Big( H_k - \sum_{r \le N} T_r^{(k)} \Big), \qquad
           s = i \omega ,

with :math:`H_0 = G` the flexibility of the constrained system (inertia relief against the
rigid-body modes), :math:`H_1 = -G C G`, :math:`H_2 = G C G C G - G M G`.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from substruct.analysis.errors import AnalysisInputError
from substruct.linalg.constraints import independent_rows
from substruct.linalg.factorize import factorizer

__all__ = ["static_solver", "static_moments"]


def static_solver(K: sp.csr_array, M: sp.csr_array, A: sp.csr_array,
                  rigid: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    r"""``F -> G_static F``: the static response of the constrained system, by one
    factorization of the saddle-point matrix (inertia relief against the rigid shapes
    ``Phi_0``, M-orthonormal).

    .. math::  \begin{bmatrix} K & \beta A_k^T & M \Phi_0 \\ \beta A_k & 0 & 0 \\
               \Phi_0^T M & 0 & 0 \end{bmatrix} x =
               \begin{bmatrix} (I - M \Phi_0 \Phi_0^T) F \\ 0 \\ 0 \end{bmatrix}

    ``A_k`` are the independent rows of ``A``, ``beta = |K| / |A_k|`` balances the blocks.

    Raises:
        ValueError: the constrained stiffness is singular (a mechanism the modes missed).
    """
    n = K.shape[0]
    Ak = A[independent_rows(A).keep] if A.shape[0] else sp.csr_array((0, n))
    normA = max(float(spla.norm(Ak)), 1e-300) if Ak.shape[0] else 1.0
    beta = max(float(spla.norm(K)), 1e-300) / normA
    MPhi = M @ rigid
    r0, m = rigid.shape[1], Ak.shape[0]
    blocks: list[list[sp.sparray | None]] = [[K]]
    if m:
        blocks = [[K, beta * Ak.T], [beta * Ak, None]]
    if r0:
        Mp = sp.csr_array(MPhi)
        blocks = [row + [Mp if i == 0 else None] for i, row in enumerate(blocks)]
        blocks.append([sp.csr_array(MPhi.T)] + [None] * len(blocks))
    big = sp.csc_array(sp.block_array(blocks, format="csc"))
    try:
        solve = factorizer("saddle")(big)
    except RuntimeError:
        raise AnalysisInputError("the constrained stiffness is singular (a mechanism with no mass?); "
                         "the modal receptance needs a static solve") from None

    def flexibility(F: np.ndarray) -> np.ndarray:
        F = np.asarray(F).reshape(n, -1)
        if r0:
            F = F - MPhi @ (rigid.T @ F)
        rhs = np.vstack([F, np.zeros((big.shape[0] - n, F.shape[1]), dtype=F.dtype)])
        x = solve(rhs)
        x = x + solve(rhs - big @ x)  # one step of iterative refinement
        return np.asarray(x[:n])

    return flexibility


def static_moments(flexibility: Callable[[np.ndarray], np.ndarray], M: sp.csr_array,
                   C: sp.csr_array | None, E: np.ndarray, order: int) -> list[np.ndarray]:
    r"""``X_k = H_k E`` for ``k = 0 .. order``: the Taylor coefficients of the constrained
    receptance in :math:`s = i\omega` about ``s = 0``.

    .. math::  H(s) = (K + s C + s^2 M)^{-1}_{A} = G - s\, G C G
               + s^2 (G C G C G - G M G) + O(s^3)

    (``G`` the constrained static flexibility; one back-substitution per term.)
    """
    X0 = flexibility(E)
    out = [X0]
    if order >= 1:
        X1 = -flexibility(C @ X0) if C is not None else np.zeros_like(X0)
        out.append(X1)
    if order >= 2:
        rhs = M @ X0 + (C @ X1 if C is not None else 0)
        out.append(-flexibility(rhs))
    return out
