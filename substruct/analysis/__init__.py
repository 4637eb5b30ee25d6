"""Analyses of an assembly: coupled modes (eqs 28-34) and receptances (eqs 11-15) by the
generalized-inverse, null-space and Lagrange (KKT) formulations.

The front door is :mod:`substruct.analysis.api`: ``modes(system, count, options=...)`` and
``receptance_sweep(system, omegas, inputs, outputs, options=...)`` on a
:class:`~substruct.analysis.system.ConstrainedSystem` return one
:class:`~substruct.analysis.results.Modes` and one :class:`~substruct.analysis.results.Receptance`
with their cross-checks; the dense, sparse and damped solvers are strategies behind them
(:func:`substruct.analysis.api.choose_solver`).  Nothing is imported here, so that importing one
module of the layer does not import them all.
"""

__all__: list[str] = []
