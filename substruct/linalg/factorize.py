r"""The sparse factorizations, in one registry: ``factorizer(kind)(A)`` is a solve ``b -> A^{-1} b``.

Every shift-invert eigensolve, static condensation and frequency sweep of the package gets its
factorization here, never from ``eigsh(sigma=...)`` itself (``eigsh``'s own factorization of
95k coordinates took 279 s and 5.5 GB).  The backends and the automatic choice among them are
in :mod:`substruct.linalg.backends`; the names accepted here:

===================  =========================================================================
kind                 matrices and method
===================  =========================================================================
``"auto"``           the fastest backend installed (:data:`~substruct.linalg.backends.\
AUTO_ORDER`) for SPD matrices (``spd=True``) or any square matrix, with fallback
``"pardiso"``        PARDISO (oneMKL, ``pypardiso`` wheels): Cholesky for SPD, else ``L U``
``"cholmod"``        SPD only: CHOLMOD supernodal Cholesky (scikit-sparse)
``"superlu-metis"``  SPD only: SuperLU in symmetric mode after a METIS nested dissection
``"superlu"``        SPD: SuperLU in symmetric mode (``MMD_AT_PLUS_A``, diagonal pivots);
                     otherwise partial pivoting, same ordering
``"saddle"``         symmetric indefinite saddle points ``[B, A^T; A, 0]`` (KKT): the fastest
                     backend for symmetric indefinite matrices, with fallback
``"complex-lu"``     any square matrix, real or complex (the impedances of frequency sweeps
                     and the bordered systems on them): the fastest backend, with fallback
===================  =========================================================================

:func:`complex_symmetric` and :func:`fill_ordering` serve the frequency sweeps: PARDISO where
it is installed, else SuperLU in one ordering for every frequency (:mod:`substruct.linalg.superlu`).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from substruct.linalg.backends import auto_factorizer, backend_factorizer
from substruct.linalg.cholmod import cholmod, has_cholmod
from substruct.linalg.pardiso import pardiso_available as has_pardiso
from substruct.linalg.solve_type import Factorize, Solve
from substruct.linalg.superlu import superlu_complex_symmetric
from substruct.linalg.superlu import (
    complex_lu,
    fill_ordering,
    superlu,
    superlu_saddle,
    superlu_spd,
)

__all__ = [
    "FACTORIZATIONS",
    "KINDS",
    "Factorize",
    "Solve",
    "cholmod",
    "complex_lu",
    "complex_symmetric",
    "factorizer",
    "fill_ordering",
    "has_cholmod",
    "has_pardiso",
    "superlu",
    "superlu_saddle",
    "superlu_spd",
]

#: The factorizations of symmetric positive definite matrices a user may choose by name.
FACTORIZATIONS = ("superlu", "cholmod", "pardiso", "superlu-metis", "auto")
#: Every name :func:`factorizer` accepts.
KINDS = FACTORIZATIONS + ("saddle", "complex-lu")


def factorizer(kind: str | Factorize = "auto", spd: bool = True) -> Factorize:
    """A factorization ``A -> (b -> A^{-1} b)`` by name, or the callable given.

    Args:
        kind: one of :data:`KINDS` (see the module docstring) or a callable.
        spd: for the names of :data:`FACTORIZATIONS`: whether the matrices will be symmetric
            positive definite (CHOLMOD needs it; SuperLU then pivots on the diagonal,
            PARDISO factorizes by Cholesky).

    Raises:
        ValueError: an unknown name; ``"cholmod"`` or ``"superlu-metis"`` for a matrix that
            is not SPD; a backend named that is not installed.
    """
    if callable(kind):
        return kind
    if kind == "superlu":
        return superlu_spd if spd else superlu
    if kind in ("cholmod", "superlu-metis") and not spd:
        raise ValueError(f"factorization {kind!r} needs a symmetric positive definite "
                         f"matrix; the saddle-point (KKT) systems need 'saddle'")
    if kind == "cholmod":
        if not has_cholmod():
            raise ValueError("factorization 'cholmod' needs scikit-sparse (make fast: "
                             "libsuitesparse-dev, then pip install scikit-sparse)")
        return cholmod
    if kind in ("pardiso", "superlu-metis"):
        return backend_factorizer(kind, "spd" if spd else "general")
    if kind == "auto":
        return auto_factorizer("spd" if spd else "general")
    if kind == "saddle":
        return auto_factorizer("symmetric")
    if kind == "complex-lu":
        return auto_factorizer("general")
    raise ValueError(f"unknown factorization {kind!r}; expected one of "
                     f"{', '.join(FACTORIZATIONS)} or a callable")


def complex_symmetric(A: sp.sparray | sp.spmatrix, order: np.ndarray | None = None, *,
                      ordered: bool = False) -> Solve:
    r"""A factorization of the complex symmetric impedance :math:`Z = K - \omega^2 M + i \omega C`
    of a frequency sweep: PARDISO (``mtype`` 6, its own nested-dissection ordering) where it
    is installed and succeeds, else SuperLU in the symmetric ordering ``order``
    (:func:`substruct.linalg.superlu.superlu_complex_symmetric`; ``ordered``: ``A`` is in it already).
    """
    def own(B: sp.sparray) -> Solve:
        return superlu_complex_symmetric(B, order, ordered=ordered)

    return auto_factorizer("complex-symmetric", superlu=own)(sp.csc_array(A))
