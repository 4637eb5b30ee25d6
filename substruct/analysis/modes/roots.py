r"""Which roots of a constrained pencil are modes: counts, rigid-body motions, classification.

The paper's state-space form (eqs 32-34) has, besides the roots of the constrained problem,
``2 rank(A)`` zero roots whose vectors violate ``A u = 0`` (``M^* K`` of eq 30 has rank
``n - rank(A)``), and every formulation has infinite roots (massless coordinates, Lagrange
multipliers).  They are artifacts, not modes; a physical mode satisfies ``A u = 0``, and a
genuine rigid-body mode (a zero root *with* ``A u = 0``) is kept.

Roots are sorted out by counts that the matrices fix (:func:`root_structure`: rank of ``A``,
rigid-body motions, massless directions), not by thresholds on root magnitudes, which fail for
badly scaled models (a stiffness of ``1e12`` beside one of ``1``); :func:`classify_roots`
applies the counts and checks every kept root against ``A u = 0``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from substruct.analysis.errors import AnalysisInputError
from substruct.analysis.modes.pencil import Refine
from substruct.analysis.results import Modes
from substruct.linalg.constraints import independent_rows
from substruct.linalg.massless import massless_directions
from substruct.linalg.scaling import RIGID_ENERGY_TOL, mass_column_scale, rigid_eigenvalue
from substruct.vocabulary import GENERALIZED_INVERSE

__all__ = [
    "RESIDUAL_TOL",
    "MIXING_TOL",
    "REAL_TOL",
    "RIGID_SINGULAR_TOL",
    "RIGID_ENERGY_TOL",
    "RIGID_DAMPING_TOL",
    "DAMPING_RANK_TOL",
    "SPURIOUS_ZERO",
    "INFINITE_ROOT",
    "RootStructure",
    "root_scale",
    "rigid_basis",
    "root_structure",
    "classify_roots",
    "normalize_shapes",
]

#: A finite nonzero root whose vector has ``|A u| / (|A| |u|)`` above this is set aside.  Roots
#: are classified by counts (:func:`classify_roots`); this is the check that would catch a
#: miscount: a spurious root's vector has a residual of order one, while a physical root's
#: computed vector has one of order ``eps`` times its condition number (``1e-6`` for a slow root
#: next to the spurious zeros of eqs 30/34, which must not be dropped for it).
RESIDUAL_TOL = 1e-3
#: Eqs (30)/(34) only: a root ``lambda`` beside the spurious zeros has a vector mixed with
#: theirs, to a part of about ``0.1 eps s^2 / |lambda|^2`` (``s`` of :func:`root_scale`;
#: measured on a free plate's suspension modes of ``1e-14 s^2``, |A u| of 3e-3, and of
#: ``2e-16 s^2``, 0.2).  A root kept by the counts is set aside only when its residual is
#: above :data:`RESIDUAL_TOL` *and* above ``MIXING_TOL eps s^2 / |lambda|^2``: the mixing
#: the pencil can explain, with a margin of 100.
MIXING_TOL = 10.0
#: A root with ``|Im lambda| <= REAL_TOL |lambda|`` is real (over- or critically damped).  Near
#: critical damping the double root splits by about ``sqrt(eps)``; this tolerance lies above that
#: noise so the three formulations report the same number of roots.
REAL_TOL = 1e-6
#: Singular-value threshold for rigid-body motions: ``[D K D; A D]`` (``D = diag(K)^{-1/2}``,
#: rows of ``A D`` of unit norm) has singular values below this on ``null(K) & null(A)``.
RIGID_SINGULAR_TOL = 1e-9
#: A rigid-body mode counts as undamped (a double zero root) when ``u^T C u / u^T M u`` is
#: below this fraction of the root scale ``max(sqrt(K_ii / M_jj), C_ii / M_jj)``.
RIGID_DAMPING_TOL = 1e-8
#: Relative eigenvalue threshold for the rank of the damping on the massless directions.
DAMPING_RANK_TOL = 1e-10

#: Reason given for the ``2 rank(A)`` spurious zero roots of eqs (30)/(34).
SPURIOUS_ZERO = ("zero root of the projected operator M*K: its vector violates A u = 0 "
                 "(artifact of eqs 30/34, one pair per independent constraint)")
#: Reason given for an infinite root.
INFINITE_ROOT = ("infinite root: a massless coordinate or direction (a combination of "
                 "coordinates with no mass) or a Lagrange multiplier with no mass attached")


def root_scale(M: np.ndarray, C: np.ndarray, K: np.ndarray) -> float:
    r"""A root magnitude no physical root much exceeds, from the diagonals (rad/s):

    .. math::  \max\big(\sqrt{\max_i K_{ii} / \min_j M_{jj}},\ \max_i C_{ii} / \min_j M_{jj}\big)

    (``min`` over the coordinates that have mass)."""
    dm, dk, dc = np.abs(np.diag(M)), np.abs(np.diag(K)), np.abs(np.diag(C))
    mpos = dm[dm > 0]
    mmin = mpos.min() if mpos.size else 1.0
    return float(max(np.sqrt(dk.max(initial=0.0) / mmin), dc.max(initial=0.0) / mmin, 1e-300))


@dataclass(frozen=True)
class RootStructure:
    """What the matrices say about the roots, before any eigenvalue is computed.

    Attributes:
        rank: ``rank(A)`` (independent constraints).
        rigid: ``n x k`` basis of the rigid-body motions ``null(K) & null(A)``, ``M``-orthonormal.
        n_zero: zero roots of the constrained problem, with multiplicity: two for an undamped
            rigid-body mode (``C u = 0``), one for a damped one (its partner is ``-c/m``).
        n_finite: finite roots of the constrained problem, with multiplicity (zeros included):
            ``2 rank(M_r) + rank(C_0)``, ``M_r`` the mass on ``null(A)`` and ``C_0`` the damping
            on its massless directions (each massless dashpot gives one real root ``-k/c``).
    """

    rank: int
    rigid: np.ndarray
    n_zero: int
    n_finite: int


def rigid_basis(K: np.ndarray, A: np.ndarray) -> np.ndarray:
    r"""Orthonormal basis of ``null(K) & null(A)``, decided on the equilibrated matrices.

    .. math::  D = \operatorname{diag}(K_{ii})^{-1/2}, \qquad
               \operatorname{null} \begin{bmatrix} D K D \\ \operatorname{rows}(A D) \end{bmatrix}

    ``D K D`` has a unit diagonal and entries at most one (``K`` positive semidefinite), so the
    rank decision does not depend on units nor on a stiff spring next to a soft one (``K_ii``
    of ``1e12`` beside ``1`` would otherwise look like a rank-deficient ``K``).  Each motion is
    then confirmed by its strain energy, componentwise (:data:`RIGID_ENERGY_TOL`).

    Coordinates with no stiffness at all (a node no element uses, a rotation that only a
    rigid link or a point mass reaches) are split off first (:func:`_free_coordinates_basis`):
    the decomposition's round-off would otherwise spread their motion over stiff coordinates
    and fail the energy test.
    """
    free = ~np.any(K != 0, axis=1)
    if free.any():
        return _free_coordinates_basis(K, A, free)
    n = K.shape[0]
    d = np.abs(np.diag(K)).astype(float)
    pos = d > 0
    fill = 1.0 / np.sqrt(d[pos].max()) if pos.any() else 1.0
    D = np.where(pos, 1.0 / np.sqrt(np.where(pos, d, 1.0)), fill)
    blocks = [D[:, None] * K * D[None, :]]
    if A.size:
        AD = A * D[None, :]
        nrm = np.linalg.norm(AD, axis=1)
        blocks.append(AD[nrm > 0] / nrm[nrm > 0, None])
    _, sv, Vh = sla.svd(np.vstack(blocks))
    sv = np.concatenate([sv, np.zeros(n - sv.size)])
    null = Vh.conj().T[:, sv <= RIGID_SINGULAR_TOL * max(sv[0], 1.0)]
    if not null.shape[1]:
        return null
    Q, _ = np.linalg.qr(D[:, None] * null)
    # confirm by energy, componentwise: u^T K u against the rounding level |u|^T |K| |u|.  A
    # stiff spring in series with a soft one (1e12 and 1) passes the test above but stores
    # k_soft / k_stiff = 1e-12 of that level in the soft mode, far above rounding (~1e-16)
    energy = Q.T @ K @ Q
    level = np.sqrt(np.maximum(np.einsum("ij,ik,kj->j", np.abs(Q), np.abs(K), np.abs(Q)),
                               1e-300))
    w, W = np.linalg.eigh(energy / np.outer(level, level))
    return Q @ W[:, np.abs(w) <= RIGID_ENERGY_TOL]


def _free_coordinates_basis(K: np.ndarray, A: np.ndarray, free: np.ndarray) -> np.ndarray:
    r""":func:`rigid_basis` when the coordinates ``free`` (``Z``) have no stiffness:
    :math:`K u = 0` is :math:`K_{SS} u_S = 0` on the others (``S``), so

    .. math::  u = \begin{bmatrix} N & 0 \\ 0 & I \end{bmatrix} v, \qquad
               N = \operatorname{rigid\_basis}(K_{SS}), \qquad
               v \in \operatorname{null}\, [A_S N, \ A_Z]

    (rows of unit norm; orthonormal columns, as both factors have them)."""
    n = K.shape[0]
    S, Z = np.flatnonzero(~free), np.flatnonzero(free)
    N = rigid_basis(K[np.ix_(S, S)], np.zeros((0, S.size))) if S.size else np.zeros((0, 0))
    p = N.shape[1]
    basis = np.zeros((n, p + Z.size))
    basis[S, :p] = N
    basis[Z, p + np.arange(Z.size)] = 1.0
    if not A.size:
        return basis
    B = A @ basis
    nrm = np.linalg.norm(B, axis=1)
    B = B[nrm > 0] / nrm[nrm > 0, None]
    if not B.size:
        return basis
    _, sv, Vh = sla.svd(B)
    sv = np.concatenate([sv, np.zeros(basis.shape[1] - sv.size)])
    return basis @ Vh.conj().T[:, sv <= RIGID_SINGULAR_TOL * max(sv[0], 1.0)]


def root_structure(M: np.ndarray, C: np.ndarray, K: np.ndarray,
                   A: np.ndarray) -> RootStructure:
    """Counts of zero and finite roots (see :class:`RootStructure`); ``M``, ``C``, ``K``
    symmetric, ``M`` positive definite on the coordinates that have mass, ``C``, ``K``
    semidefinite.

    Raises:
        ValueError: a motion with no mass, no stiffness and no constraint (singular pencil).
    """
    n = K.shape[0]
    rank = independent_rows(A, col_scale=mass_column_scale(M)).rank if A.size else 0
    rigid = rigid_basis(K, A)
    n_zero = 0
    if rigid.shape[1]:
        Mr = rigid.T @ M @ rigid
        w, V = np.linalg.eigh((Mr + Mr.T) / 2)
        if w.min() <= 1e-12 * max(np.abs(M).max(), 1e-300):
            raise AnalysisInputError("singular model: a motion with no mass, no stiffness and no "
                             "constraint (a massless coordinate attached to nothing)")
        rigid = rigid @ (V / np.sqrt(w))  # M-orthonormal
        Cr = rigid.T @ C @ rigid
        rates = np.abs(np.linalg.eigvalsh((Cr + Cr.T) / 2))
        n_undamped = int(np.sum(rates <= RIGID_DAMPING_TOL * root_scale(M, C, K)))
        n_zero = rigid.shape[1] + n_undamped
    S0 = massless_directions(M, A)
    n_first = 0
    if S0.shape[1] and np.any(C):
        C0 = S0.T @ C @ S0
        ev = np.abs(np.linalg.eigvalsh((C0 + C0.T) / 2))
        n_first = int(np.sum(ev > DAMPING_RANK_TOL * np.abs(C).max()))
    n_finite = 2 * (n - rank - S0.shape[1]) + n_first
    return RootStructure(rank=rank, rigid=rigid, n_zero=n_zero, n_finite=n_finite)


def classify_roots(lam: np.ndarray, U: np.ndarray, A: np.ndarray, M: np.ndarray,
                   C: np.ndarray, K: np.ndarray, method: str,
                   refine: Refine | None = None) -> Modes:
    """Split roots into physical modes and roots set aside (see the module docstring).

    The split is by counts that the matrices fix (:func:`root_structure`), not by thresholds
    on root magnitudes:

    * the largest ``2n - n_finite`` roots (``n_finite`` plus ``2 rank(A)`` for eqs 30/34) are
      infinite roots: massless coordinates, Lagrange multipliers (higher-index infinite roots
      come out as large finite numbers, near ``eps^{-1/2}`` or ``eps^{-1/3}`` times the scale);
    * for eqs (30)/(34), the ``2 rank(A)`` artifacts are the roots whose vectors violate
      ``A u = 0`` most, among the smallest ``n_zero + 2 rank(A)`` finite roots and any other
      finite root above :data:`RESIDUAL_TOL` (a suspension mode softer than the round-off
      split of the spurious zeros comes before them in magnitude);
    * of the remaining finite roots the smallest ``n_zero`` are the zero roots: rigid-body
      modes (``K u = 0``, ``A u = 0``) are reported as physical zeros with their vectors taken
      from ``null(K) & null(A)``, because a zero root shared with spurious ones has no
      meaningful vector;
    * the other finite roots must satisfy ``A u = 0`` (checked against :data:`RESIDUAL_TOL`,
      and for eqs 30/34 against the mixing with the spurious zeros' vectors that a root of
      that size has, :data:`MIXING_TOL`; a root that does not is set aside with its residual
      as the reason); ``refine(j, lambda_j)``, given by each formulation, polishes them
      (:func:`substruct.analysis.modes.pencil.rayleigh_root`) and may return a better vector.

    Reporting is that of :class:`~substruct.analysis.results.Modes`: one root of each complex
    conjugate pair (``Im > 0``); a real root (``|Im| <= REAL_TOL |lambda|``) is a mode of its
    own with ``Im`` set to zero; an undamped rigid-body mode (a double zero) is one entry.

    Args:
        lam: all roots of the formulation's pencil (``inf`` for infinite ones).
        U: ``n x len(lam)`` displacement parts of their vectors.
        A, M, C, K: the dense matrices of the constrained problem.
        method: ``generalized-inverse`` (eqs 30/34, with the ``2 rank(A)`` artifacts),
            ``null-space`` or ``kkt``.
        refine: the formulation's refinement, or ``None``.
    """
    n = U.shape[0]
    An = np.linalg.norm(A, 2) if A.size else 1.0
    st = root_structure(M, C, K, A)
    extra = 2 * st.rank if method == GENERALIZED_INVERSE else 0
    mag = np.where(np.isfinite(lam), np.abs(lam), np.inf)
    order = np.argsort(mag, kind="stable")
    n_fin = min(st.n_finite + extra, lam.size)
    fin_idx, inf_idx = order[:n_fin], order[n_fin:]

    def residual(u: np.ndarray) -> float:
        if not A.size:
            return 0.0
        return float(np.linalg.norm(A @ u) / (An * max(float(np.linalg.norm(u)), 1e-300)))

    res_of = {int(j): residual(U[:, j]) for j in fin_idx}
    spurious: list[complex] = []
    reasons: list[str] = []
    # the 2 rank(A) artifacts of eqs 30/34: of the smallest n_zero + extra roots and of any
    # other finite root that violates A u = 0, those that violate it most.  A suspension mode
    # softer than the round-off split of the spurious zeros (|lambda| of sqrt(eps) s) comes
    # before them in magnitude; by magnitude alone it was taken for one and an artifact kept
    window = [int(j) for j in fin_idx[:min(st.n_zero + extra, n_fin)]]
    suspects = window + [j for j in res_of if j not in window and res_of[j] > RESIDUAL_TOL]
    artifacts = sorted(suspects, key=lambda j: -res_of[j])[:extra]
    for j in artifacts:
        spurious.append(complex(lam[j]))
        reasons.append(SPURIOUS_ZERO)
    kept = np.array([j for j in fin_idx if int(j) not in artifacts], dtype=int)
    rest_idx = kept[st.n_zero:]  # the smallest n_zero: the rigid-body modes, from their basis
    mixing = MIXING_TOL * np.finfo(float).eps * root_scale(M, C, K) ** 2 if extra else 0.0
    phys_lam: list[complex] = [0j] * st.rigid.shape[1]
    phys_u: list[np.ndarray] = [st.rigid[:, j].astype(complex) for j in range(st.rigid.shape[1])]
    # undamped: a real pair of roots (omega^2 < 0, which no stiffness gives) with |omega^2| at
    # round-off of the matrices' scale is a rigid-body mode whose K u = 0 holds only to the
    # input's rounding (a supplier's reduced matrices): reported at 0, not as a real pair of
    # damping ratios +1 and -1.  A small positive omega^2 stays: it may be a soft mode (a
    # unit spring in series with a 1e12 one has omega^2 below 1e-12 tr K / tr M)
    tiny = rigid_eigenvalue(sp.csr_array(K), sp.csr_array(M)) if not np.any(C) else -1.0
    near_rigid: list[np.ndarray] = []
    for j in rest_idx:
        lj, u = complex(lam[j]), U[:, j]
        r = res_of[int(j)]
        if r > RESIDUAL_TOL and r * abs(lj) ** 2 > mixing:
            spurious.append(lj)
            reasons.append(f"violates the constraints: |A u|/(|A||u|) = {r:.2e}")
            continue
        real = abs(lj.imag) <= REAL_TOL * abs(lj)
        if real and abs(lj) ** 2 <= tiny:
            near_rigid.append(u)
            continue
        if not real and lj.imag < 0:
            continue  # the conjugate of a kept root
        if refine is not None:
            lj, better = refine(int(j), lj)
            u = u if better is None else better
        if real:
            lj = complex(lj.real, 0.0)  # real: each root is its own mode
        phys_lam.append(lj)
        phys_u.append(u)
    if near_rigid:  # two roots a mode (+-r, or a repeated -r): one direction of their span each
        Q = np.linalg.svd(np.array(near_rigid).T, full_matrices=False)[0]
        phys_lam += [0j] * (len(near_rigid) // 2)
        phys_u += list(Q[:, :len(near_rigid) // 2].T)
    for j in inf_idx:
        spurious.append(complex(lam[j]) if np.isfinite(lam[j]) else complex(np.inf))
        reasons.append(INFINITE_ROOT)

    lam_p = np.array(phys_lam, dtype=complex)
    Up = np.array(phys_u, dtype=complex).T.reshape(n, -1)
    order = np.lexsort((lam_p.real, np.abs(lam_p)))
    lam_p, Up = lam_p[order], Up[:, order]
    Up = normalize_shapes(Up, M)
    omega = np.abs(lam_p)
    with np.errstate(invalid="ignore", divide="ignore"):
        zeta = np.where(omega > 0, -lam_p.real / np.where(omega > 0, omega, 1), 0.0)
    res = np.array([residual(Up[:, j]) for j in range(Up.shape[1])])
    return Modes(method=method, eigenvalues=lam_p, omega=omega, damping_ratio=zeta, shapes=Up,
                 residual=res, spurious=np.array(spurious, dtype=complex),
                 spurious_reason=reasons)


def normalize_shapes(U: np.ndarray, M: np.ndarray) -> np.ndarray:
    """Each column: phase so its largest entry is real positive; scaled to ``u^H M u = 1`` if
    that is positive, else to unit norm.  ``M`` dense or sparse."""
    if not U.shape[1]:
        return U
    k = np.argmax(np.abs(U), axis=0)
    top = U[k, np.arange(U.shape[1])]
    U = U * np.where(np.abs(top) > 0, np.abs(top) / np.where(top == 0, 1, top), 1.0)
    MU = M @ U.real + 1j * (M @ U.imag)
    mass = np.real(np.sum(np.conj(U) * MU, axis=0))
    norm = np.linalg.norm(U, axis=0)
    mmax = float(abs(M).max()) if np.size(M) else 0.0
    scale = np.where(mass > 1e-14 * norm**2 * max(mmax, 1e-300), np.sqrt(np.abs(mass)), norm)
    return U / np.where(scale > 0, scale, 1.0)
