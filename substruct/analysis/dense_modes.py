r"""Coupled modes of constrained systems (paper eqs 23-34) and their independent checks.

The paper's route: with ``M^*`` of eq (10), the constrained free vibration is (eq 28)

.. math::  (I - M^* M_o) \ddot u + M^* C \dot u + M^* K u = 0

and its roots are found from the state-space pencil of eqs (32)-(34),

.. math::  R \bar\eta = \lambda W \bar\eta, \quad
           W = \begin{bmatrix} 0 & I - M^* M_o \\ I - M^* M_o & M^* C \end{bmatrix}, \quad
           R = \begin{bmatrix} I - M^* M_o & 0 \\ 0 & -M^* K \end{bmatrix}.

``M^* K`` has rank ``n - rank(A)``: the pencil returns ``2 rank(A)`` zero roots whose vectors
violate ``A u = 0``.  They are artifacts of the formulation (spurious), not modes; a physical
mode satisfies ``A u = 0``.  A genuine rigid-body mode (zero root *with* ``A u = 0``) is kept.

Checks: null-space elimination ``u = N p`` and the Lagrange (KKT) pencil
``\lambda^2 [M, 0; 0, 0] + \lambda [C, 0; 0, 0] + [K, A^T; A, 0]``.

All three pencils are balanced (:func:`_fan_lin_van_dooren`) before QZ.  Their roots are sorted
out by counts that the matrices fix (rank of ``A``, rigid-body motions, massless directions;
:func:`_structure`), not by thresholds on root magnitudes, which fail for badly scaled models;
every kept root is then refined on the Rayleigh functional of its own vector
(:func:`_rayleigh`), which is accurate componentwise where QZ is only normwise backward stable:
a low root beside a stiffness of ``1e12``, a slow decay beside a zero root.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from substruct.analysis.coupling import constraint_gain, projected_inverse, split_mass
from substruct.linalg.constraints import dense, independent_rows, null_space_basis

__all__ = [
    "Modes",
    "coupled_modes",
    "modes_agreement",
    "MODE_METHODS",
]

MODE_METHODS: tuple[str, ...] = ("generalized-inverse", "null-space", "kkt")

#: A finite nonzero root whose vector has ``|A u| / (|A| |u|)`` above this is set aside.  Roots
#: are classified by counts (:func:`_classify`); this is the check that would catch a miscount:
#: a spurious root's vector has a residual of order one, while a physical root's computed vector
#: has one of order ``eps`` times its condition number (``1e-6`` for a slow root next to the
#: spurious zeros of eqs 30/34, which must not be dropped for it).
RESIDUAL_TOL = 1e-3
#: A root with ``|Im lambda| <= REAL_TOL |lambda|`` is real (over- or critically damped).  Near
#: critical damping the double root splits by about ``sqrt(eps)``; this tolerance lies above that
#: noise so the three formulations report the same number of roots.
REAL_TOL = 1e-6
#: Singular-value threshold for rigid-body motions: ``[D K D; A D]`` (``D = diag(K)^{-1/2}``,
#: rows of ``A D`` of unit norm) has singular values below this on ``null(K) & null(A)``.
RIGID_TOL = 1e-9
#: ... and its strain energy ``u^T K u`` is below this fraction of ``|u|^T |K| |u|`` (rounding is
#: a few ``eps`` of it; a ``1e12`` spring in series with a ``1`` leaves ``2.5e-13``).
RIGID_ENERGY_TOL = 3e-14
#: A rigid-body mode counts as undamped (a double zero root) when ``u^T C u / u^T M u`` is
#: below this fraction of the root scale ``max(sqrt(K_ii / M_jj), C_ii / M_jj)``.
RIGID_DAMPING_TOL = 1e-8
#: Relative eigenvalue threshold for the rank of the damping on the massless directions.
DAMPING_RANK_TOL = 1e-10


@dataclass
class Modes:
    """Physical modes of a constrained system and the roots set aside.

    How roots are reported (the same for the three formulations):

    * a complex root stands for its conjugate pair: one entry, ``Im lambda > 0``;
    * a real root (over-damped, or critically damped within ``REAL_TOL``) is an entry of its
      own, with ``Im lambda = 0`` exactly, ``omega = |lambda|`` and ``damping_ratio = 1``; an
      over-damped pair ``-zeta w +- w sqrt(zeta^2 - 1)`` therefore gives two entries, neither of
      which has the classical ``zeta > 1`` (pair them by hand if that is wanted);
    * a rigid-body mode (``K u = 0``, ``A u = 0``) is one entry ``lambda = 0`` with its exact
      vector; if the damping acts on it (``C u != 0``) its decay root ``~ -c/m`` is a further
      real entry;
    * infinite roots (massless coordinates that no constraint reaches, Lagrange multipliers)
      and the ``2 rank(A)`` zero roots of eqs (30)/(34) are not modes: they are listed in
      ``spurious`` with a reason each.

    Attributes:
        eigenvalues: complex roots ``lambda`` (one of each conjugate pair, ``Im >= 0``),
            ascending in ``|lambda|``.
        omega: ``|lambda|`` in rad/s (the undamped natural frequency for proportional damping).
        damping_ratio: ``-Re(lambda) / |lambda|`` (0 for a zero root, 1 for a decaying real
            root).
        shapes: ``n x k`` complex mode shapes (phase set so the largest entry is real positive;
            scaled to ``u^H M u = 1`` where that is positive).
        residual: ``|A u| / (|A| |u|)`` for each mode.
        spurious: roots set aside, complex.
        spurious_reason: one explanation per spurious root.
        method: the formulation that computed them.
    """

    eigenvalues: np.ndarray
    omega: np.ndarray
    damping_ratio: np.ndarray
    shapes: np.ndarray
    residual: np.ndarray
    spurious: np.ndarray = field(default_factory=lambda: np.zeros(0, complex))
    spurious_reason: list[str] = field(default_factory=list)
    method: str = ""

    @property
    def freq_hz(self) -> np.ndarray:
        """Natural frequencies in Hz."""
        return self.omega / (2 * np.pi)

    def __len__(self) -> int:
        return self.omega.size


def _fan_lin_van_dooren(m2: float, c2: float, k2: float) -> tuple[float, float]:
    r"""Scaling ``lambda = gamma mu`` and factor ``delta`` of ``lambda^2 M + lambda C + K``.

    .. math::  \gamma = \sqrt{\|K\| / \|M\|}, \qquad
               \delta = 2 / (\|K\| + \gamma \|C\|)

    (Fan, Lin and Van Dooren, SIAM J. Matrix Anal. Appl. 26, 2004).  The companion pencil of
    ``delta (gamma^2 mu^2 M + gamma mu C + K)`` has blocks of comparable norm, so that the
    backward error of the QZ algorithm is small relative to each coefficient (unscaled, masses
    of ``2e3`` beside stiffnesses of ``7e-4`` gave roots wrong by ``5e-7``).
    """
    if m2 <= 0 or k2 <= 0:
        return 1.0, 1.0 / max(m2, c2, k2, 1e-300)
    gamma = np.sqrt(k2 / m2)
    return gamma, 2.0 / (k2 + c2 * gamma)


def _linearized_pencil(Mq: np.ndarray, Cq: np.ndarray, Kq: np.ndarray):
    """First companion form of ``lambda^2 Mq + lambda Cq + Kq``: ``X v = lambda Y v``,
    ``v = [lambda u; u]``."""
    n = Mq.shape[0]
    I, Z0 = np.eye(n), np.zeros((n, n))
    X = np.block([[-Cq, -Kq], [I, Z0]])
    Y = np.block([[Mq, Z0], [Z0, I]])
    return X, Y


def _roots(X: np.ndarray, Y: np.ndarray, n: int,
           gamma: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Finite-or-infinite roots ``gamma mu`` of ``X v = mu Y v`` and the displacement parts of
    ``v`` (the second block of ``v = [mu u; u]``)."""
    ab, V = sla.eig(X, Y, homogeneous_eigvals=True, check_finite=True)
    alpha, beta = ab
    with np.errstate(divide="ignore", invalid="ignore"):
        lam = np.where(np.abs(beta) > 0, gamma * alpha / np.where(beta == 0, 1, beta), np.inf)
    U = V[n:2 * n]
    return lam, U


