"""Substructures made from their case specifications: rods (assumed modes or finite
elements, with optional modal truncation, eqs 21-22), spring-mass-damper systems (eqs 17-20),
springs, point masses, matrices and meshed solids."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Collection, Mapping

import numpy as np
import scipy.sparse as sp

from substruct.case.kinds import is_frame, is_matrices, is_nastran, is_solid, is_superelement
from substruct.case.loader import Case, DiscreteSpec, FiniteElements, RodSpec
from substruct.case.substructures import MassSpec, SpringSpec
from substruct.models.discrete import fixed_free, free_free, point_mass, spring
from substruct.models.reduction import modal_truncation
from substruct.substructure import Geometry, PointError, Substructure, as_csr

if TYPE_CHECKING:
    from substruct.case.matrices import MatrixSpec

__all__ = ["make_substructures"]


# ---------------------------------------------------------------------- substructures


def _matrices_substructure(spec: MatrixSpec) -> Substructure:
    labels = spec.dof_labels()
    n = len(labels)
    index = {lab: k for k, lab in enumerate(labels)}

    def locate(where: Any) -> sp.csr_array:
        if where not in index:
            raise PointError(f"{spec.name}: no coordinate {where!r}")
        return sp.csr_array(([1.0], ([0], [index[where]])), shape=(1, n))

    K = as_csr(spec.matrix("K"))
    return Substructure(name=spec.name, M=as_csr(spec.matrix("M")), K=K,
                        C=as_csr(spec.matrix("C"), n), dof_labels=tuple(labels),
                        locate=locate, kind="matrices", geometry=_chain_geometry(K, index),
                        meta={"n_dof": n})


def _chain_geometry(K: sp.csr_array, index: dict[str, int]) -> Geometry | None:
    """Coordinates drawn as nodes at ``x = 0, 1, ...`` moving along ``x``, joined by a line
    wherever ``K`` couples two of them (the springs of a lumped model)."""
    n = K.shape[0]
    if n > 2000 or K.nnz > 40000:
        return None
    coo = sp.coo_array(sp.triu(K, k=1))
    pairs = np.column_stack([coo.row, coo.col])[coo.data != 0].astype(int)
    linked = np.zeros(n, dtype=bool)
    linked[pairs.ravel()] = True
    cells = [("line", pairs)] if len(pairs) else []
    if not linked.all():
        cells.append(("vertex", np.flatnonzero(~linked).reshape(-1, 1)))
    points = np.column_stack([np.arange(n, dtype=float), np.zeros(n), np.zeros(n)])
    interp = sp.csr_array((np.ones(n), (3 * np.arange(n), np.arange(n))), shape=(3 * n, n))
    return Geometry(points=points, cells=cells, interp=interp, glyphs=dict(index))


def _rod(case: Case, i: int, spec: RodSpec, nodes_at: list[float]) -> Substructure:
    from substruct.models.rod import rod_assumed_modes, rod_fe  # scikit-fem: for rods only

    disc = spec.discretization
    try:
        if isinstance(disc, FiniteElements):
            sub = rod_fe(spec.name, spec.length, spec.EA_function, spec.m_function,
                         disc.elements, order=disc.order, support=spec.support,
                         nodes_at=nodes_at)
        else:
            sub = rod_assumed_modes(spec.name, spec.length, spec.EA_function, spec.m_function,
                                    disc.n, support=spec.support, mapping=disc.mapping,
                                    nodes_at=nodes_at)
    except ValueError as err:
        raise case.error(("substructures", i, "discretization"), str(err)) from None
    if spec.reduce is not None:
        damping = spec.reduce.damping.as_argument() if spec.reduce.damping else None
        try:
            sub = modal_truncation(sub, spec.reduce.modes, damping)
        except ValueError as err:
            raise case.error(("substructures", i, "reduce", "modes"), str(err),
                             spec.reduce.modes) from None
    return sub


def make_substructures(case: Case, positions: dict[str, list[float]],
                       prebuilt: Mapping[str, Substructure] | None = None,
                       only: Collection[str] | None = None) -> list[Substructure]:
    """The substructures of a case, in case order, as specified (solids unreduced: they are
    tied and reduced by :func:`substruct.builder.solids.tie_and_reduce`).

    Args:
        case: the validated case.
        positions: for each rod, the places its points use, which finite-element meshes put
            nodes at.
        prebuilt: substructures already made (and reduced) from this same definition, by name,
            used as they are; a solid tied by an ``interfaces:`` item is still made unreduced,
            for its ties (``tie_and_reduce`` puts the prebuilt one in its place).
        only: make these names only (``None``: all).

    Raises:
        CaseError: a substructure that cannot be made (naming its field).
    """
    subs = []
    tied = {n for item in case.interfaces for n in item.between}
    for i, spec in enumerate(case.substructures):
        if only is not None and spec.name not in only:
            continue
        if prebuilt and spec.name in prebuilt and spec.name not in tied:
            subs.append(prebuilt[spec.name])
        elif isinstance(spec, RodSpec):
            subs.append(_rod(case, i, spec, positions.get(spec.name, [])))
        elif isinstance(spec, DiscreteSpec):
            make = fixed_free if spec.type == "fixed-free" else free_free
            subs.append(make(spec.name, spec.mass, spec.stiffness, spec.damping))
        elif isinstance(spec, SpringSpec):
            subs.append(spring(spec.name, spec.stiffness, spec.damping, grounded=spec.ground))
        elif isinstance(spec, MassSpec):
            subs.append(point_mass(spec.name, spec.mass))
        elif is_solid(spec):  # each kind's builder imported when used
            from substruct.builder.solids import build_solid

            subs.append(build_solid(case, i, spec))
        elif is_matrices(spec):
            subs.append(_matrices_substructure(spec))
        elif is_frame(spec):
            from substruct.builder.frames import build_frame

            subs.append(build_frame(case, i, spec))
        elif is_superelement(spec):
            from substruct.builder.superelements import build_superelement

            subs.append(build_superelement(case, i, spec))
        elif is_nastran(spec):
            from substruct.builder.nastran import build_nastran  # Nastran: only when used

            subs.append(build_nastran(case, spec))
        # type: frf has no matrices: split off by substruct.builder.frf_parts
    return subs

