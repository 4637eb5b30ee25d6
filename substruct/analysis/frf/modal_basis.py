r"""The retained roots of the coupled system and the modal sums over them (the receptance
by modal superposition of :mod:`substruct.analysis.frf.modal`, eqs 23-34).

In the first-order (state-space) form, which holds for any damping,

.. math::  H(\omega) = \sum_r \frac{u_r u_r^T}{a_r (i\omega - \lambda_r)}, \qquad
           a_r = u_r^T (2 \lambda_r M + C)\, u_r ,

each complex root beside its conjugate; a cluster of repeated roots is summed through its
projected pencil (:mod:`substruct.analysis.frf.clusters`; on its invariant subspace when its
vectors are nearly parallel, a defective root, :mod:`substruct.analysis.frf.defective`), and
rigid-body modes (zero roots of
an undamped model) are kept apart, :math:`-\Phi_0 \Phi_0^T / \omega^2`.

:func:`modal_terms` evaluates the sum projected on outputs and inputs a frequency at a time
(one matrix product per frequency, on sub-blocks of frequencies whose temporary stays below
:data:`TERMS_BYTES`): the value at a frequency does not depend on which other frequencies are
computed with it, so a sweep computed a block at a time (into a sink) gives the numbers of the
whole sweep, bit for bit.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import scipy.sparse as sp

from substruct.analysis.errors import AnalysisInputError
from substruct.analysis.frf.clusters import (
    Cluster,
    cluster_moment,
    cluster_terms,
    root_accuracy,
    root_clusters,
)
from substruct.analysis.frf.defective import complete_clusters
from substruct.analysis.modes.amls import AmlsOptions, amls_damped_basis
from substruct.analysis.modes.eigen import modes
from substruct.analysis.modes.sparse import has_damping
from substruct.analysis.results import Modes

__all__ = ["DEFAULT_CUTOFF", "RIGID_ROOT_FRACTION", "TERMS_BYTES", "ModalBasis", "modal_basis",
           "modal_terms", "modal_moment", "root_entries"]

#: Default cut-off: the modes up to this multiple of the highest frequency of the grid.
DEFAULT_CUTOFF = 10.0
#: A root below this fraction of the frequency scale is a rigid-body mode.
RIGID_ROOT_FRACTION = 1e-6
#: The largest temporary of :func:`modal_terms` (the scaled factor of one sub-block of
#: frequencies: frequencies x roots x the fewer of outputs and inputs, complex).
TERMS_BYTES = 16 << 20


@dataclass(frozen=True)
class ModalBasis:
    """The retained roots of the coupled system, as the modal sum needs them.

    Attributes:
        eigenvalues: elastic roots ``lambda_r`` (``Im >= 0``; one per conjugate pair).
        shapes: ``n x N`` complex shapes ``u_r``.
        norms: ``a_r = u_r^T (2 lambda_r M + C) u_r``.
        paired: whether a root stands for a conjugate pair (``Im lambda_r > 0``).
        rigid: ``n x r0`` rigid-body shapes, ``Phi_0^T M Phi_0 = I`` (undamped models only).
        highest: the largest ``|lambda_r|`` computed (rad/s).
        clusters: the repeated roots, summed through their projected pencils
            (:mod:`substruct.analysis.frf.clusters`) instead of ``1 / a_r``.
    """

    eigenvalues: np.ndarray
    shapes: np.ndarray
    norms: np.ndarray
    paired: np.ndarray
    rigid: np.ndarray
    highest: float
    clusters: tuple[Cluster, ...] = ()

    @property
    def count(self) -> int:
        """Number of retained elastic roots."""
        return int(self.eigenvalues.size)


def root_entries(n: int, damped: bool) -> int:
    r"""The most entries an eigensolver can report for ``n`` coordinates: ``n`` undamped (one
    per conjugate pair :math:`\pm i\omega_r`), ``2 n`` damped, where an over-damped mode gives
    two real roots, each an entry of its own, beside the pairs of the others.

    .. math::  \#\{\text{entries}\} = N_{pairs} + N_{real}, \qquad
               2 N_{pairs} + N_{real} \le 2 n
    """
    return 2 * n if damped else n


def _modes(M: sp.csr_array, C: sp.csr_array | None, K: sp.csr_array, A: sp.csr_array,
           count: int | None, solver: str) -> Modes:
    return modes(M, C, K, A, count, solver=solver, what="frf (modal)")


def modal_basis(M: sp.csr_array, C: sp.csr_array | None, K: sp.csr_array, A: sp.csr_array,
                omega_max: float, *, count: int | None = None,
                cutoff: float = DEFAULT_CUTOFF, solver: str = "auto",
                amls: Any = None) -> ModalBasis:
    r"""The roots of the coupled system up to ``cutoff * omega_max`` (or the lowest ``count``).

    .. math::  |\lambda_r| \le c\, \omega_{max}

    With ``count`` ``None`` the sparse solvers are asked for 20, 40, 80, ... roots until one
    passes the cut-off (the dense solver computes all and keeps those below it), up to
    :func:`root_entries` (``2 n`` for a damped model: an over-damped mode is two real roots, an
    entry each, so ``n`` entries could leave a root below the cut-off out).  With
    ``solver="amls"`` one AMLS reduction gives every undamped mode below the cut-off (or the
    lowest ``count``) and the damping is projected on them
    (:func:`substruct.analysis.modes.amls.amls_damped_basis`, options ``amls``).  Repeated
    roots are grouped (:func:`substruct.analysis.frf.clusters.root_clusters`), whatever basis
    of their eigenspace the eigensolver gave.

    Raises:
        ValueError: a damped model with rigid-body modes.
    """
    damped = has_damping(C)
    n = K.shape[0]
    entries = root_entries(n, damped)
    Cm = C if damped else None
    limit = cutoff * omega_max
    if solver == "amls":
        opts = amls if amls is not None else AmlsOptions()
        opts = replace(opts, omega_max=None if count is not None else limit)
        md, _ = amls_damped_basis(M, Cm, K, A, None if count is None else min(int(count), n),
                                  opts)
    elif count is not None:
        md = _modes(M, Cm, K, A, min(int(count), entries), solver)
    else:
        k = min(20, entries)
        while True:
            md = _modes(M, Cm, K, A, k, solver)
            if len(md) < k or md.omega.max(initial=0.0) > limit or k >= entries:
                break
            k = min(2 * k, entries)
        md = md.lowest(int(np.sum(md.omega <= limit)) + (1 if np.any(md.omega > limit) else 0))
    lam = np.asarray(md.eigenvalues, dtype=complex)
    U = np.asarray(md.shapes, dtype=complex)
    highest = float(np.abs(lam).max(initial=0.0))
    scale = max(omega_max, highest, 1e-300)
    rigid = np.abs(lam) <= RIGID_ROOT_FRACTION * scale
    if np.any(rigid) and damped:
        raise AnalysisInputError("modal receptance of a damped model with rigid-body modes is not "
                         "supported; use method: generalized-inverse")
    Phi = U[:, rigid].real
    if Phi.shape[1]:
        L = np.linalg.cholesky(Phi.T @ (M @ Phi))
        Phi = np.linalg.solve(L, Phi.T).T  # Phi_0^T M Phi_0 = I
    lam, U = lam[~rigid], U[:, ~rigid]
    MU = M @ U
    CU = C @ U if damped and C is not None else np.zeros_like(U)
    norms = np.einsum("ir,ir->r", U, 2 * lam[None, :] * MU + CU)
    Cd = C if damped else None
    accuracy = root_accuracy(M, Cd, K, A, lam, U, norms)
    clusters = root_clusters(M, Cd, K, lam, U, lam.imag > 0, accuracy)
    U, clusters = complete_clusters(M, Cd, K, A, lam, U, clusters)
    return ModalBasis(lam, U, norms, lam.imag > 0, Phi, highest, clusters)


def _singles(basis: ModalBasis) -> np.ndarray:
    """Whether each root is summed on its own (in no cluster)."""
    single = np.ones(basis.count, dtype=bool)
    for c in basis.clusters:
        single[c.index] = False
    return single


def _scaled_product(P: np.ndarray, f: np.ndarray, Q: np.ndarray,
                    out: np.ndarray | None = None) -> np.ndarray:
    """``out[k] = P diag(f[k]) Q`` for each row ``k`` of ``f``: one matrix product per
    frequency (the smaller factor scaled), the same arithmetic whatever the other rows."""
    if P.shape[0] <= Q.shape[1]:
        return np.matmul(P, f[:, :, None] * Q[None], out=out)
    return np.matmul(P[None] * f[:, None, :], Q, out=out)


def modal_terms(basis: ModalBasis, P: np.ndarray, Q: np.ndarray, omegas: np.ndarray,
                out: np.ndarray | None = None) -> np.ndarray:
    r"""``sum_r T_r(omega_k)`` projected on outputs and inputs, ``(n_omega, q, p)`` (into
    ``out`` if given).

    .. math::  \sum_r \frac{(O u_r)(u_r^T E)}{a_r (i \omega - \lambda_r)}
               + \text{conjugates}

    ``P = O U`` (``q x N``), ``Q = U^T E`` (``N x p``).  A cluster of repeated roots is
    summed through its projected pencil
    (:func:`substruct.analysis.frf.clusters.cluster_terms`).  Computed a frequency at a time
    (module docstring): each frequency's value is independent of the rest of ``omegas``.
    """
    lam, a, pair = basis.eigenvalues, basis.norms, basis.paired
    w = np.asarray(omegas, dtype=float)
    q, p = P.shape[0], Q.shape[1]
    if out is None:
        out = np.empty((w.size, q, p), dtype=complex)
    single = _singles(basis)
    rows = max(1, TERMS_BYTES // max(1, 16 * lam.size * min(q, p)))
    Pc, Qc = np.conj(P), np.conj(Q)
    for start in range(0, w.size, rows):
        iw = 1j * w[start:start + rows, None]
        o = out[start:start + rows]
        f = np.where(single[None, :], 1.0 / (a[None, :] * (iw - lam[None, :])), 0)
        _scaled_product(P, f, Q, o)
        if np.any(pair):
            g = np.where(pair[None, :] & single[None, :],
                         1.0 / (np.conj(a)[None, :] * (iw - np.conj(lam)[None, :])), 0)
            o += _scaled_product(Pc, g, Qc)
        if basis.clusters:
            o += cluster_terms(basis.clusters, pair, P, Q, w[start:start + rows])
    return out


def modal_moment(basis: ModalBasis, P: np.ndarray, Q: np.ndarray, k: int) -> np.ndarray:
    r"""The coefficient of :math:`s^k` of the retained elastic terms about ``s = 0``:

    .. math::  \sum_r -\frac{(O u_r)(u_r^T E)}{a_r \lambda_r^{k+1}} + \text{conjugates}
    """
    lam, a, pair = basis.eigenvalues, basis.norms, basis.paired
    f = np.where(_singles(basis), -1.0 / (a * lam ** (k + 1)), 0)
    out = (P * f[None, :]) @ Q
    if np.any(pair):
        g = np.where(pair, np.conj(f), 0)
        out = out + (np.conj(P) * g[None, :]) @ np.conj(Q)
    if basis.clusters:
        out = out + cluster_moment(basis.clusters, pair, P, Q, k)
    return np.asarray(out)
