r"""Stacking substructures and building the constraint matrix (paper eqs 23-27, 52-53).

The assembled, unconstrained system is block diagonal (eq 23),

.. math::  M^c = \operatorname{diag}(M_1, \dots, M_s), \quad
           C^c = \operatorname{diag}(C_1, \dots), \quad K^c = \operatorname{diag}(K_1, \dots),

over the stacked coordinates ``u = [q_1; ...; q_s]``.  Every compatibility condition "point ``p``
of ``S`` moves with point ``p'`` of ``T``" (eq 24) and every user constraint
``sum_k c_k u(p_k) = rhs`` (eq 52) is one row of ``A`` (eqs 25-26, 53), made of the substructures'
point rows ``u(p) = r(p) @ q``.  The right-hand side may be a constant ``b`` or tied to the force,
``A u = R F`` (eq 14, read at displacement level).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np
import scipy.sparse as sp

from substruct.linalg.constraints import ConstraintError
from substruct.linalg.system import ConstrainedSystem
from substruct.substructure import PointError, Substructure

__all__ = ["PointRef", "Connection", "LinearConstraint", "Assembly", "assemble"]


@dataclass(frozen=True)
class PointRef:
    """A point of a named substructure: ``where`` is what its locator understands."""

    substructure: str
    where: Any

    def __str__(self) -> str:
        return f"{self.substructure}@{self.where}"


@dataclass(frozen=True)
class Connection:
    """Compatibility ``u(a) = u(b)`` (eq 24): one row ``r_a - r_b`` of ``A``."""

    a: PointRef
    b: PointRef
    name: str = ""


@dataclass(frozen=True)
class LinearConstraint:
    r"""A user constraint ``sum_k c_k u(p_k) = rhs + sum_j d_j F(p_j)`` (eqs 41, 52).

    Attributes:
        terms: ``(point, coefficient)`` pairs of the left-hand side.
        rhs: constant right-hand side (enters ``b``).
        force_terms: ``(point, coefficient)`` pairs tying the right-hand side to the applied
            force (enter ``R``: the generalized force of a unit load at ``p_j`` is ``r(p_j)^T``).
        name: label used in outputs and error messages.
    """

    terms: tuple[tuple[PointRef, float], ...]
    rhs: float = 0.0
    force_terms: tuple[tuple[PointRef, float], ...] = ()
    name: str = ""


@dataclass
class Assembly:
    """The stacked system and its constraints.

    Attributes:
        substructures: in stacking order.
        offsets: ``offsets[i]`` is the first stacked coordinate of substructure ``i``
            (``offsets[-1]`` is the total).
        M, C, K: block-diagonal sparse matrices (eq 23).
        A: sparse ``m x N`` constraint matrix (eqs 25-26, 53).
        b: constant right-hand sides (``m``).
        R: sparse ``m x N``, the force-tied right-hand sides (``A u = b + R F``).
        constraint_labels: one per row of ``A``.
        dof_labels: ``"<substructure>.<label>"`` per stacked coordinate.
    """

    substructures: list[Substructure]
    offsets: np.ndarray
    M: sp.csr_array
    C: sp.csr_array
    K: sp.csr_array
    A: sp.csr_array
    b: np.ndarray
    R: sp.csr_array
    constraint_labels: list[str]
    dof_labels: list[str] = field(default_factory=list)

    @property
    def system(self) -> ConstrainedSystem:
        """The stacked system with all its constraints, as every analysis takes it
        (:class:`~substruct.linalg.system.ConstrainedSystem`: CSR, rows equilibrated)."""
        return ConstrainedSystem.of(self.M, self.C, self.K, self.A, self.b, self.R,
                                    coordinate_labels=self.dof_labels or None,
                                    constraint_labels=self.constraint_labels)

    @property
    def n_dof(self) -> int:
        """Total number of stacked coordinates ``N``."""
        return int(self.offsets[-1])

    def index(self, name: str) -> int:
        """Position of the substructure called ``name``."""
        for i, sub in enumerate(self.substructures):
            if sub.name == name:
                return i
        raise PointError(f"unknown substructure {name!r}; known: "
                         + ", ".join(s.name for s in self.substructures))

    def block(self, name: str) -> slice:
        """Stacked coordinates of substructure ``name``."""
        i = self.index(name)
        return slice(int(self.offsets[i]), int(self.offsets[i + 1]))

    def row(self, point: PointRef) -> sp.csr_array:
        """``1 x N`` row giving the displacement of ``point`` from the stacked coordinates."""
        return self.rows([point])

    def rows(self, points: Sequence[PointRef]) -> sp.csr_array:
        """Stacked rows of several points (``k x N``), built in one piece from the local rows
        (hundreds of inputs and outputs of a sweep)."""
        if not points:
            return sp.csr_array((0, self.n_dof))
        data, cols, counts = [], [], []
        for p in points:
            i = self.index(p.substructure)
            local = self.substructures[i].row(p.where)
            data.append(local.data)
            cols.append(local.indices + self.offsets[i])
            counts.append(local.nnz)
        indptr = np.concatenate([[0], np.cumsum(counts)])
        return sp.csr_array((np.concatenate(data), np.concatenate(cols), indptr),
                            shape=(len(points), self.n_dof))


def assemble(substructures: Sequence[Substructure], connections: Sequence[Connection] = (),
             constraints: Sequence[LinearConstraint] = ()) -> Assembly:
    r"""Stack substructures (eq 23) and build ``A``, ``b``, ``R`` (eqs 24-27, 52-53).

    Rows come in order: connections first, then user constraints.

    Raises:
        ConstraintError: a constraint with no term, or whose terms cancel (an empty row).
        PointError: a point no substructure has.
    """
    names = [s.name for s in substructures]
    dupes = sorted({n for n in names if names.count(n) > 1})
    if dupes:
        raise ValueError(f"duplicate substructure name {dupes[0]!r}")
    sizes = [s.n_dof for s in substructures]
    offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(int)
    M = sp.csr_array(sp.block_diag([s.M for s in substructures], format="csr"))
    C = sp.csr_array(sp.block_diag([s.C for s in substructures], format="csr"))
    K = sp.csr_array(sp.block_diag([s.K for s in substructures], format="csr"))
    labels = [f"{s.name}.{lab}" for s in substructures for lab in s.dof_labels]
    asm = Assembly(list(substructures), offsets, M, C, K,
                   sp.csr_array((0, offsets[-1])), np.zeros(0), sp.csr_array((0, offsets[-1])),
                   [], labels)
    a_rows, r_rows, b, row_labels = [], [], [], []
    N = asm.n_dof
    for k, con in enumerate(connections):
        a_rows.append(asm.row(con.a) - asm.row(con.b))
        r_rows.append(sp.csr_array((1, N)))
        b.append(0.0)
        row_labels.append(con.name or f"connection {k + 1}: {con.a} = {con.b}")
    for k, lc in enumerate(constraints):
        label = lc.name or f"constraint {k + 1}"
        if not lc.terms:
            raise ConstraintError(f"{label}: a constraint needs at least one term")
        row = sp.csr_array((1, N))
        for point, coef in lc.terms:
            row = row + float(coef) * asm.row(point)
        if row.count_nonzero() == 0 or abs(row).max() == 0:
            raise ConstraintError(f"{label}: its terms cancel or reference nothing (an empty "
                                  "row)")
        rrow = sp.csr_array((1, N))
        for point, coef in lc.force_terms:
            rrow = rrow + float(coef) * asm.row(point)
        a_rows.append(row)
        r_rows.append(rrow)
        b.append(float(lc.rhs))
        row_labels.append(label)
    if a_rows:
        asm.A = sp.csr_array(sp.vstack(a_rows))
        asm.A.eliminate_zeros()
        asm.R = sp.csr_array(sp.vstack(r_rows))
    asm.b = np.asarray(b, dtype=float)
    asm.constraint_labels = row_labels
    return asm
