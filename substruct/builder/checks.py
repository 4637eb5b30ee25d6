"""Checks of an assembled case that name the field of the case file: connections that join
nothing, springs with a free end, nonhomogeneous constraints that cannot hold."""

from __future__ import annotations

import sys
from typing import Sequence

import numpy as np
import scipy.sparse as sp

from substruct.assembly.stack import Assembly, PointRef
from substruct.builder.points import point_uses
from substruct.case.loader import Case, parse_point
from substruct.case.substructures import SpringSpec
from substruct.linalg.constraints import independent_rows
from substruct.linalg.scaling import row_scale
from substruct.substructure import Substructure

__all__ = ["check_connection_row", "warn_free_springs", "check_connections_consistent"]

#: Largest constraint matrix (entries) whose consistency is checked densely before computing.
CONSISTENCY_LIMIT = 5_000_000


def check_connection_row(case: Case, by_name: dict[str, Substructure], a: PointRef,
                          b: PointRef, loc: tuple[int, int], chain: Sequence[str]) -> None:
    r"""Refuse a connection whose row ``r_a - r_b`` of ``A`` (eq 24) is empty.

    That is the same point twice (``[rod@0.5, rod@L/2]``) or two supported points: the
    "connection" joins nothing, which is a slip, and a user constraint with an empty row is
    refused likewise (:func:`substruct.assembly.stack.assemble`).
    """
    ra = sp.csr_array(by_name[a.substructure].row(a.where))
    rb = sp.csr_array(by_name[b.substructure].row(b.where))
    same = a.substructure == b.substructure
    moves = ra.count_nonzero() > 0
    empty = (ra - rb).count_nonzero() == 0 if same else not (moves or rb.count_nonzero())
    if empty:
        i, j = loc
        what = "the same coordinate" if same and moves else "supported (they cannot move)"
        raise case.error(("connections", i, j), f"connects nothing: {chain[j - 1]} and "
                         f"{chain[j]} are {what}, so u({chain[j - 1]}) = u({chain[j]}) is "
                         f"an empty row of A", chain[j])


def warn_free_springs(case: Case) -> None:
    """One line on stderr for each ``spring`` with an end that no connection or active
    constraint uses: the spring then carries no force (the solver sets its massless free end
    aside, an infinite root), which is almost always a modelling slip (not an error)."""
    used = set()
    for use in point_uses(case):
        if use.loc[0] in ("connections", "constraints"):
            sub, where = parse_point(use.text)
            used.add((sub, "i" if where is None else where))
    for k, spec in enumerate(case.substructures):
        if not isinstance(spec, SpringSpec):
            continue
        free = [p for p in spec.points() if (spec.name, p) not in used]
        if free:
            ends = " and ".join(f"{spec.name}@{p}" for p in free)
            what = "is" if len(free) == 1 else "are"
            hint = ", or ground: true for a spring to ground" if free == ["j"] else ""
            message = case.error(("substructures", k), f"spring {spec.name!r}: {ends} {what} "
                                 f"in no connection or constraint, so the spring carries no "
                                 f"force (connect {'it' if len(free) == 1 else 'them'}{hint})")
            sys.stderr.write(f"substruct: warning: {message}\n")


def check_connections_consistent(case: Case, asm: Assembly, n_connections: int) -> None:
    r"""Refuse nonhomogeneous constraints that cannot hold, before anything is computed.

    A row of ``A`` that is a combination ``W`` of independent rows must have the same
    combination of right-hand sides (``b`` and ``R``):

    .. math::  A_d = W A_k \;\Rightarrow\; b_d = W b_k,\; R_d = W R_k

    (the check :func:`substruct.linalg.constraints.check_connections_consistent` makes again when the receptances
    are computed; here it names the constraint in the case file).
    """
    A = asm.A
    m, N = A.shape
    if m == 0 or (asm.R.nnz == 0 and not np.any(asm.b)) or m * N > CONSISTENCY_LIMIT:
        return
    # decided on the equilibrated rows D A q = D b + D R F, whatever the scale of each row
    scale = row_scale(A, keep_zero=True)
    As = sp.csr_array(scale.apply(sp.csr_array(A)))
    rows = independent_rows(As)
    if rows.dropped.size == 0:
        return
    labels = list(asm.constraint_labels)
    d = np.ldexp(1.0, -scale.exponent)
    for field, rhs in (("rhs", asm.b.reshape(m, 1)), ("rhs_force", asm.R.toarray())):
        rs = scale.apply(np.asarray(rhs, dtype=float))
        size = max(float(np.abs(rs).max()), 1e-300)
        err = np.abs(rs[rows.dropped] - rows.combination @ rs[rows.keep]).max(axis=1) / size
        bad = np.flatnonzero(err > 1e-8)
        if bad.size:
            # the dependency  sum_r c_r (D A)_r = 0  whose right-hand sides do not cancel,
            # written on the rows of A themselves: sum_r (c_r d_r) A_r = 0
            cs = np.zeros(m)
            cs[rows.keep] = -rows.combination[bad[0]]
            cs[rows.dropped[bad[0]]] = 1.0
            involved = np.flatnonzero(np.abs(cs) > 1e-12 * np.abs(cs).max())
            c = cs * d
            # blame the last user constraint involved (connections have no right-hand side)
            t = int(max(involved, key=lambda r: (r >= n_connections, r)))
            _inconsistent(case, field, labels, n_connections, t,
                          {int(r): -c[r] / c[t] for r in involved if r != t},
                          float(np.abs(cs @ rs).max() / abs(cs[t]) / size))


def _inconsistent(case: Case, field: str, labels: list[str], n_connections: int, t: int,
                  combination: dict[int, float], diff: float) -> None:
    """Raise the :class:`CaseError` for row ``t = sum combination[r] row r`` of ``A``."""
    terms = sorted(combination.items(), key=lambda kv: -abs(kv[1]))
    combo = " + ".join(f"{w:.4g} x ({labels[r]})" for r, w in terms[:3])
    combo += " + ..." if len(terms) > 3 else ""
    problem = (f"inconsistent constraints: the left-hand side of {labels[t]!r} is {combo}, "
               f"but its {field} is not the same combination (differs by {diff:.3g}, "
               f"relative)")
    if t < n_connections:
        raise case.error(("constraints",), problem)
    con = [c for c in case.constraints if c.active][t - n_connections]
    k = case.constraints.index(con)
    raise case.error(("constraints", k, field), problem,
                     dict(con.rhs_force) if field == "rhs_force" else con.rhs)

