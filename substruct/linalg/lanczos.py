r"""The one shift-invert Lanczos eigensolver of the package.

Every sparse eigen solve (the coupled modes of :mod:`substruct.analysis.modes.sparse`, modal
truncation and the fixed-interface modes of Craig-Bampton in :mod:`substruct.models`) is

.. math::  K u = \omega^2 M u, \qquad (K - \sigma M)^{-1} M u = \frac{1}{\omega^2 - \sigma} u,

solved by ARPACK's Lanczos iteration (``scipy.sparse.linalg.eigsh``) in shift-invert mode with
``OPinv`` a solve chosen from the factorization registry (:mod:`substruct.linalg.factorize`),
never one that ``eigsh`` makes for itself (SuperLU with partial pivoting; the registry's choice,
measured, is in docs/performance.md, "The factorization: measured, and the default"), then a
Rayleigh-Ritz step on the vectors it returns.

A cluster of nearly equal eigenvalues straddling the ``k``-th (identical parts coupled weakly:
50 superelements with the same fixed-interface frequencies) stalls the restarted Lanczos
iteration while its basis is smaller than the cluster: it must tell the members apart to the
working precision.  A first attempt is therefore limited to :data:`FIRST_ATTEMPT_RESTARTS`
restarts; one that has not converged by then starts again with a basis
:data:`BASIS_GROWTH` times larger (up to ``n``), which holds the whole cluster and converges
in a few restarts.  A problem that converges within the limit is solved exactly as before.

With massless coordinates (zero rows of ``M``; the sparse eigensolvers make every massless
direction one, :func:`substruct.linalg.massless.massless_split`) the vectors are purified
(:func:`purified`): one more application of the operator removes the part in
:math:`\operatorname{null}(M)` that the iteration, orthogonalizing in the semi-inner product of
a singular ``M``, cannot see.

Rigid-body modes (a free model) are deflated (:func:`shift_invert_lanczos_deflated`): about a
shift just below zero their eigenvalues of the operator, :math:`1/|\sigma|`, exceed the elastic
ones by the ratio :math:`\omega_1^2 / |\sigma|` (7e8 for a free-free cylinder of 2,000
coordinates), and the elastic vectors come out with relative residuals of 3e-5 instead of
round-off; a second pass in the ``M``-orthogonal complement of the rigid-body vectors, with the
same factorization, gives them to 1e-17.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from substruct.linalg.factorize import Solve

__all__ = ["shift_invert_lanczos", "shift_invert_lanczos_deflated", "rayleigh_ritz", "purified",
           "FIRST_ATTEMPT_RESTARTS", "BASIS_GROWTH"]

#: ARPACK restarts (``maxiter``) of an attempt before the basis is enlarged; the last attempt
#: (a basis of ``n``) has ARPACK's own limit.  Measured: 10 coupled superelements with a cluster
#: of 10 wanted modes converge in about 15 restarts.
FIRST_ATTEMPT_RESTARTS = 50
#: Factor by which the Krylov basis grows from one attempt to the next.
BASIS_GROWTH = 4


def shift_invert_lanczos(K: sp.sparray, M: sp.sparray, k: int, sigma: float, solve: Solve,
                         v0: np.ndarray | None = None, ncv: int | None = None
                         ) -> tuple[np.ndarray, np.ndarray]:
    r"""The ``k`` eigenpairs of :math:`K u = \omega^2 M u` nearest ``sigma`` by ``eigsh`` in
    shift-invert mode, with ``OPinv`` the given solve :math:`(K - \sigma M)^{-1}` (or an
    equivalent operator on a constrained space), never a factorization ``eigsh`` makes.

    Args:
        K, M: ``n x n`` sparse stiffness and mass.
        k: number of eigenpairs.
        sigma: the shift.
        solve: ``b -> (K - sigma M)^{-1} b``.
        v0: starting vector (seeded by the caller for repeatable results), or ``None``.
        ncv: Krylov basis size, or ``None`` for ARPACK's default.

    Returns:
        ``(lam, U)``: eigenvalues :math:`\omega^2` and vectors as ARPACK returns them.

    Raises:
        scipy.sparse.linalg.ArpackNoConvergence: not converged with a basis of ``n`` within
            ARPACK's own limit of restarts.
    """
    n = K.shape[0]
    op = spla.LinearOperator((n, n), matvec=solve, dtype=float)
    size = ncv if ncv is not None else min(n, max(2 * k + 1, 20))  # ARPACK's default
    first = True
    while True:
        last = size >= n
        try:
            lam, V = spla.eigsh(K, k=k, M=M, sigma=sigma, which="LM", OPinv=op, v0=v0,
                                ncv=ncv if first else size,
                                maxiter=None if last else FIRST_ATTEMPT_RESTARTS)
            if np.any(np.asarray(abs(sp.csr_array(M)).sum(axis=1)).ravel() == 0):
                V = purified(M, lam, V, sigma, solve)  # a singular M: null(M) removed
            return lam, V
        except spla.ArpackNoConvergence:
            if last:
                raise
        first = False
        size = min(n, BASIS_GROWTH * size)


def purified(M: sp.sparray, lam: np.ndarray, V: np.ndarray, sigma: float,
             solve: Solve) -> np.ndarray:
    r"""The Ritz vectors ``V`` of the shift-invert operator with their part in
    :math:`\operatorname{null}(M)` removed: one more application of the operator,

    .. math::  v \leftarrow (\lambda - \sigma)\, (K - \sigma M)^{-1} M v,

    which leaves an eigenvector as it is.  With a singular ``M`` (massless coordinates, a point
    mass off its node without rotary inertia) the Lanczos iteration orthogonalizes in the
    semi-inner product of ``M``, blind to :math:`\operatorname{null}(M)`, and its vectors pick
    up components there of any size (an energy :math:`u^T K u` of 1e31 against
    :math:`\omega^2 = 5` was seen with a basis nearly as large as the space that has mass);
    :math:`M` annihilates them (Ericsson and Ruhe's purification)."""
    if not V.shape[1]:
        return V
    MV = M @ V
    W = np.column_stack([np.asarray(solve(MV[:, j])).ravel() for j in range(V.shape[1])])
    return W * (lam - sigma)[None, :]


def shift_invert_lanczos_deflated(K: sp.sparray, M: sp.sparray, k: int, sigma: float,
                                  solve: Solve, rigid_below: float,
                                  v0: np.ndarray | None = None, ncv: int | None = None
                                  ) -> tuple[np.ndarray, np.ndarray]:
    r""":func:`shift_invert_lanczos`, with the rigid-body modes deflated (module docstring).

    A first pass gives ``k`` pairs; those with :math:`|\lambda| \le` ``rigid_below`` are the
    rigid-body modes :math:`R` (``r`` of them).  When :math:`0 < r < k` the other ``k - r`` are
    computed again by Lanczos on the ``M``-orthogonal complement of :math:`R`,

    .. math::  \operatorname{OP} = (I - R R^T M)\,(K - \sigma M)^{-1} M , \qquad R^T M R = I,

    (self-adjoint in the ``M`` inner product: :math:`R` spans eigenvectors, so the projector
    commutes with :math:`(K - \sigma M)^{-1} M`), where the rigid-body modes have the operator's
    eigenvalue 0 instead of its largest, :math:`1/|\sigma|`.

    Returns:
        ``(lam, V)``: ``k`` eigenvalues (unordered) and their vectors, the rigid-body ones first
        when the second pass ran.
    """
    lam, V = shift_invert_lanczos(K, M, k, sigma, solve, v0, ncv)
    rigid = np.abs(lam) <= rigid_below
    r = int(rigid.sum())
    if r == 0 or r == k:
        return lam, V
    R = V[:, rigid]
    R = R @ np.linalg.inv(np.linalg.cholesky(R.T @ (M @ R))).T  # M-orthonormal

    def deflated(b: np.ndarray) -> np.ndarray:
        y = np.asarray(solve(b))
        return y - R @ (R.T @ (M @ y))

    start = np.random.default_rng(0).standard_normal(K.shape[0]) if v0 is None else v0
    start = start - R @ (R.T @ (M @ start))
    size = None if ncv is None else max(ncv - r, min(K.shape[0] - r, 2 * (k - r) + 1))
    lam2, V2 = shift_invert_lanczos(K, M, k - r, sigma, deflated, start, size)
    return np.concatenate([lam[rigid], lam2]), np.hstack([R, V2])


def rayleigh_ritz(K: sp.sparray, M: sp.sparray, V: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
    r"""Eigenpairs of the projected problem on the columns of ``V``, ascending.

    .. math::  (V^T K V)\, y = \lambda\, (V^T M V)\, y, \qquad \Phi = V y

    (symmetrized: ARPACK's vectors are ``M``-orthogonal only to its tolerance).
    """
    kr, mr = V.T @ (K @ V), V.T @ (M @ V)
    lam, rot = sla.eigh((kr + kr.T) / 2, (mr + mr.T) / 2)
    return lam, V @ rot
