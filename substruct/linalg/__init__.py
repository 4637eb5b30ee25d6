"""Linear algebra shared by every layer: row equilibration, rank and consistency of
constraints, null-space bases and the factorizations."""

__all__: list[str] = []
