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
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from .constraints import dense, independent_rows, null_space_basis
from .coupling import projected_inverse, split_mass

__all__ = [
    "Modes",
    "coupled_modes",
    "modes_agreement",
    "MODE_METHODS",
]

MODE_METHODS: tuple[str, ...] = ("generalized-inverse", "null-space", "kkt")

#: A root counts as a physical mode when ``|A u| / (|A| |u|)`` is below this.
RESIDUAL_TOL = 1e-6
#: Roots below this fraction of the typical root ``sqrt(max K_ii / max M_ii)`` count as zero.
ZERO_TOL = 1e-6
#: Roots above this multiple of the largest possible root magnitude count as infinite.
INF_TOL = 1e4


@dataclass
class Modes:
    """Physical modes of a constrained system and the roots set aside.

    Attributes:
        eigenvalues: complex roots ``lambda`` (one of each conjugate pair, ``Im >= 0``),
            ascending in ``|lambda|``.
        omega: ``|lambda|`` in rad/s (the undamped natural frequency for proportional damping).
        damping_ratio: ``-Re(lambda) / |lambda|`` (0 for a zero root).
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


def _linearized_pencil(Mq: np.ndarray, Cq: np.ndarray, Kq: np.ndarray):
    """First companion form of ``lambda^2 Mq + lambda Cq + Kq``: ``X v = lambda Y v``,
    ``v = [lambda u; u]``."""
    n = Mq.shape[0]
    I, Z0 = np.eye(n), np.zeros((n, n))
    X = np.block([[-Cq, -Kq], [I, Z0]])
    Y = np.block([[Mq, Z0], [Z0, I]])
    return X, Y


def _roots(X: np.ndarray, Y: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Finite-or-infinite roots of ``X v = lambda Y v`` and the displacement parts of ``v``."""
    ab, V = sla.eig(X, Y, homogeneous_eigvals=True, check_finite=True)
    alpha, beta = ab
    with np.errstate(divide="ignore", invalid="ignore"):
        lam = np.where(np.abs(beta) > 0, alpha / np.where(beta == 0, 1, beta), np.inf)
    # the displacement is the second block of v = [lambda u; u]; for roots near infinity it is
    # tiny, so fall back to the velocity block divided by lambda
    U = V[n:2 * n]
    return lam, U


def _scales(M: np.ndarray, C: np.ndarray, K: np.ndarray) -> tuple[float, float]:
    """A typical and a largest possible root magnitude, from the matrix diagonals."""
    dm, dk, dc = np.abs(np.diag(M)), np.abs(np.diag(K)), np.abs(np.diag(C))
    kmax = max(dk.max(initial=0.0), 1e-300)
    mpos = dm[dm > 0]
    mmax = mpos.max() if mpos.size else 1.0
    mmin = mpos.min() if mpos.size else 1.0
    cpos = dc[dc > 0]
    typical = np.sqrt(kmax / mmax)
    largest = max(np.sqrt(kmax / mmin), (cpos.max() / mmin) if cpos.size else 0.0,
                  (kmax / cpos.min()) if cpos.size else 0.0)
    return typical, largest


def _classify(lam: np.ndarray, U: np.ndarray, A: np.ndarray, M: np.ndarray, C: np.ndarray,
              K: np.ndarray, method: str) -> Modes:
    """Split roots into physical modes and spurious roots; see the module docstring.

    * infinite roots (massless coordinates, multipliers) and the large finite roots that stand
      for them numerically (higher-index infinite roots come out near ``eps^{-1/2}``);
    * roots whose vector violates ``A u = 0``: the ``2 rank(A)`` zero roots of eqs (30)/(34);
    * rigid-body modes: ``K u = 0`` and ``A u = 0`` (``K`` positive semidefinite), found
      directly, because a zero root shared with spurious roots has no meaningful vector.
    """
    n = U.shape[0]
    An = np.linalg.norm(A, 2) if A.size else 1.0
    typical, largest = _scales(M, C, K)
    mag = np.abs(lam)
    finite = np.isfinite(lam) & (mag < INF_TOL * largest)
    zero_thr = ZERO_TOL * typical

    def residual(u: np.ndarray) -> float:
        if not A.size:
            return 0.0
        return float(np.linalg.norm(A @ u) / (An * max(np.linalg.norm(u), 1e-300)))

    # rigid-body modes: null([K; A])
    stacked = np.vstack([K / max(np.abs(K).max(), 1e-300), A / An]) if A.size else \
        K / max(np.abs(K).max(), 1e-300)
    _, sv, Vh = sla.svd(stacked)
    sv = np.concatenate([sv, np.zeros(n - sv.size)])
    rigid = Vh.conj().T[:, sv <= 1e-9]

    spurious: list[complex] = []
    reasons: list[str] = []
    for l in lam[~finite]:
        spurious.append(complex(l) if np.isfinite(l) else complex(np.inf))
        reasons.append("infinite root: a massless coordinate or a Lagrange multiplier "
                       "with no mass attached")
    phys_lam: list[complex] = [0j] * rigid.shape[1]
    phys_u: list[np.ndarray] = [rigid[:, j].astype(complex) for j in range(rigid.shape[1])]
    zero_spurious: list[complex] = []
    for l, u in zip(lam[finite], U[:, finite].T):
        is_zero = abs(l) <= zero_thr
        if is_zero and rigid.shape[1]:
            zero_spurious.append(complex(l))  # rigid roots and spurious zeros, sorted out below
            continue
        r = residual(u)
        if r > RESIDUAL_TOL:
            spurious.append(complex(l))
            reasons.append(
                "zero root of the projected operator M*K: its vector violates A u = 0 "
                "(artifact of eqs 30/34, one pair per independent constraint)" if is_zero else
                f"violates the constraints: |A u|/(|A||u|) = {r:.2e}")
            continue
        if l.imag < -1e-9 * abs(l):
            continue  # the conjugate of a kept root
        phys_lam.append(complex(l))
        phys_u.append(u)
    # each rigid-body mode accounts for a double zero root; the other zeros are spurious
    zero_spurious.sort(key=abs)
    for l in zero_spurious[2 * rigid.shape[1]:]:
        spurious.append(l)
        reasons.append("zero root of the projected operator M*K: its vector violates A u = 0 "
                       "(artifact of eqs 30/34, one pair per independent constraint)")

    lam_p = np.array(phys_lam, dtype=complex)
    Up = np.array(phys_u, dtype=complex).T.reshape(n, -1)
    # real roots (overdamped) are each kept; a root with Im ~ 0 and its twin are distinct roots
    order = np.lexsort((lam_p.real, np.abs(lam_p)))
    lam_p, Up = lam_p[order], Up[:, order]
    Up = np.column_stack([_normalize(Up[:, j], M) for j in range(Up.shape[1])]) \
        if Up.shape[1] else Up
    omega = np.abs(lam_p)
    with np.errstate(invalid="ignore", divide="ignore"):
        zeta = np.where(omega > 0, -lam_p.real / np.where(omega > 0, omega, 1), 0.0)
    res = np.array([residual(Up[:, j]) for j in range(Up.shape[1])])
    return Modes(eigenvalues=lam_p, omega=omega, damping_ratio=zeta, shapes=Up, residual=res,
                 spurious=np.array(spurious, dtype=complex), spurious_reason=reasons,
                 method=method)


