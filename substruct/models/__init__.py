"""Makers of substructures: rods (assumed modes, enriched assumed modes, finite elements),
discrete systems (spring-mass-damper secondaries, springs, point masses) and meshed solids."""

from substruct.models.discrete import fixed_free, free_free, point_mass, spring
from substruct.models.enrichment import rod_assumed_modes_enriched, static_shapes
from substruct.models.rod import (
    SUPPORTS,
    paper_taper,
    rod_assumed_modes,
    rod_fe,
    uniform_rod_frequencies,
)
from substruct.models.mesh_io import read_mesh
from substruct.models.solid import solid_box, solid_from_mesh, solid_rectangle

__all__ = [
    "SUPPORTS",
    "fixed_free",
    "free_free",
    "paper_taper",
    "point_mass",
    "read_mesh",
    "rod_assumed_modes",
    "rod_assumed_modes_enriched",
    "rod_fe",
    "solid_box",
    "solid_from_mesh",
    "solid_rectangle",
    "spring",
    "static_shapes",
    "uniform_rod_frequencies",
]
