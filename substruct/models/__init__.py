"""Makers of substructures: rods (assumed modes, enriched assumed modes, finite elements),
discrete systems (spring-mass-damper secondaries, springs, point masses) and meshed solids.

The names are imported from their modules on first use: a case of rods and springs never
loads the mesh readers and the solid meshers (meshio, scikit-fem's 3D elements, k-d trees).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from substruct.lazy import lazy_getattr

if TYPE_CHECKING:
    from substruct.models.discrete import fixed_free, free_free, point_mass, spring
    from substruct.models.enrichment import rod_assumed_modes_enriched, static_shapes
    from substruct.models.mesh_io import read_mesh
    from substruct.models.rod import (
        AssumedModesOptions,
        SUPPORTS,
        paper_taper,
        rod_assumed_modes,
        rod_fe,
        uniform_rod_frequencies,
    )
    from substruct.models.solid import (
        BoxGrid,
        RectangleGrid,
        solid_box,
        solid_from_mesh,
        solid_rectangle,
    )

#: Public name -> the module that defines it.
_LAZY = {
    "AssumedModesOptions": "rod",
    "BoxGrid": "solid",
    "RectangleGrid": "solid",
    "SUPPORTS": "rod",
    "fixed_free": "discrete",
    "free_free": "discrete",
    "paper_taper": "rod",
    "point_mass": "discrete",
    "read_mesh": "mesh_io",
    "rod_assumed_modes": "rod",
    "rod_assumed_modes_enriched": "enrichment",
    "rod_fe": "rod",
    "solid_box": "solid",
    "solid_from_mesh": "solid",
    "solid_rectangle": "solid",
    "spring": "discrete",
    "static_shapes": "enrichment",
    "uniform_rod_frequencies": "rod",
}

__all__ = sorted(_LAZY)


__getattr__ = lazy_getattr(__name__, _LAZY, prefix="substruct.models.")


def __dir__() -> list[str]:
    """The public names, lazy ones included."""
    return sorted(__all__)
