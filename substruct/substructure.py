"""The substructure: sparse matrices, a table of its coordinates, and a way to find its points.

A substructure is the unit that the assembler stacks (paper eqs 17, 23). Its equation of motion is

.. math::  M \\ddot q + C \\dot q + K q = f

with ``M``, ``C``, ``K`` sparse ``n x n`` matrices over ``n`` coordinates.  The coordinates may be
nodal displacements (finite elements, spring-mass systems) or generalized amplitudes (assumed
modes, modal coordinates after reduction).  Whatever they are, the physical displacement at a
*point* of the substructure is a linear function of them: ``u(point) = row(point) @ q``.  That row
is what the compatibility conditions (eqs 24-26) and user constraints (eq 52) are made of.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any, Callable

import numpy as np
import scipy.sparse as sp

__all__ = ["Geometry", "Substructure", "PointError"]

Locator = Callable[[Any], sp.csr_array]


class PointError(ValueError):
    """A point reference that does not lie on the substructure."""


@dataclass(frozen=True)
class Geometry:
    """What is needed to draw a substructure deformed by a coordinate vector.

    Attributes:
        points: ``(N, 3)`` coordinates of the drawing nodes.
        cells: meshio-style list of ``(cell_type, connectivity)`` pairs.
        interp: sparse ``(3 N, n)`` matrix; ``(interp @ q).reshape(N, 3)`` is the displacement of
            the drawing nodes for the coordinate vector ``q``.
        glyphs: names of drawing nodes to mark (attachment points), as ``{label: node index}``.
        rotations: sparse ``(3 N, n)`` or ``None``: ``(rotations @ q).reshape(N, 3)`` are the
            rotations of the drawing nodes (frames, shells and Nastran models; ``None`` for
            parts without rotations).
    """

    points: np.ndarray
    cells: list[tuple[str, np.ndarray]]
    interp: sp.csr_array
    glyphs: dict[str, int] = field(default_factory=dict)
    rotations: sp.csr_array | None = None

    def displacement(self, q: np.ndarray) -> np.ndarray:
        """Nodal displacements ``(N, 3)`` (complex if ``q`` is) for coordinates ``q``."""
        return np.asarray(self.interp @ q).reshape(-1, 3)

    def transformed(self, T: sp.sparray | np.ndarray) -> "Geometry":
        """The same drawing for new coordinates ``p`` with ``q = T p``."""
        rot = None if self.rotations is None else sp.csr_array(self.rotations @ T)
        return replace(self, interp=sp.csr_array(self.interp @ T), rotations=rot)


@dataclass(frozen=True, eq=False)
class Substructure:
    """A linear substructure with sparse matrices and named points.

    Attributes:
        name: name from the case file, kept verbatim in every output.
        M, K, C: sparse ``n x n`` mass, stiffness and damping matrices (``C`` is zero if the
            substructure is undamped).  ``M`` may be singular (massless coordinates, eq 6).
        dof_labels: one label per coordinate, e.g. ``"y3"`` or ``"node12.ux"``.
        locate: maps a point reference (a position ``x`` for a rod, a name such as ``"mass"``
            for a discrete system, ``(xyz, component)`` for a solid) to a sparse ``1 x n`` row
            ``r`` with ``u(point) = r @ q``.  Raises :class:`PointError` for a point that is not
            on the substructure.
        kind: a short description of the model (``"rod/assumed-modes"``, ``"fixed-free"`` ...).
        geometry: how to draw it, or ``None``.
        meta: model data worth keeping in results (lengths, element order, basis size ...).
        position: maps a point reference to its ``(3,)`` coordinates in space (for drawing
            attachments where they are attached), or ``None``.
    """

    name: str
    M: sp.csr_array
    K: sp.csr_array
    C: sp.csr_array
    dof_labels: tuple[str, ...]
    locate: Locator
    kind: str = "matrices"
    geometry: Geometry | None = None
    meta: dict[str, Any] = field(default_factory=dict)
    position: Callable[[Any], np.ndarray] | None = None

    def __post_init__(self) -> None:
        n = self.M.shape[0]
        for label, mat in (("M", self.M), ("K", self.K), ("C", self.C)):
            if mat.shape != (n, n):
                raise ValueError(f"{self.name}: {label} has shape {mat.shape}, expected ({n}, {n})")
        if len(self.dof_labels) != n:
            raise ValueError(f"{self.name}: {len(self.dof_labels)} DOF labels for {n} coordinates")

    @property
    def n_dof(self) -> int:
        """Number of coordinates ``n``."""
        return self.M.shape[0]

    @property
    def massless(self) -> np.ndarray:
        """Boolean mask of coordinates with a zero row in ``M`` (the ``s`` block of eq 6)."""
        row_norm = np.asarray(abs(self.M).sum(axis=1)).ravel()
        return row_norm == 0.0

    def row(self, where: Any) -> sp.csr_array:
        """Sparse ``1 x n`` row giving the displacement at point ``where``."""
        found = self.locate(where)
        r = found if isinstance(found, sp.csr_array) else sp.csr_array(found)
        if r.shape != (1, self.n_dof):
            raise ValueError(f"{self.name}: locator returned shape {r.shape}")
        return r

    def transformed(self, T: sp.sparray | np.ndarray, labels: tuple[str, ...], kind: str,
                    **meta: Any) -> "Substructure":
        """Change of coordinates ``q = T p`` (eqs 21-22): ``T^T M T``, ``T^T C T``, ``T^T K T``.

        Points and drawing follow the new coordinates: ``row_new(x) = row(x) @ T``.
        """
        Ts = sp.csr_array(T) if sp.issparse(T) else np.asarray(T)

        def project(mat: sp.csr_array) -> sp.csr_array:
            out = Ts.T @ (mat @ Ts)
            out = sp.csr_array(out)
            return sp.csr_array((out + out.T) / 2)

        old_locate = self.locate

        def locate(where: Any) -> sp.csr_array:
            return sp.csr_array(old_locate(where) @ Ts)

        geometry = self.geometry.transformed(Ts) if self.geometry is not None else None
        return Substructure(
            name=self.name, M=project(self.M), K=project(self.K), C=project(self.C),
            dof_labels=labels, locate=locate, kind=kind, geometry=geometry,
            meta={**self.meta, **meta}, position=self.position,
        )


def as_csr(mat: Any, n: int | None = None) -> sp.csr_array:
    """A float ``csr_array`` from a dense or sparse matrix (a zero ``n x n`` one for ``None``)."""
    if mat is None:
        if n is None:
            raise ValueError("size needed for a missing matrix")
        return sp.csr_array((n, n), dtype=float)
    return sp.csr_array(mat, dtype=float)
