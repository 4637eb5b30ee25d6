r"""The one input of every analysis: a constrained linear system, converted and equilibrated once.

.. math::  M \ddot q + C \dot q + K q = F, \qquad A q = b + R F

(the paper's eqs 1-2 with the force-tied right-hand side of eq 14).  :meth:`ConstrainedSystem.of`
takes matrices in any form (dense, scipy.sparse, ``None`` for an absent ``C``, ``A`` or ``R``),
converts them to CSR once and scales the constraint rows once, by powers of two to a 2-norm
within ``[2^-1/2, 2^1/2]``, ``D A q = D b + D R F`` (:func:`substruct.linalg.scaling.equilibrate`): the same constraint, its rank and
consistency decided whatever the scale of a row.  The analyses then take the system as it is.

The type lives in :mod:`substruct.linalg`, below the assembly, so that an
:class:`~substruct.assembly.stack.Assembly` can hand out its own (``Assembly.system``) and the
analyses can take it, the layers going down only.

Examples
--------
Two unit masses on springs of 2 and 1, the second held by ``2^-20 q_2 = 0`` (the row scaled by
``2^20``):

>>> import numpy as np
>>> from substruct.linalg.system import ConstrainedSystem
>>> s = ConstrainedSystem.of(np.eye(2), None, [[3.0, -1.0], [-1.0, 1.0]], [[0.0, 2.0**-20]])
>>> s.n, s.m, s.C is None
(2, 1, True)
>>> s.A.toarray()
array([[0., 1.]])
>>> s.constraint_labels
('1',)
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Sequence, TypeAlias

import numpy as np
import scipy.sparse as sp

from substruct.linalg.constraints import IndependentRows, independent_rows
from substruct.linalg.scaling import equilibrate, mass_column_scale
from substruct.linalg.solve_type import Matrix

__all__ = ["ConstrainedSystem"]

#: A matrix as the analyses accept it: dense or scipy.sparse.


def _square(name: str, X: Matrix, n: int | None) -> sp.csr_array:
    Xs = sp.csr_array(X, dtype=float)
    size = Xs.shape[0] if n is None else n
    if Xs.shape != (size, size):
        raise ValueError(f"{name} must be {size} x {size}, got {Xs.shape[0]} x {Xs.shape[1]}")
    return Xs


def _empty(X: Matrix | None) -> bool:
    return X is None or np.size(X) == 0 if not sp.issparse(X) else \
        X.shape[0] * X.shape[1] == 0  # type: ignore[union-attr]


@dataclass(frozen=True, eq=False)
class ConstrainedSystem:
    r"""``M q'' + C q' + K q = F`` under ``A q = b + R F``, CSR, constraint rows equilibrated.

    Build it with :meth:`of` (or ``Assembly.system``), not directly.

    Attributes:
        M, K: ``n x n`` CSR (``M`` may have massless rows, eq 6).
        C: ``n x n`` CSR, or ``None`` for an undamped system.
        A: ``m x n`` CSR, rows equilibrated (2-norms within ``[2^-1/2, 2^1/2]``; ``m`` may be 0).
        b: ``m`` right-hand sides, scaled with the rows.
        R: ``m x n`` CSR force ties scaled with the rows, or ``None`` when no row is tied to the
            force (``A q = b``).
        row_scale: the factors ``d_i`` (powers of two) the rows were multiplied by (``D A`` is :attr:`A`).
        coordinate_labels: one name per coordinate (``"1"``, ... if none were given).
        constraint_labels: one name per constraint row (``"1"``, ... if none were given).
    """

    M: sp.csr_array
    C: sp.csr_array | None
    K: sp.csr_array
    A: sp.csr_array
    b: np.ndarray
    R: sp.csr_array | None
    row_scale: np.ndarray
    coordinate_labels: tuple[str, ...]
    constraint_labels: tuple[str, ...]

    @classmethod
    def of(cls, M: Matrix, C: Matrix | None, K: Matrix, A: Matrix | None = None,
           b: Sequence[float] | np.ndarray | None = None, R: Matrix | None = None, *,
           coordinate_labels: Sequence[str] | None = None,
           constraint_labels: Sequence[str] | None = None) -> ConstrainedSystem:
        r"""The system of these matrices: CSR once, the rows of ``A q = b + R F`` scaled
        together once (powers of two, 2-norms near 1), ``D A q = D b + D R F``.

        Args:
            M, C, K: ``n x n`` (``C`` ``None`` for none).
            A: ``m x n`` constraint rows of any rank (``None`` or empty for none).
            b: ``m`` right-hand sides (zeros if ``None``).
            R: ``m x n`` force ties (``None``, or all zero, for ``A q = b``).
            coordinate_labels, constraint_labels: names (``"1"``, ``"2"``, ... by default).

        Raises:
            ValueError: shapes that do not fit; labels of the wrong count.
            substruct.linalg.scaling.ZeroRowError: a constraint row that is exactly zero.

        Examples
        --------
        >>> import numpy as np
        >>> from substruct.linalg.system import ConstrainedSystem
        >>> s = ConstrainedSystem.of(np.eye(3), None, 2 * np.eye(3), [[2.0, -2.0, 0.0]],
        ...                          constraint_labels=["tie"])
        >>> s.A.toarray()
        array([[ 0.5, -0.5,  0. ]])
        >>> s.row_scale, s.R is None, s.b
        (array([0.25]), True, array([0.]))
        """
        Ms = _square("M", M, None)
        n = Ms.shape[0]
        Ks = _square("K", K, n)
        Cs = None if C is None else _square("C", C, n)
        As = sp.csr_array((0, n)) if _empty(A) else sp.csr_array(A, dtype=float)
        if As.shape[1] != n:
            As = As.reshape(-1, n) if As.shape[0] * As.shape[1] % n == 0 else As
        if As.shape[1] != n:
            raise ValueError(f"A must have {n} columns, got {As.shape[1]}")
        As.eliminate_zeros()
        m = As.shape[0]
        bs = np.zeros(m) if b is None else np.asarray(b, dtype=float).reshape(-1)
        if bs.shape != (m,):
            raise ValueError(f"b must have {m} entries, got {bs.size}")
        Rs = None if _empty(R) else sp.csr_array(R, dtype=float)
        if Rs is not None and Rs.shape != (m, n):
            raise ValueError(f"R must be {m} x {n}, got {Rs.shape[0]} x {Rs.shape[1]}")
        if Rs is not None and not np.any(Rs.data != 0):
            Rs = None
        rows = _labels("constraint", constraint_labels, m)
        scale = np.ones(m)
        if m:
            eq = equilibrate(As, bs, Rs, labels=rows)
            As = sp.csr_array(eq.A)
            bs = np.asarray(eq.b, dtype=float)
            Rs = None if eq.R is None else sp.csr_array(eq.R)
            scale = np.ldexp(1.0, -np.asarray(eq.scale.exponent))
        return cls(M=Ms, C=Cs, K=Ks, A=As, b=bs, R=Rs, row_scale=scale,
                   coordinate_labels=_labels("coordinate", coordinate_labels, n),
                   constraint_labels=rows)

    @property
    def n(self) -> int:
        """Number of coordinates."""
        return int(self.K.shape[0])

    @property
    def m(self) -> int:
        """Number of constraint rows (of any rank)."""
        return int(self.A.shape[0])

    @property
    def damped(self) -> bool:
        """Whether ``C`` has a nonzero entry."""
        return self.C is not None and bool(np.any(self.C.data != 0))

    @cached_property
    def independent(self) -> IndependentRows:
        """``rank(A)`` independent rows of :attr:`A`, rank decided on mass-scaled columns
        (:func:`substruct.linalg.constraints.independent_rows`), computed once."""
        return independent_rows(self.A, col_scale=mass_column_scale(self.M))

    def with_rows(self, A: Matrix | None,
                  constraint_labels: Sequence[str] | None = None) -> ConstrainedSystem:
        """The same ``M``, ``C``, ``K`` under other constraint rows ``A q = 0`` (a variant of
        a model with some rows left out)."""
        return ConstrainedSystem.of(self.M, self.C, self.K, A,
                                    coordinate_labels=self.coordinate_labels,
                                    constraint_labels=constraint_labels)


def _labels(kind: str, labels: Sequence[str] | None, count: int) -> tuple[str, ...]:
    if labels is None:
        return tuple(str(i + 1) for i in range(count))
    out = tuple(map(str, labels))
    if len(out) != count:
        raise ValueError(f"{count} {kind} labels needed, got {len(out)}")
    return out
