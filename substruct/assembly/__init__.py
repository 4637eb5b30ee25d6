"""Stacking substructures into one model with the constraint matrix ``A q = b + R F``
(paper eqs 23-27), and interface ties between meshed solids."""

from substruct.assembly.stack import Assembly, Connection, LinearConstraint, PointRef, assemble

__all__ = ["Assembly", "Connection", "LinearConstraint", "PointRef", "assemble"]
