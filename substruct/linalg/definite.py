r"""Whether a factorized shifted pencil :math:`B = K - \sigma M` (:math:`\sigma \le 0`) is
numerically singular: a motion with neither mass nor stiffness.

:math:`K` and :math:`M` positive semidefinite and :math:`\sigma < 0` make :math:`B` positive
semidefinite, singular exactly when some :math:`z \ne 0` has :math:`K z = 0` and
:math:`M z = 0` (a massless coordinate or mechanism held by nothing: the torsion of a free bar
whose mass is lumped on its translations).  A factorization of such a :math:`B` need not fail:
SuperLU pivots on a round-off entry and its solves carry a multiple of :math:`z` set by that
round-off, which may enter the mode shapes unseen (:math:`z` changes neither
:math:`K u - \omega^2 M u` nor :math:`u^T M u`), and the motion itself has no eigenvalue
(:math:`0/0`): the dense solver and AMLS refuse such a model, and so must the sparse one.

Two steps of inverse iteration from a random vector, :math:`x = B^{-1} B^{-1} b`, turn
:math:`x` towards the eigenvector of :math:`B`'s smallest eigenvalue.  Its Rayleigh quotient
:math:`x^T B x` is then compared with the round-off of computing it,
:math:`\epsilon\, |x|^T |B|\, |x|`: a regular pencil leaves :math:`x^T B x` at least
:math:`|\sigma|\, x^T M x` (a free body's rigid motion: :math:`10^{-9}` of the stiffness's scale
with the default shift, :func:`substruct.analysis.modes.krylov.default_shift`), a singular one
at round-off, of either sign (measured: a free bar of CBARs with point masses only, -0.02
round-offs; Nastran's free-free shell cylinder, 1.5e3; the threshold is 10).  The test is the
one a dense Cholesky factorization makes (it fails where a pivot falls to round-off), with any
backend's solves, and free of units.
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.sparse as sp

from substruct.linalg.solve_type import Factorize, Solve

__all__ = ["SINGULAR_ROUNDOFF", "SingularPencil", "definite_factorization",
           "numerically_singular"]

#: ``x^T B x`` at or below this many round-offs ``eps |x|^T |B| |x|``: singular
SINGULAR_ROUNDOFF = 10.0


def numerically_singular(B: sp.sparray, solve: Solve, seed: int = 0) -> bool:
    r"""Whether the symmetric positive semidefinite ``B`` is singular to round-off.

    .. math::  x = B^{-1} B^{-1} b, \qquad
               x^T B x \le c\, \epsilon\, |x|^T |B|\, |x|, \quad c = 10
               \ (\text{:data:`SINGULAR_ROUNDOFF`}),

    ``b`` standard normal (``seed``), ``solve`` a factorization of ``B``.

    Args:
        B: sparse symmetric ``n x n`` (the shifted pencil :math:`K - \sigma M`).
        solve: ``f -> B^{-1} f``.
        seed: of the random start.
    """
    b = np.random.default_rng(seed).standard_normal(B.shape[0])
    x = np.asarray(solve(np.asarray(solve(b)).ravel())).ravel()
    if not np.all(np.isfinite(x)):
        return True
    x = x / max(np.abs(x).max(), 1e-300)
    energy = float(x @ (B @ x))
    roundoff = float(np.abs(x) @ (abs(B) @ np.abs(x)))
    return bool(energy <= SINGULAR_ROUNDOFF * np.finfo(float).eps * roundoff)


class SingularPencil(ValueError):
    """The shifted pencil is singular: a motion with neither mass nor stiffness."""


def definite_factorization(factorize: Factorize, B: sp.sparray) -> Solve:
    """``factorize(B)``, refused if ``B`` is singular (:func:`numerically_singular`).

    A backend that failed on the singular ``B`` before another took it (CHOLMOD's "not
    positive definite") warns only when ``B`` is regular: the refusal says all there is.

    Raises:
        SingularPencil: ``B`` singular to round-off, or exactly (SuperLU's zero pivot).
    """
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            solve = factorize(B)
        except RuntimeError as exc:
            if "singular" not in str(exc):
                raise
            raise SingularPencil(str(exc)) from exc
        if numerically_singular(B, solve):
            raise SingularPencil("the shifted pencil is singular to round-off")
    for w in caught:
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return solve
