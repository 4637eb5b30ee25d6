"""substruct: finite-element substructuring for structural dynamics.

Substructures (finite-element models, assumed-modes models, spring-mass-damper attachments) are
coupled through linear constraints by the generalized-inverse method of Eun, Lee, Chung and Park
("Structural and Mechanical Systems Subjected to Constraints"), checked against null-space and
Lagrange-multiplier formulations.

The Python API mirrors the command line::

    import substruct
    case = substruct.load_case("cases/tapered_rod.yaml")
    result = substruct.run_case(case)
    result.modes.omega
"""

__version__ = "0.1.0"

__all__ = ["__version__", "load_case", "run_case"]


def __getattr__(name: str):
    """Import the case and run layers on first use, so ``import substruct`` stays light."""
    if name == "load_case":
        from substruct.case.loader import load_case
        return load_case
    if name == "run_case":
        from substruct.run.runner import run_case
        return run_case
    raise AttributeError(f"module 'substruct' has no attribute {name!r}")
