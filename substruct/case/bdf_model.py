"""The model a Nastran file describes, read and cross-referenced
(:mod:`substruct.case.bdf_xref`): grids in basic coordinates and the elements, masses,
springs, links, supports and requests joined to them, ready for
:mod:`substruct.models.nastran`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from substruct.case.bdf_cards import Bar, Conm2, Mat1, Rod
from substruct.case.bdf_constraints import Mpc, Rbar, Rbe2, Rbe3
from substruct.case.bdf_control import Eigrl
from substruct.case.bdf_shells import Plate
from substruct.case.bdf_solids import SolidCell
from substruct.case.bdf_springs import Bush

__all__ = ["BdfSection", "ShellSection", "BushSpring", "BulkData"]


@dataclass(frozen=True)
class BdfSection:
    """A line element's property with its material: ``A, I1, I2, J, nsm`` and ``E, G, rho``
    (``I1``, ``I2`` zero for a rod); ``shear``: shear flexibility, with the factors ``kshear``
    (``K1``, ``K2`` of planes 1 and 2; 0: none in that plane): PBEAM's, 1 when blank, 0.9 for
    a PBARL/PBEAML ``ROD``; ``beam``: a CBEAM
    (whose lumped mass has the torsional inertia)."""

    A: float
    I1: float
    I2: float
    J: float
    nsm: float
    mat: Mat1
    shear: bool
    kshear: tuple[float, float] = (1.0, 1.0)
    beam: bool = False


@dataclass
class BulkData:
    """A bulk data file read and cross-referenced.

    Attributes:
        grids: grid id -> position in basic coordinates.
        frames: grid id -> ``F`` (3 x 3) of a grid whose GRID ``CD`` is not basic: its
            coordinates are along the columns of ``F`` (basic), :math:`u_{basic} = F u_{CD}`
            (:mod:`substruct.case.bdf_coords`).
        rods, bars: elements with their :class:`BdfSection`.
        plates: CQUAD4 and CTRIA3 with their :class:`ShellSection`.
        bushes: CBUSH with their stiffness and axes (:class:`BushSpring`).
        solids: CHEXA, CPENTA and CTETRA with their PSOLID's MAT1.
        masses: CONM2 with offset and inertia in basic coordinates.
        springs: ``(id, k, (grid, component), (grid, component) or None)``, components 0-5.
        rbe2, rbe3, rbar, mpcs: rigid elements and the chosen MPC set.
        spc: grid id -> components held (0-5): the chosen SPC set and GRID PS.
        eigrl: the chosen EIGRL (``None`` if the file has none).
        wtmass, coupled, autospc: PARAM WTMASS, COUPMASS > 0, AUTOSPC.
    """

    source: str
    grids: dict[int, np.ndarray] = field(default_factory=dict)
    frames: dict[int, np.ndarray] = field(default_factory=dict)
    rods: list[tuple[Rod, BdfSection]] = field(default_factory=list)
    bars: list[tuple[Bar, BdfSection]] = field(default_factory=list)
    masses: list[Conm2] = field(default_factory=list)
    springs: list[tuple[int, float, tuple[int, int], tuple[int, int] | None]] = \
        field(default_factory=list)
    plates: list[tuple[Plate, "ShellSection"]] = field(default_factory=list)
    bushes: list["BushSpring"] = field(default_factory=list)
    solids: list[tuple[SolidCell, Mat1]] = field(default_factory=list)
    rbe2: list[Rbe2] = field(default_factory=list)
    rbe3: list[Rbe3] = field(default_factory=list)
    rbar: list[Rbar] = field(default_factory=list)
    mpcs: list[Mpc] = field(default_factory=list)
    spc: dict[int, set[int]] = field(default_factory=dict)
    eigrl: Eigrl | None = None
    wtmass: float = 1.0
    coupled: bool = False
    autospc: bool = True
    title: str = ""


@dataclass(frozen=True)
class ShellSection:
    """A PSHELL with its materials: thickness ``t``, membrane material ``membrane`` and
    bending material ``bending`` (``None``: none), bending inertia ratio ``bend`` (``12 I /
    T^3``), non-structural mass per area ``nsm``, transverse shear stiffness per width
    ``shear`` (``TS G3``, MID3 given: a Reissner-Mindlin plate; ``None``: Kirchhoff's); the
    mass density is MID1's (MID2's if MID1 is blank)."""

    t: float
    membrane: Mat1 | None
    bending: Mat1 | None
    bend: float
    nsm: float
    shear: float | None = None

    @property
    def rho(self) -> float:
        """The density of the mass."""
        mat = self.membrane if self.membrane is not None else self.bending
        assert mat is not None
        return mat.rho


@dataclass(frozen=True)
class BushSpring:
    """A CBUSH with its PBUSH: stiffnesses ``k`` (K1 - K6, element axes), the element axes
    ``axes`` (rows, basic) when they come from a coordinate system, else the orientation
    vector ``v`` (basic) for the axis ``GA -> GB`` as CBAR."""

    bush: Bush
    k: tuple[float, ...]
    axes: np.ndarray | None
    v: np.ndarray | None
