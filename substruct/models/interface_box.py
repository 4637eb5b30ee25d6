r"""A 3D box cut along its length into parts, each built and reduced on its own.

The box :math:`[0, L_x] \times [0, L_y] \times [0, L_z]` of ``n_x x n_y x n_z`` hexahedra (or
tetrahedra), clamped on the face :math:`x = 0` if asked, is cut by the planes
:math:`x = x_1 < \dots < x_{P-1}` at element boundaries into ``P`` parts of nearly equal
element counts.  Part ``k`` is its own mesh (:func:`~substruct.models.solid.solid_box`); its
interfaces are the cut planes at its ends, named ``"cut<j>"``, with the polynomial basis of
:mod:`substruct.models.interface_basis`.  The monolithic box of the same mesh is
:meth:`BoxCut.whole`.

:func:`reduce_box_part` is one independent task, ``(cut, k, g, p) -> ReducedPart``: it builds
part ``k``'s mesh and matrices, reduces them
(:func:`~substruct.models.interface_reduction.reduce_part`) and lets them go, so the full
matrices of the box are never formed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from substruct.linalg.factorize import Factorize
from substruct.models.interface_basis import InterfaceBasis, interface_basis
from substruct.models.interface_reduction import ReducedPart, reduce_part
from substruct.models.solid import BoxGrid, solid_box
from substruct.substructure import Substructure

__all__ = ["BoxCut", "box_part", "part_interfaces", "reduce_box_part"]


@dataclass(frozen=True)
class BoxCut:
    """A box and how it is cut (module docstring).

    Attributes:
        lengths: ``(L_x, L_y, L_z)``.
        divisions: elements ``(n_x, n_y, n_z)``; ``n_x >= n_parts``.
        n_parts: ``P``.
        E, nu, rho: material.
        cell: ``"hex"`` or ``"tet"``.
        clamped: the face ``x = 0`` is held.
    """

    lengths: tuple[float, float, float]
    divisions: tuple[int, int, int]
    n_parts: int
    E: float = 2.1e11
    nu: float = 0.3
    rho: float = 7850.0
    cell: str = "hex"
    clamped: bool = True

    def __post_init__(self) -> None:
        if not 1 <= self.n_parts <= self.divisions[0]:
            raise ValueError(f"box cut: n_parts = {self.n_parts!r} needs 1 <= n_parts <= "
                             f"n_x = {self.divisions[0]}")

    def cut_elements(self) -> np.ndarray:
        """Element index along ``x`` of each part's start, and ``n_x`` last (``P + 1``)."""
        return np.round(np.linspace(0, self.divisions[0], self.n_parts + 1)).astype(int)

    def x_at(self, element: int) -> float:
        """The ``x`` coordinate of the element boundary ``element``."""
        return self.lengths[0] * element / self.divisions[0]

    def n_dof(self) -> int:
        """Free coordinates of the whole box (clamped face removed)."""
        nx, ny, nz = self.divisions
        return 3 * (nx + int(not self.clamped)) * (ny + 1) * (nz + 1)

    def whole(self) -> Substructure:
        """The monolithic box of the same mesh (the reference of the reduced assembly)."""
        return solid_box("box", BoxGrid(self.lengths, self.divisions, cell=self.cell), self.E,
                         self.nu, self.rho, fixed=self._fixed())

    def _fixed(self) -> list[dict[str, list[list[float]]]]:
        _, ly, lz = self.lengths
        return [{"box": [[0, 0, 0], [0, ly, lz]]}] if self.clamped else []


def box_part(cut: BoxCut, k: int) -> Substructure:
    """Part ``k`` (``0 <= k < P``) of the cut box, meshed alone."""
    if not 0 <= k < cut.n_parts:
        raise ValueError(f"box cut: part {k!r} outside 0..{cut.n_parts - 1}")
    e = cut.cut_elements()
    x0, x1 = cut.x_at(e[k]), cut.x_at(e[k + 1])
    _, ly, lz = cut.lengths
    _, ny, nz = cut.divisions
    fixed = cut._fixed() if k == 0 else []
    grid = BoxGrid((x1 - x0, ly, lz), (int(e[k + 1] - e[k]), ny, nz), cell=cut.cell,
                   origin=(x0, 0.0, 0.0))
    return solid_box(f"part{k}", grid, cut.E, cut.nu, cut.rho, fixed=fixed)


def part_interfaces(cut: BoxCut, k: int, sub: Substructure, degree: int | None
                    ) -> list[InterfaceBasis]:
    """The cut planes at the ends of part ``k`` with their bases (``"cut<j>"`` at
    ``x = x_j``)."""
    e = cut.cut_elements()
    _, ly, lz = cut.lengths
    faces = []
    for j in (k, k + 1):
        if 0 < j < cut.n_parts:
            x = cut.x_at(e[j])
            faces.append(interface_basis(sub, f"cut{j}", [[x, 0, 0], [x, ly, lz]], degree))
    return faces


def reduce_box_part(cut: BoxCut, k: int, n_modes: int, degree: int | None, *,
                    factorization: str | Factorize = "auto", keep_basis: bool = True
                    ) -> ReducedPart:
    """Build part ``k`` of ``cut``, reduce it by Craig-Bampton with ``n_modes`` fixed-interface
    modes and interface bases of ``degree`` (``None``: all interface DOFs), return the
    reduced part; the mesh and sparse matrices are released on return."""
    if cut.n_parts < 2:
        raise ValueError("box cut: a reduction needs at least two parts (an interface)")
    sub = box_part(cut, k)
    faces = part_interfaces(cut, k, sub, degree)
    return reduce_part(sub, faces, n_modes, factorization=factorization,
                       keep_basis=keep_basis)