def _normalize(u: np.ndarray, M: np.ndarray) -> np.ndarray:
    """Phase so the largest entry is real positive; scale to ``u^H M u = 1`` if positive."""
    k = int(np.argmax(np.abs(u)))
    if abs(u[k]) > 0:
        u = u * (abs(u[k]) / u[k])
    mass = float(np.real(np.conj(u) @ (M @ u)))
    scale = np.sqrt(mass) if mass > 1e-14 * np.linalg.norm(u) ** 2 * max(np.abs(M).max(), 1e-300) \
        else np.linalg.norm(u)
    return u / scale if scale > 0 else u


def _modes_generalized_inverse(M, C, K, A) -> Modes:
    """Eqs (28)-(34): the state-space pencil of the projected equations."""
    n = K.shape[0]
    ms = split_mass(sp.csr_array(M))
    Mstar = projected_inverse(ms, A)
    Mo = np.diag(ms.massless.astype(float))
    T = np.eye(n) - Mstar @ Mo
    # eq (33) carries T in its first block row as well (T u' = T u'); that row only defines the
    # velocity, and with a massless coordinate that no constraint reaches T is singular and the
    # pencil would be singular too.  The identity there gives the same roots when T is regular.
    I = np.eye(n)
    Wm = np.block([[np.zeros((n, n)), I], [T, Mstar @ C]])
    Rm = np.block([[I, np.zeros((n, n))], [np.zeros((n, n)), -Mstar @ K]])
    lam, U = _roots(Rm, Wm, n)
    return _classify(lam, U, A, M, C, K, "generalized-inverse")


def _modes_null_space(M, C, K, A) -> Modes:
    """``u = N p`` with ``A N = 0``: ``N^T (lambda^2 M + lambda C + K) N p = 0``."""
    n = K.shape[0]
    N = null_space_basis(A) if A.size else np.eye(n)
    Mr, Cr, Kr = N.T @ M @ N, N.T @ C @ N, N.T @ K @ N
    if not np.any(Cr) and np.linalg.eigvalsh((Mr + Mr.T) / 2).min() > 1e-12 * \
            max(np.abs(Mr).max(), 1e-300):
        w2, P = sla.eigh(Kr, Mr)
        lam = np.sqrt(w2.astype(complex)) * 1j  # a negative w2 (unstable) gives a real root
        U = N @ P
        lam = np.concatenate([lam, lam.conj()])
        U = np.hstack([U, U])
    else:
        X, Y = _linearized_pencil(Mr, Cr, Kr)
        lam, P = _roots(X, Y, N.shape[1])
        U = N @ P
    return _classify(lam, U.astype(complex), A, M, C, K, "null-space")


def _modes_kkt(M, C, K, A) -> Modes:
    """Lagrange multipliers: the pencil ``lambda^2 [M,0;0,0] + lambda [C,0;0,0] + [K,A^T;A,0]``."""
    n = K.shape[0]
    rows = independent_rows(A)
    Ak = A[rows.keep] if A.size else np.zeros((0, n))
    r = Ak.shape[0]
    Mq = sla.block_diag(M, np.zeros((r, r)))
    Cq = sla.block_diag(C, np.zeros((r, r)))
    Kq = np.block([[K, Ak.T], [Ak, np.zeros((r, r))]])
    X, Y = _linearized_pencil(Mq, Cq, Kq)
    lam, V = _roots(X, Y, n + r)
    return _classify(lam, V[:n], A, M, C, K, "kkt")


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