def _quadratic_roots(Mq: np.ndarray, Cq: np.ndarray,
                     Kq: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Roots and displacement vectors of ``lambda^2 Mq + lambda Cq + Kq``, by the scaled
    companion pencil (:func:`_fan_lin_van_dooren`)."""
    norm = lambda X: float(np.linalg.norm(X))  # noqa: E731
    gamma, delta = _fan_lin_van_dooren(norm(Mq), norm(Cq), norm(Kq))
    X, Y = _linearized_pencil(delta * gamma**2 * Mq, delta * gamma * Cq, delta * Kq)
    return _roots(X, Y, Mq.shape[0], gamma)


def _forms(U: np.ndarray, *mats: np.ndarray) -> list[np.ndarray]:
    """``u_j^T X u_j`` for every column ``u_j`` of ``U`` and every real matrix ``X``."""
    out = []
    for X in mats:
        XU = X @ U.real + 1j * (X @ U.imag) if np.iscomplexobj(U) else X @ U
        out.append(np.sum(U * XU, axis=0))
    return out


def _rayleigh(lam: complex, a: complex, b: complex, c: complex,
              trust: float = 1e-3) -> tuple[complex, bool]:
    r"""A root refined by Newton steps on the Rayleigh functional of its computed vector.

    .. math::  f(\lambda) = u^T (\lambda^2 M + \lambda C + K) u + e(u)
               = a \lambda^2 + b \lambda + c = 0

    (``u^T``, not ``u^H``: ``M``, ``C``, ``K`` are real symmetric, the problem complex
    symmetric, and ``f`` is stationary at an eigenvector; see :func:`_forms`).  ``u`` must
    satisfy ``A u = 0``, or ``e`` must carry the constraint term (``2 mu^T A u`` with the KKT
    multipliers).  The error is of second order in the error of ``u``, and ``u^T K u`` is
    accurate to rounding *componentwise*, while QZ on a linearization is only normwise backward
    stable: a root far below the largest one loses ``eps (|lambda|_max / |lambda|)^2`` of
    relative accuracy there (five digits for a stiffness of ``1e12`` beside ``1``, three for a
    slow decay next to a zero root).  The correction is kept only when it is small
    (``trust |lambda|``) and lowers ``|f|``.

    Returns:
        ``(root, kept)``: the refined root and ``True``, or ``lam`` and ``False``.
    """
    f = lambda x: (a * x + b) * x + c  # noqa: E731
    x = complex(lam)
    for _ in range(3):
        d = 2 * a * x + b
        if d == 0:
            break
        x = x - f(x) / d
    if np.isfinite(x) and abs(x - lam) <= trust * abs(lam) and abs(f(x)) <= abs(f(lam)):
        return x, True
    return complex(lam), False


def _refiner(U: np.ndarray, M: np.ndarray, C: np.ndarray, K: np.ndarray,
             extra: np.ndarray | None = None
             ) -> Callable[[int, complex], tuple[complex, np.ndarray | None]]:
    """``refine(j, lambda)`` for :func:`_classify`: :func:`_rayleigh` on column ``j`` of ``U``
    (``extra[j]`` added to ``u^T K u``); the forms are computed once, on first use."""
    cache: list = []

    def refine(j: int, lam: complex) -> tuple[complex, np.ndarray | None]:
        if not cache:
            a, b, c = _forms(U, M, C, K)
            cache.extend([a, b, c if extra is None else c + extra])
        a, b, c = cache
        return _rayleigh(lam, a[j], b[j], c[j])[0], None

    return refine


def _root_scale(M: np.ndarray, C: np.ndarray, K: np.ndarray) -> float:
    """A root magnitude no physical root much exceeds, from the diagonals (rad/s)."""
    dm, dk, dc = np.abs(np.diag(M)), np.abs(np.diag(K)), np.abs(np.diag(C))
    mpos = dm[dm > 0]
    mmin = mpos.min() if mpos.size else 1.0
    return max(np.sqrt(dk.max(initial=0.0) / mmin), dc.max(initial=0.0) / mmin, 1e-300)


@dataclass(frozen=True)
class _Structure:
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


def _rigid_basis(K: np.ndarray, A: np.ndarray) -> np.ndarray:
    r"""Orthonormal basis of ``null(K) & null(A)``, decided on the equilibrated matrices.

    .. math::  D = \operatorname{diag}(K_{ii})^{-1/2}, \qquad
               \operatorname{null} \begin{bmatrix} D K D \\ \operatorname{rows}(A D) \end{bmatrix}

    ``D K D`` has a unit diagonal and entries at most one (``K`` positive semidefinite), so the
    rank decision does not depend on units nor on a stiff spring next to a soft one (``K_ii``
    of ``1e12`` beside ``1`` would otherwise look like a rank-deficient ``K``).
    """
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
    null = Vh.conj().T[:, sv <= RIGID_TOL * max(sv[0], 1.0)]
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


def _structure(M: np.ndarray, C: np.ndarray, K: np.ndarray, A: np.ndarray) -> _Structure:
    """Counts of zero and finite roots (see :class:`_Structure`); ``M``, ``C``, ``K`` symmetric,
    ``M`` positive definite on the coordinates that have mass, ``C``, ``K`` semidefinite.

    Raises:
        ValueError: a motion with no mass, no stiffness and no constraint (singular pencil).
    """
    n = K.shape[0]
    rank = independent_rows(A).rank if A.size else 0
    rigid = _rigid_basis(K, A)
    n_zero = 0
    if rigid.shape[1]:
        Mr = rigid.T @ M @ rigid
        w, V = np.linalg.eigh((Mr + Mr.T) / 2)
        if w.min() <= 1e-12 * max(np.abs(M).max(), 1e-300):
            raise ValueError("singular model: a motion with no mass, no stiffness and no "
                             "constraint (a massless coordinate attached to nothing)")
        rigid = rigid @ (V / np.sqrt(w))  # M-orthonormal
        Cr = rigid.T @ C @ rigid
        rates = np.abs(np.linalg.eigvalsh((Cr + Cr.T) / 2))
        n_undamped = int(np.sum(rates <= RIGID_DAMPING_TOL * _root_scale(M, C, K)))
        n_zero = rigid.shape[1] + n_undamped
    massless = np.flatnonzero(np.abs(M).sum(axis=1) == 0)
    if massless.size:
        As = A[:, massless] if A.size else np.zeros((0, massless.size))
        S = null_space_basis(As) if As.size and np.any(As) else np.eye(massless.size)
        S0 = np.zeros((n, S.shape[1]))
        S0[massless] = S
    else:
        S0 = np.zeros((n, 0))
    n_first = 0
    if S0.shape[1] and np.any(C):
        C0 = S0.T @ C @ S0
        ev = np.abs(np.linalg.eigvalsh((C0 + C0.T) / 2))
        n_first = int(np.sum(ev > DAMPING_RANK_TOL * np.abs(C).max()))
    n_finite = 2 * (n - rank - S0.shape[1]) + n_first
    return _Structure(rank=rank, rigid=rigid, n_zero=n_zero, n_finite=n_finite)


_SPURIOUS_ZERO = ("zero root of the projected operator M*K: its vector violates A u = 0 "
                  "(artifact of eqs 30/34, one pair per independent constraint)")
_INFINITE = ("infinite root: a massless coordinate or a Lagrange multiplier with no mass "
             "attached")


def _classify(lam: np.ndarray, U: np.ndarray, A: np.ndarray, M: np.ndarray, C: np.ndarray,
              K: np.ndarray, method: str,
              refine: Callable[[int, complex], tuple[complex, np.ndarray | None]] | None = None
              ) -> Modes:
    """Split roots into physical modes and roots set aside; see the module docstring.

    The split is by counts that the matrices fix (:func:`_structure`), not by thresholds on
    root magnitudes, which fail when a stiffness of ``1e12`` sits beside one of ``1``:

    * the largest ``2n - n_finite`` roots (``n_finite`` plus ``2 rank(A)`` for eqs 30/34) are
      infinite roots: massless coordinates, Lagrange multipliers (higher-index infinite roots
      come out as large finite numbers, near ``eps^{-1/2}`` or ``eps^{-1/3}`` times the scale);
    * of the finite roots the smallest ``n_zero`` (plus ``2 rank(A)`` for eqs 30/34) are zero
      roots; the ``2 rank(A)`` of eqs (30)/(34) are artifacts whose vectors violate
      ``A u = 0``; rigid-body modes (``K u = 0``, ``A u = 0``) are reported as physical zeros
      with their vectors taken from ``null(K) & null(A)``, because a zero root shared with
      spurious ones has no meaningful vector;
    * the other finite roots must satisfy ``A u = 0`` (checked; a root that does not is set
      aside with its residual as the reason); ``refine(j, lambda_j)``, given by each
      formulation, polishes them (:func:`_rayleigh`) and may return a better vector.

    Reporting: complex roots come in conjugate pairs and one of each pair (``Im > 0``) is a
    mode; a real root (``|Im| <= REAL_TOL |lambda|``: over- or critically damped) is a mode of
    its own, with ``Im`` set to zero, ``omega = |lambda|`` and damping ratio 1 (``-1`` if it
    grows), so an over-damped pair gives two entries; an undamped rigid-body mode (a double
    zero) is one entry with ``omega = 0`` and damping ratio 0.
    """
    n = U.shape[0]
    An = np.linalg.norm(A, 2) if A.size else 1.0
    st = _structure(M, C, K, A)
    extra = 2 * st.rank if method == "generalized-inverse" else 0
    mag = np.where(np.isfinite(lam), np.abs(lam), np.inf)
    order = np.argsort(mag, kind="stable")
    n_fin = min(st.n_finite + extra, lam.size)
    n_zero = min(st.n_zero + extra, n_fin)
    zero_idx, rest_idx, inf_idx = order[:n_zero], order[n_zero:n_fin], order[n_fin:]

    def residual(u: np.ndarray) -> float:
        if not A.size:
            return 0.0
        return float(np.linalg.norm(A @ u) / (An * max(np.linalg.norm(u), 1e-300)))

    spurious: list[complex] = []
    reasons: list[str] = []
    # the 2 rank(A) artifacts of eqs 30/34 among the zero roots: those that violate A u = 0 most
    zres = np.array([residual(U[:, j]) for j in zero_idx])
    for j in zero_idx[np.argsort(-zres, kind="stable")][:extra]:
        spurious.append(complex(lam[j]))
        reasons.append(_SPURIOUS_ZERO)
    phys_lam: list[complex] = [0j] * st.rigid.shape[1]
    phys_u: list[np.ndarray] = [st.rigid[:, j].astype(complex) for j in range(st.rigid.shape[1])]
    for j in rest_idx:
        l, u = complex(lam[j]), U[:, j]
        r = residual(u)
        if r > RESIDUAL_TOL:
            spurious.append(l)
            reasons.append(f"violates the constraints: |A u|/(|A||u|) = {r:.2e}")
            continue
        real = abs(l.imag) <= REAL_TOL * abs(l)
        if not real and l.imag < 0:
            continue  # the conjugate of a kept root
        if refine is not None:
            l, better = refine(j, l)
            u = u if better is None else better
        if real:
            l = complex(l.real, 0.0)  # real: each root is its own mode
        phys_lam.append(l)
        phys_u.append(u)
    for j in inf_idx:
        spurious.append(complex(lam[j]) if np.isfinite(lam[j]) else complex(np.inf))
        reasons.append(_INFINITE)

    lam_p = np.array(phys_lam, dtype=complex)
    Up = np.array(phys_u, dtype=complex).T.reshape(n, -1)
    order = np.lexsort((lam_p.real, np.abs(lam_p)))
    lam_p, Up = lam_p[order], Up[:, order]
    Up = _normalize(Up, M)
    omega = np.abs(lam_p)
    with np.errstate(invalid="ignore", divide="ignore"):
        zeta = np.where(omega > 0, -lam_p.real / np.where(omega > 0, omega, 1), 0.0)
    res = np.array([residual(Up[:, j]) for j in range(Up.shape[1])])
    return Modes(eigenvalues=lam_p, omega=omega, damping_ratio=zeta, shapes=Up, residual=res,
                 spurious=np.array(spurious, dtype=complex), spurious_reason=reasons,
                 method=method)


def _normalize(U: np.ndarray, M: np.ndarray) -> np.ndarray:
    """Each column: phase so its largest entry is real positive; scaled to ``u^H M u = 1`` if
    that is positive, else to unit norm."""
    if not U.shape[1]:
        return U
    k = np.argmax(np.abs(U), axis=0)
    top = U[k, np.arange(U.shape[1])]
    U = U * np.where(np.abs(top) > 0, np.abs(top) / np.where(top == 0, 1, top), 1.0)
    MU = M @ U.real + 1j * (M @ U.imag)
    mass = np.real(np.sum(np.conj(U) * MU, axis=0))
    norm = np.linalg.norm(U, axis=0)
    scale = np.where(mass > 1e-14 * norm**2 * max(np.abs(M).max(), 1e-300),
                     np.sqrt(np.abs(mass)), norm)
    return U / np.where(scale > 0, scale, 1.0)


def _modes_generalized_inverse(M, C, K, A) -> Modes:
    """Eqs (28)-(34): the state-space pencil of the projected equations.

    Solved for ``mu = lambda / gamma`` with ``gamma = sqrt(|M^* K| / |T|)``, which balances the
    blocks of (32)-(34) the way :func:`_fan_lin_van_dooren` balances a companion pencil.
    """
    n = K.shape[0]
    ms = split_mass(sp.csr_array(M))
    Mstar = projected_inverse(ms, A)
    Mo = dense(ms.Mo)
    T = np.eye(n) - Mstar @ Mo
    # eq (33) carries T in its first block row as well (T u' = T u'); that row only defines the
    # velocity, and with a massless coordinate that no constraint reaches T is singular and the
    # pencil would be singular too.  The identity there gives the same roots when T is regular.
    I = np.eye(n)
    MsK, MsC = Mstar @ K, Mstar @ C
    gamma, _ = _fan_lin_van_dooren(float(np.linalg.norm(T)), float(np.linalg.norm(MsC)),
                                   float(np.linalg.norm(MsK)))
    Wm = np.block([[np.zeros((n, n)), I], [T, MsC / gamma]])
    Rm = np.block([[I, np.zeros((n, n))], [np.zeros((n, n)), -MsK / gamma**2]])
    lam, U = _roots(Rm, Wm, n, gamma)
    return _classify(lam, U, A, M, C, K, "generalized-inverse", _gi_polish(ms, M, C, K, A, U))


def _gi_polish(ms, M, C, K, A, U) -> Callable[[int, complex], tuple[complex, np.ndarray | None]]:
    r"""Refinement of the roots of eqs (32)-(34) within the generalized-inverse formulation.

    The pencil carries ``M^* K``, in which the projector of eq (10) mixes the rows of ``K``:
    with a stiffness of ``1e12`` next to ``1`` its soft entries are known to ``1e-4`` only, and
    so are the soft modes' roots and vectors.  The vector ``u`` is projected onto ``null(A)``
    (``P = I - M_d^{-1} A^T S^+ A``, eqs 5, 10) and the root refined on its Rayleigh functional
    (:func:`_rayleigh`); if that moves the root by more than ``1e-11`` of itself the vector is
    not good enough, and one step of inverse iteration with the receptance of eq (15) at
    ``lambda``, which works with ``K`` itself, replaces it.  The vector reported is the projected
    one (the pencil's own has ``|A u|`` of ``eps cond``, ``2e-10`` seen):

    .. math::  G_\alpha(\lambda)\, x = D_\alpha M u, \qquad
               G_\alpha = -Z + A^T S^+ (A M_d^{-1} Z + \alpha A), \quad
               D_\alpha = A^T S^+ A M_d^{-1} - I, \quad Z = \lambda^2 M + \lambda C + K
    """
    n = K.shape[0]
    if A.size:
        Y, Sp = constraint_gain(ms, A)
        P = np.eye(n) - Y @ Sp @ A
        normA = float(np.linalg.norm(A))
    else:
        P = np.eye(n)

    cache: list = []

    def polish(j: int, lam: complex) -> tuple[complex, np.ndarray | None]:
        if not cache:
            cache.extend(_forms(P @ U, M, C, K))
        first, kept = _rayleigh(lam, cache[0][j], cache[1][j], cache[2][j])
        u = P @ U[:, j]
        if kept and abs(first - lam) <= 1e-11 * abs(lam):
            return first, u
        Z = lam**2 * M + lam * C + K
        f = M @ u
        if A.size:
            YtZ = Y.T @ Z
            alpha = max(abs(lam) ** 2, float(np.linalg.norm(YtZ)) / normA)
            G = -Z + A.T @ (Sp @ (YtZ + alpha * A))
            rhs = A.T @ (Sp @ (Y.T @ f)) - f
        else:
            G, rhs = -Z, -f
        try:
            x = P @ np.linalg.solve(G, rhs)
        except np.linalg.LinAlgError:
            return first, u
        if not np.all(np.isfinite(x)) or not np.any(x):
            return first, u
        a, b, c = (v[0] for v in _forms(x[:, None], M, C, K))
        second, kept = _rayleigh(lam, a, b, c, trust=0.1)
        return (second, x) if kept else (first, u)

    return polish


def _modes_null_space(M, C, K, A) -> Modes:
    """``u = N p`` with ``A N = 0``: ``N^T (lambda^2 M + lambda C + K) N p = 0``."""
    n = K.shape[0]
    N = null_space_basis(A) if A.size else np.eye(n)
    Mr, Cr, Kr = N.T @ M @ N, N.T @ C @ N, N.T @ K @ N
    if not N.shape[1]:  # the constraints fix every coordinate: no motion at all
        lam, U = np.zeros(0, complex), np.zeros((n, 0), complex)
    elif not np.any(Cr) and np.linalg.eigvalsh((Mr + Mr.T) / 2).min() > 1e-12 * \
            max(np.abs(Mr).max(), 1e-300):
        w2, P = sla.eigh(Kr, Mr)
        lam = np.sqrt(w2.astype(complex)) * 1j  # a negative w2 (unstable) gives a real root
        U = N @ P
        lam = np.concatenate([lam, lam.conj()])
        U = np.hstack([U, U])
    else:
        lam, P = _quadratic_roots(Mr, Cr, Kr)
        U = N @ P
    U = U.astype(complex)
    return _classify(lam, U, A, M, C, K, "null-space", _refiner(U, M, C, K))


def _modes_kkt(M, C, K, A) -> Modes:
    """Lagrange multipliers: the pencil ``lambda^2 [M,0;0,0] + lambda [C,0;0,0] + [K,A^T;A,0]``."""
    n = K.shape[0]
    rows = independent_rows(A)
    Ak = A[rows.keep] if A.size else np.zeros((0, n))
    if Ak.size:  # multipliers in units of force: A^T of the size of K
        Ak = Ak * (np.linalg.norm(K) / np.linalg.norm(Ak) if np.any(K) else 1.0)
    r = Ak.shape[0]
    Mq = sla.block_diag(M, np.zeros((r, r)))
    Cq = sla.block_diag(C, np.zeros((r, r)))
    Kq = np.block([[K, Ak.T], [Ak, np.zeros((r, r))]])
    lam, V = _quadratic_roots(Mq, Cq, Kq)
    # the KKT functional adds 2 mu^T A u (the multipliers of the scaled rows)
    return _classify(lam, V[:n], A, M, C, K, "kkt",
                     _refiner(V[:n], M, C, K, 2 * np.sum(V[n:] * (Ak @ V[:n]), axis=0)))


def coupled_modes(M: sp.sparray | np.ndarray, C: sp.sparray | np.ndarray | None,
                  K: sp.sparray | np.ndarray, A: sp.sparray | np.ndarray | None,
                  method: str = "generalized-inverse", n_modes: int | None = None) -> Modes:
    r"""Physical modes of ``M u'' + C u' + K u = 0`` under ``A u = 0`` (eqs 23-34).

    Args:
        M, C, K: ``n x n`` matrices (``M`` may be singular on massless coordinates, eq 6).
        A: ``m x n`` constraint matrix of any rank (``None`` for none).
        method: ``"generalized-inverse"`` (the paper's eqs 28-34), ``"null-space"`` or ``"kkt"``.
        n_modes: keep the lowest ``n_modes`` physical modes (all if ``None``).

    Dense algebra: for the reduced models of the paper (a few thousand coordinates at most).
    """
    Md = dense(sp.csr_array(M, dtype=float))
    n = Md.shape[0]
    Kd = dense(sp.csr_array(K, dtype=float))
    Cd = np.zeros((n, n)) if C is None else dense(sp.csr_array(C, dtype=float))
    Ad = np.zeros((0, n)) if A is None or np.size(A) == 0 else \
        dense(sp.csr_array(A, dtype=float))
    if method == "generalized-inverse":
        modes = _modes_generalized_inverse(Md, Cd, Kd, Ad)
    elif method == "null-space":
        modes = _modes_null_space(Md, Cd, Kd, Ad)
    elif method == "kkt":
        modes = _modes_kkt(Md, Cd, Kd, Ad)
    else:
        raise ValueError(f"unknown method {method!r}; expected one of {', '.join(MODE_METHODS)}")
    if n_modes is not None:
        k = min(n_modes, len(modes))
        modes = Modes(modes.eigenvalues[:k], modes.omega[:k], modes.damping_ratio[:k],
                      modes.shapes[:, :k], modes.residual[:k], modes.spurious,
                      modes.spurious_reason, modes.method)
    return modes


def modes_agreement(a: Modes, b: Modes) -> float:
    r"""Largest relative difference between the eigenvalues of two mode sets.

    .. math::  \delta = \max_j |\lambda^a_j - \lambda^b_j| / \max(|\lambda^b_j|, \epsilon)

    over the common number of modes; ``inf`` if one set has no modes and the other has.
    """
    k = min(len(a), len(b))
    if k == 0:
        return 0.0 if len(a) == len(b) else float("inf")
    scale = max(np.abs(b.eigenvalues[:k]).max(), 1e-300)
    denom = np.maximum(np.abs(b.eigenvalues[:k]), 1e-8 * scale)
    return float(np.max(np.abs(a.eigenvalues[:k] - b.eigenvalues[:k]) / denom))
