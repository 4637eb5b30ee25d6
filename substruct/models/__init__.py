"""Makers of substructures: rods (assumed modes, finite elements) and discrete systems."""

from substruct.models.discrete import fixed_free, free_free
from substruct.models.rod import (
    SUPPORTS,
    paper_taper,
    rod_assumed_modes,
    rod_fe,
    uniform_rod_frequencies,
)

__all__ = [
    "SUPPORTS",
    "fixed_free",
    "free_free",
    "paper_taper",
    "rod_assumed_modes",
    "rod_fe",
    "uniform_rod_frequencies",
]
