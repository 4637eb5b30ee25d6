"""substruct: finite-element substructuring for structural dynamics.

Substructures (finite-element models, assumed-modes models, spring-mass-damper attachments) are
coupled through linear constraints by the generalized-inverse method of Eun, Lee, Chung and Park
("Structural and Mechanical Systems Subjected to Constraints"), checked against null-space and
Lagrange-multiplier formulations.
"""

__version__ = "0.1.0"

__all__ = ["__version__"]
