"""Analyses of an assembly: coupled modes (eqs 28-34) and receptances (eqs 11-15) by the
generalized-inverse, null-space and Lagrange (KKT) formulations."""

__all__: list[str] = []
