r"""What the sparse eigensolvers share: checked inputs with equilibrated constraint rows, the shift,
the size of the Krylov basis, the shift-invert Lanczos call and the constraint residuals.

The sparse solvers (:mod:`substruct.analysis.modes.sparse`, :mod:`substruct.analysis.modes.damped`)
work on the coordinates the constraints leave free.  Their Krylov basis must fit in that space:
ARPACK fails ("error -9999") when asked for a basis larger than the invariant subspace the
operator spans, which is

.. math::  n_{free} = n - \operatorname{rank}(A) - \dim(\operatorname{null}(M) \cap
           \operatorname{null}(A))

for the undamped pencils (the massless directions that the constraints leave free carry
infinite roots, outside the reach of the shift-invert operator: a massless coordinate, or a
combination of coordinates without mass such as the rotations of a node carrying a point mass
off it without rotary inertia) and twice that for the first-order pencils of damped models.  :func:`krylov_size` caps the basis by it.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from substruct.analysis.errors import AnalysisInputError
from substruct.linalg.massless import massless_count
from substruct.linalg.nullspace import Elimination, master_slave
from substruct.linalg.scaling import (
    equilibrate,
    mass_column_scale,
    massless_coordinates,
    rigid_eigenvalue,
    spectral_norm,
    stiffness_over_mass,
)

__all__ = [
    "KRYLOV_MIN",
    "check_inputs",
    "constraint_residuals",
    "default_shift",
    "eliminate",
    "free_coordinates",
    "krylov_size",
    "rigid_eigenvalue",
    "stiffness_over_mass",
]

#: Smallest Krylov basis ARPACK builds by default (``max(2 k + 1, 20)`` for ``k`` roots).
KRYLOV_MIN = 20


def check_inputs(M: sp.sparray | np.ndarray, K: sp.sparray | np.ndarray,
                 A: sp.sparray | np.ndarray | None, n_modes: int
                 ) -> tuple[sp.csr_array, sp.csr_array, sp.csr_array, int]:
    r"""``(M, K, D A, k)``: CSR copies of the matrices, checked for shape, the constraint rows
    equilibrated (:func:`substruct.linalg.scaling.equilibrate`: ``D A u = 0`` has the solutions of
    ``A u = 0``, whatever the scale of a row), and the number of modes.

    Raises:
        ValueError: shapes that do not match, ``n_modes < 1``, a constraint row that is exactly
            zero (:class:`substruct.linalg.scaling.ZeroRowError`).
    """
    Kc = sp.csr_array(K, dtype=float)
    n = Kc.shape[0]
    Mc = sp.csr_array(M, dtype=float)
    if Mc.shape != (n, n):
        raise ValueError(f"M has shape {Mc.shape}, K has {Kc.shape}")
    Ac = sp.csr_array((0, n)) if A is None else sp.csr_array(A, dtype=float)
    if Ac.shape[1] != n:
        raise ValueError(f"A has {Ac.shape[1]} columns for {n} coordinates")
    Ac.eliminate_zeros()
    if Ac.shape[0]:
        Ac = sp.csr_array(equilibrate(Ac).A)
    k = int(n_modes)
    if k < 1:
        raise ValueError(f"n_modes must be >= 1, got {n_modes!r}")
    return Mc, Kc, Ac, k


def default_shift(K: sp.sparray, M: sp.sparray) -> float:
    r"""A small negative shift, :math:`-10^{-9} \operatorname{tr} K / \operatorname{tr} M`,
    so that ``K - sigma M`` is definite even with rigid-body modes."""
    return -1e-9 * stiffness_over_mass(K, M)


def eliminate(M: sp.sparray, A: sp.sparray) -> Elimination:
    """Master-slave elimination of ``A`` (:func:`substruct.linalg.nullspace.master_slave`):
    massless coordinates preferred as slaves, the rank decided on mass-scaled columns."""
    return master_slave(A, prefer=massless_coordinates(M), col_scale=mass_column_scale(M))


def free_coordinates(el: Elimination, M: sp.sparray) -> int:
    r""":math:`n - \operatorname{rank}(A)` less the massless directions of the reduced mass
    :math:`T^T M T` (:func:`substruct.linalg.massless.massless_count`): the dimension of the
    space the shift-invert operator of the undamped pencil spans."""
    T = sp.csc_array(el.T)
    return int(T.shape[1] - massless_count(sp.csr_array(T.T @ (sp.csr_array(M) @ T))))


#: A null-space pencil (``n - rank(A)`` coordinates) too small for a Krylov basis around the
#: roots asked for is solved densely up to this size (a 698-coordinate model whose rigid
#: elements leave 2 free coordinates: 0.1 s, where the dense generalized-inverse state space
#: of all 698 took 25 s).
DENSE_FREE = 3000


def krylov_size(k: int, free: int, ncv: int | None = None, *, margin: int = 1) -> int:
    r"""The Krylov basis for ``k`` roots in a space of dimension ``free``.

    .. math::  n_{cv} = \min(\text{ncv} \text{ or } \max(2k + 1, 20),\; n_{free} - 1),
               \qquad k + \text{margin} \le n_{cv}

    (``margin`` 1 for Lanczos, ``eigsh``; 2 for Arnoldi, ``eigs``).  One vector less than the
    space keeps ARPACK from running into an invariant subspace it cannot extend.

    Raises:
        ValueError: the space is too small for ``k`` roots and a basis around them (use the dense
            solver).
    """
    want = max(2 * k + 1, KRYLOV_MIN) if ncv is None else int(ncv)
    size = min(want, free - 1)
    if size < k + margin:
        raise AnalysisInputError(f"{k} modes asked of a constrained model with {free} free coordinates "
                         f"(n - rank(A)): too few for a Krylov basis (use the dense "
                         f"coupled_modes)")
    return size


def constraint_residuals(A: sp.sparray, U: np.ndarray) -> np.ndarray:
    r"""``|A u| / (|A|_2 |u|)`` for each column ``u`` of ``U`` (zeros when there is no row)."""
    if not A.shape[0] or not U.shape[1]:
        return np.zeros(U.shape[1])
    return np.linalg.norm(A @ U, axis=0) / (spectral_norm(A) * np.linalg.norm(U, axis=0))
