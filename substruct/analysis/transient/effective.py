r"""The solve with the effective matrix of the generalized-inverse form, and its constraint
correction.

The step solves with :math:`S = (1 - \alpha_m) M + (1 - \alpha_f) \gamma h C + (1 - \alpha_f)
\beta h^2 K` (:func:`substruct.analysis.transient.integrators.effective_matrix`) and corrects
the result onto the constraints,

.. math::  a = a^0 + S^{-1} A^T (A S^{-1} A^T)^+ (c - A a^0), \qquad a^0 = S^{-1} r ,

which is the solution of the saddle-point system
:math:`\begin{bmatrix} S & A^T \\ A & 0 \end{bmatrix}
\begin{bmatrix} a \\ \lambda \end{bmatrix} = \begin{bmatrix} r \\ c \end{bmatrix}`.
:math:`S` is singular where a motion :math:`z` has neither mass, nor damping, nor stiffness
(:math:`M z = C z = K z = 0`): the common motion of the two massless ends of a spring, a
massless coordinate with no element at all.  Such a motion may still be held by the
constraints (the spring's ends connected to masses), and then the saddle-point system is
regular (:math:`S` is definite on the null space of :math:`A`).  Its solution does not change
when :math:`S` is replaced by the augmented

.. math::  S_a = S + A^T D A , \qquad D = \operatorname{diag}(d_i) \ge 0 ,

since on :math:`A a = c` the term adds :math:`A^T D (A a - c) = 0` to the first row once its
right-hand side :math:`A^T D c` is moved into the multipliers
(:math:`\lambda_a = \lambda - D c`): the accelerations, displacements and velocities of every
step are the same, and :math:`S_a` is definite exactly when the saddle-point system is regular.
:func:`effective_solver` keeps :math:`S` where it is definite (the usual case, bit for bit
what it was) and takes :math:`S_a` where :math:`S` is singular to round-off
(:func:`substruct.linalg.definite.numerically_singular`), with :math:`d_i` the largest diagonal
entry of :math:`S` on the coordinates of row ``i`` (rows equilibrated), so that :math:`S_a` has
the scale of :math:`S`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from substruct.analysis.errors import AnalysisInputError
from substruct.analysis.transient.base import Motion
from substruct.analysis.transient.integrators import Correction
from substruct.linalg.constraints import independent_rows, pinv_sym
from substruct.linalg.definite import numerically_singular
from substruct.linalg.factorize import Solve, factorizer
from substruct.linalg.scaling import mass_column_scale

__all__ = ["EffectiveSolve", "spd_solver", "effective_solver", "augmentation",
           "constraint_correction"]


def spd_solver(S: sp.sparray | np.ndarray, kind: str) -> Solve:
    """A solve with the symmetric positive definite ``S``: an explicit inverse if small and
    dense, else the registry's factorization ``kind`` (SuperLU if CHOLMOD refuses it).

    Raises:
        numpy.linalg.LinAlgError: a dense ``S`` exactly singular.
    """
    if isinstance(S, np.ndarray):
        inv = np.linalg.inv(S)
        return lambda r: inv @ r
    try:
        return factorizer(kind, spd=True)(sp.csc_array(S))
    except Exception:  # CHOLMOD: not positive definite to its test; SuperLU pivots instead
        return factorizer("superlu", spd=False)(sp.csc_array(S))


def _regular_solver(S: sp.sparray | np.ndarray, kind: str) -> Solve | None:
    """:func:`spd_solver` of ``S``, or ``None`` if ``S`` is singular to round-off."""
    try:
        solve = spd_solver(S, kind)
    except (np.linalg.LinAlgError, RuntimeError):
        return None
    return None if numerically_singular(sp.csr_array(S), solve) else solve


def augmentation(S: sp.sparray | np.ndarray, A: sp.csr_array) -> sp.sparray | np.ndarray:
    r""":math:`S_a = S + A^T D A` (module docstring), ``A`` with equilibrated rows:
    :math:`d_i = \max_{j:\, A_{ij} \ne 0} S_{jj}`, or :math:`\max_j S_{jj}` for a row whose
    coordinates all have :math:`S_{jj} = 0`.  Dense if ``S`` is."""
    diag = np.abs(np.asarray(S.diagonal(), dtype=float))
    top = float(diag.max(initial=0.0)) or 1.0
    pattern = sp.csr_array(A, copy=True)
    pattern.data = np.ones_like(pattern.data)
    d = np.asarray((pattern @ sp.diags_array(diag)).max(axis=1).toarray()).ravel()
    d = np.where(d > 0.0, d, top)
    extra = sp.csr_array(A.T @ sp.diags_array(d) @ A)
    if isinstance(S, np.ndarray):
        return S + extra.toarray()
    return sp.csr_array(S + extra)


@dataclass(frozen=True)
class EffectiveSolve:
    """The matrix the generalized-inverse step solves with (``S`` or the augmented ``S_a``),
    its solve, and whether it was augmented."""

    S: sp.sparray | np.ndarray
    solve: Solve
    augmented: bool


def effective_solver(S: sp.sparray | np.ndarray, A: sp.csr_array, kind: str) -> EffectiveSolve:
    r"""The solve of the generalized-inverse step: with ``S`` if it is definite, else with
    :math:`S_a = S + A^T D A` (:func:`augmentation`), which gives the same constrained step.

    Raises:
        AnalysisInputError: :math:`S_a` is singular too: a motion with neither mass, damping
            nor stiffness that no constraint holds.
    """
    solve = _regular_solver(S, kind)
    if solve is not None:
        return EffectiveSolve(S, solve, False)
    Sa = augmentation(S, A) if A.shape[0] else S
    solve = _regular_solver(Sa, kind) if A.shape[0] else None
    if solve is None:
        raise AnalysisInputError("a motion with neither mass, damping nor stiffness that no "
                                 "constraint holds (a massless coordinate held by nothing)")
    return EffectiveSolve(Sa, solve, True)


def constraint_correction(S: sp.sparray | np.ndarray, solve: Solve, A: sp.csr_array,
                          b: np.ndarray, motion: Motion | None = None) -> Correction:
    r"""The gain :math:`S^{-1} A^T (A S^{-1} A^T)^+` (``A`` equilibrated), its rank decided on
    ``A`` with the columns scaled by ``S``
    (:func:`substruct.linalg.constraints.independent_rows`); ``S`` and ``solve`` those of
    :func:`effective_solver` (augmented or not, the same projection onto :math:`A a = c`).
    Rows of rank ``n`` hold every coordinate: the correction is then the prescribed motion
    itself (``Correction.held``)."""
    At = sp.csr_array(A.T).toarray()
    Y = np.asarray(solve(At)).reshape(At.shape)
    rank = independent_rows(A, col_scale=mass_column_scale(sp.csr_array(S))).rank
    return Correction(A=A, b=b, gain=Y @ pinv_sym(At.T @ Y, rank),
                      e=None if motion is None else motion.e,
                      g=None if motion is None else motion.g, held=rank == A.shape[1])
