r"""Case-file Craig-Bampton with interface reduction (``reduce: {method: craig-bampton,
modes: g, interface_degree: p}``).

Each interface of the solid (an ``interfaces:`` item that ties it, or a ``reduce.interface``
selector) becomes one :class:`~substruct.models.interface_basis.InterfaceBasis` of degree
``p``; the other boundary coordinates (points of connections, constraints and FRF outputs on
the solid) stay physical (``R = I``), and the solid is reduced by
:func:`~substruct.models.interface_reduction.reduce_part`.  The ties of the case stay node
to node rows; on the reduced solids they read
:math:`R_a(x_k)\, \xi_a - R_b(x_k)\, \xi_b = 0` for every node and component, ``3 N``
rows of rank ``r`` (both bases span the same fields), which the constraint handling reduces
to the ``r`` independent ones: the same coupling as shared interface coordinates (the
reference of the tests, ``tests/reference_reduced_coupling.py``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from substruct.case.solids import SolidReduce
from substruct.models.interface_basis import InterfaceBasis, interface_basis_of_dofs
from substruct.models.interface_reduction import reduce_part
from substruct.substructure import Substructure

__all__ = ["interface_reduced"]


def interface_reduced(case: Any, loc: tuple[Any, ...], reduce: SolidReduce,
                       sub: Substructure, cols: set[int], faces: list[tuple[str, set[int]]]
                       ) -> Substructure:
    r"""Craig-Bampton of ``sub`` with each interface reduced to polynomial fields of degree
    ``reduce.interface_degree`` (module docstring).

    Args:
        case: the case (for its one-line errors).
        loc: the location of the solid's ``reduce`` field.
        reduce: the reduction (``method: craig-bampton`` with ``interface_degree``).
        sub: the unreduced solid.
        cols: every boundary coordinate (interfaces and points used on the solid).
        faces: ``(label, coordinates)`` of each interface, disjoint.

    Returns:
        The reduced solid, :math:`T = [\Phi, \Psi; 0, R_b]`, coordinates ``eta1 .. eta<g>``,
        ``<interface>.xi<j>`` and the labels of the points kept physical.
    """

    field = (*loc, "interface_degree")
    bases: list[InterfaceBasis] = []
    taken: set[int] = set()
    for label, dofs in faces:
        if not dofs:
            continue
        if dofs & taken:
            raise case.error(field, f"the interfaces of {sub.name!r} share nodes; an interface "
                             "basis needs disjoint interfaces", reduce.interface_degree)
        taken |= dofs
        try:
            bases.append(interface_basis_of_dofs(sub, label, np.array(sorted(dofs)),
                                                 reduce.interface_degree))
        except ValueError as err:
            raise case.error(field, " ".join(str(err).split()),
                             reduce.interface_degree) from None
    rest = np.array(sorted(cols - taken), dtype=np.int64)
    if rest.size:
        bases.append(InterfaceBasis(name="points", xyz=np.zeros((0, 3)), dofs=rest,
                                    basis=np.eye(rest.size), degree=None))
    try:
        part = reduce_part(sub, bases, reduce.modes)
    except ValueError as err:
        raise case.error((*loc, "modes"), " ".join(str(err).split()), reduce.modes) from None
    assert part.T is not None
    labels = tuple(f"eta{j}" for j in range(1, part.n_modes + 1)) + tuple(
        f"{f.name}.xi{j}" if f.degree is not None else sub.dof_labels[int(d)]
        for f in bases for j, d in enumerate(f.dofs[:f.r] if f.degree is None else
                                             range(1, f.r + 1)))
    return sub.transformed(part.T, labels, kind="craig-bampton",
                           omega_fixed_interface=part.omega_fixed_interface,
                           n_modes=part.n_modes, n_boundary=part.size - part.n_modes,
                           interface_degree=reduce.interface_degree, reduced_from=sub.n_dof,
                           reduced_kind=sub.kind)
