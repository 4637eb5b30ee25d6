r"""The generalized-inverse (Udwadia-Kalaba) projection of a constrained system, eqs (5)-(10).

Paper equations in the paper's order, each beside its code:

* eq (5), constrained acceleration, in the form that scales to sparse matrices,

  .. math::  M^{-1/2} (A M^{-1/2})^+ = M^{-1} A^T (A M^{-1} A^T)^+

  (``B^+ = B^T (B B^T)^+`` with ``B = A M^{-1/2}``): only solves with ``M`` and an ``m x m``
  pseudo-inverse are needed, never ``M^{1/2}``;
* eqs (6)-(10), semidefinite mass: ``M = M_d - M_o`` with ``M_o`` the identity on the massless
  coordinates (times the mean mass, see :class:`MassSplit`),
  ``M^* = [I - M_d^{-1} A^T (A M_d^{-1} A^T)^+ A] M_d^{-1}``.

``I - M_d^{-1} A^T (A M_d^{-1} A^T)^+ A`` is the ``M_d``-orthogonal projector onto
:math:`\operatorname{null}(A)`; the receptance (eqs 11-15, :mod:`substruct.analysis.formulations.coupling`)
and the coupled modes (eqs 28-34, :mod:`substruct.analysis.modes.dense`) are built on it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from substruct.analysis.errors import AnalysisInputError
from substruct.linalg.constraints import independent_rows, pinv_sym
from substruct.linalg.dense import dense
from substruct.linalg.factorize import Solve, factorizer
from substruct.linalg.massless import MASSLESS_TOL
from substruct.linalg.scaling import (
    equilibrate,
    mass_column_scale,
    massless_coordinates,
)

__all__ = [
    "MassSplit",
    "constrained_acceleration",
    "constraint_gain",
    "nearly_singular",
    "projected_inverse",
    "split_mass",
]


@dataclass(frozen=True)
class MassSplit:
    r"""The split ``M = M_d - M_o`` of eq (7) and a factorization of ``M_d``.

    ``M_o`` is ``mu`` times the identity on the massless coordinates (zero rows of ``M``, eq 6)
    and zero elsewhere, so ``M_d = M + M_o`` is positive definite when ``M`` is positive definite
    on the coordinates that have mass.  The paper takes ``mu = 1``; any ``mu > 0`` gives the same
    constrained motion (eq 10 holds for every such split), and ``mu`` of the size of the masses
    keeps ``M_d`` as well conditioned as ``M_a``: with ``mu = 1`` and masses of ``1e3`` the
    condition number of ``M_d`` grows a thousandfold and so does the error of ``M^*``.
    """

    Md: sp.csc_array
    massless: np.ndarray
    factor: Solve
    mu: float = 1.0

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """``M_d^{-1} rhs`` (real or complex ``rhs``)."""
        return self.factor(np.asarray(rhs))

    @property
    def Mo(self) -> sp.csr_array:
        """``M_o`` of eq (7)."""
        return sp.diags_array(self.mu * self.massless.astype(float)).tocsr()


def split_mass(M: sp.sparray | np.ndarray) -> MassSplit:
    r"""Split a positive semidefinite mass matrix as in eq (7) and factorize ``M_d``.

    .. math::  M = M_d - M_o, \quad M_d = \begin{bmatrix} M_a & 0 \\ 0 & \mu I\end{bmatrix},
               \quad M_o = \begin{bmatrix} 0 & 0 \\ 0 & \mu I\end{bmatrix}, \quad
               \mu = \operatorname{mean} \operatorname{diag} M_a
    """
    M = sp.csr_array(M, dtype=float)
    massless = massless_coordinates(M)
    diag = M.diagonal()[~massless]
    mu = float(np.mean(np.abs(diag))) if diag.size and np.any(diag) else 1.0
    Md = (M + sp.diags_array(mu * massless.astype(float))).tocsc()
    try:  # partial pivoting: an M_d singular on the coordinates with mass is reported
        factor = factorizer("superlu", spd=False)(Md)
    except RuntimeError as exc:  # exactly singular
        raise AnalysisInputError(SINGULAR_MASS) from exc
    if nearly_singular(Md, factor):
        raise AnalysisInputError(SINGULAR_MASS)
    return MassSplit(Md=Md, massless=massless, factor=factor, mu=mu)


#: The refusal of a mass matrix singular on coordinates that have mass.
SINGULAR_MASS = ("mass matrix is singular on coordinates that have mass (a combination of "
                 "them carries none, e.g. a point mass off its node without inertia, or a "
                 "pinned beam end in skew axes): the generalized-inverse formulation needs "
                 "M positive definite off its zero rows; method null-space or kkt takes it")

#: Smallest eigenvalue of the mass matrix scaled to equal diagonal entries (the coordinates'
#: masses made comparable, :func:`substruct.linalg.scaling.mass_column_scale`), over that
#: diagonal, below which it is singular.  Measured on the worked cases: 4.5e-4 (shells,
#: quadratic solids) to 1 (lumped); a direction without mass is at round-off (-4e-16 for a
#: pinned CBAR end in skew axes with coupled mass).  The one threshold of the massless
#: directions the eigensolvers count (:data:`substruct.linalg.massless.MASSLESS_TOL`).
SINGULAR_MASS_TOL = MASSLESS_TOL


def nearly_singular(Md: sp.sparray, factor: Solve, steps: int = 3) -> bool:
    r"""Whether ``M_d`` is singular to round-off: the smallest eigenvalue of
    :math:`C M_d C` (``C`` of :func:`~substruct.linalg.scaling.mass_column_scale`, which makes
    every diagonal entry the mean mass) over that mean, below :data:`SINGULAR_MASS_TOL`,
    estimated by ``steps`` of inverse iteration with the factorization from a fixed start; the
    decision does not depend on the units.  :math:`1 / \|(C M_d C)^{-1} x\|` with
    :math:`\|x\| = 1` is never below the smallest eigenvalue, so a regular matrix is never
    called singular; a direction without mass dominates the first step."""
    n = Md.shape[0]
    if n == 0:
        return False
    c = mass_column_scale(Md)
    mean = float(np.mean(c**2 * np.abs(Md.diagonal())))
    x = np.random.default_rng(0).standard_normal(n)
    x /= np.linalg.norm(x)
    for _ in range(steps):
        y = np.asarray(factor(x / c)).ravel() / c
        norm = float(np.linalg.norm(y))
        if not np.isfinite(norm) or norm * mean * SINGULAR_MASS_TOL > 1.0:
            return True
        x = y / norm
    return False


def constraint_gain(M: sp.sparray | np.ndarray | MassSplit,
                    A: sp.sparray | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r"""The gain of the constraint correction in eq (5), in scalable form.

    .. math::  M^{-1/2} (A M^{-1/2})^+ = M^{-1} A^T S^+, \qquad S = A M^{-1} A^T

    With a semidefinite mass, ``M_d`` of eq (7) takes the place of ``M`` (eq 9).  The rank of
    ``S`` is the rank of ``A`` decided on equilibrated rows and mass-scaled columns
    (:func:`substruct.linalg.constraints.independent_rows`), never on the size of the
    eigenvalues of ``S`` alone, which scale with the rows (a row ``1e-8 q_1`` gives an
    eigenvalue ``1e-16``, which a relative cut takes for zero).

    Returns:
        ``(Y, S_pinv)`` with ``Y = M_d^{-1} A^T`` (``n x m``) and ``S_pinv = S^+`` (``m x m``);
        the gain is ``Y @ S_pinv``.
    """
    ms = M if isinstance(M, MassSplit) else split_mass(M)
    At = dense(sp.csr_array(A).T) if sp.issparse(A) else np.asarray(A).T
    Y = ms.solve(At) if At.size else np.zeros_like(At)
    Y = Y.reshape(At.shape)
    S = (At.T @ Y) if At.size else np.zeros((At.shape[1], At.shape[1]))
    rank = independent_rows(At.T, col_scale=mass_column_scale(ms.Md)).rank if At.size else 0
    return Y, pinv_sym(S, rank)


def projected_inverse(M: sp.sparray | np.ndarray | MassSplit,
                      A: sp.sparray | np.ndarray) -> np.ndarray:
    r"""``M^*`` of eq (10), dense (for reduced models).

    .. math::  M^* = \left[I - M_d^{-1/2} (A M_d^{-1/2})^+ A\right] M_d^{-1}
                   = M_d^{-1} - Y S^+ Y^T

    ``I - Y S^+ A`` is the ``M_d``-orthogonal projector onto ``null(A)``.
    """
    ms = M if isinstance(M, MassSplit) else split_mass(M)
    n = ms.Md.shape[0]
    Y, Sp = constraint_gain(ms, A)
    Minv = ms.solve(np.eye(n))
    return Minv - Y @ Sp @ Y.T


def constrained_acceleration(M: sp.sparray | np.ndarray, A: sp.sparray | np.ndarray,
                             b: np.ndarray, force: np.ndarray) -> np.ndarray:
    r"""Acceleration of a constrained system, eq (5), or eq (10) with massless coordinates.

    ``force`` is ``P - C \dot q - K q``.  With ``a = M^{-1} force``:

    .. math::  \ddot q = a + M^{-1} A^T (A M^{-1} A^T)^+ (b - A a)          \quad (5)

    With a semidefinite ``M`` (eqs 7-10):

    .. math::  (I - M^* M_o)\, \ddot q = M_d^{-1} A^T (A M_d^{-1} A^T)^+ b + M^* force  \quad (10)

    ``M^* M_o`` has nonzero columns only at the ``s`` massless coordinates, so (10) is solved by
    one ``s x s`` dense system; no ``n x n`` matrix is formed.

    The correction of eq (5) is applied once more to the result,
    ``\ddot q \leftarrow \ddot q + M_d^{-1} A^T S^+ (b - A \ddot q)``: in exact arithmetic it
    adds nothing; in floating point it removes the part of the rounding error that violates the
    constraint, which ``cond(S)`` amplifies (``|A q'' - b| = 3e-10 |A||q''|`` for 6 constraints
    on 7 coordinates, ``1e-16`` after).
    """
    ms = split_mass(M)
    A = sp.csr_array(A, dtype=float)
    b = np.asarray(b, dtype=float).ravel()
    if A.shape[0]:  # D A q'' = D b: the same motion, rows of unit norm
        eq = equilibrate(A, b)
        A, b = sp.csr_array(eq.A), np.asarray(eq.b)
    force = np.asarray(force, dtype=float).ravel()
    Y, Sp = constraint_gain(ms, A)

    def mstar(v: np.ndarray) -> np.ndarray:  # M^* v = M_d^{-1} v - Y S^+ Y^T v
        return ms.solve(v) - Y @ (Sp @ (Y.T @ v))

    rhs = Y @ (Sp @ b) + mstar(force)

    def refined(qdd: np.ndarray) -> np.ndarray:
        return qdd + Y @ (Sp @ (b - A @ qdd)) if A.shape[0] else qdd

    s = np.flatnonzero(ms.massless)
    if s.size == 0:
        return refined(rhs)
    E = np.zeros((ms.Md.shape[0], s.size))
    E[s, np.arange(s.size)] = 1.0
    cols = ms.mu * mstar(E)  # the columns of M^* M_o that are not zero
    lhs = np.eye(s.size) - cols[s]
    try:
        qs = np.linalg.solve(lhs, rhs[s])
    except np.linalg.LinAlgError as exc:
        raise AnalysisInputError("massless coordinates not determined by the constraints "
                         "(I - M* M_o is singular)") from exc
    return refined(rhs + cols @ qs)
