r"""What a transient analysis returns: one :class:`Transient`, plain arrays, whichever form
(generalized inverse, null space, modal superposition) computed it.

The constraint residual is, at each recorded instant, :math:`\max_i |(D A q - D b)_i|` with the
rows of ``A`` scaled to unit norm (``D``), and the drift figure of a run is

.. math::  \text{drift} = \frac{\max_k \max_i |(D A q_k - D b)_i|}{\max_k \max_j |q_{k,j}|} .

The energy history holds, per recorded instant, the kinetic energy
:math:`\tfrac12 \dot x^T M_x \dot x`, the strain energy :math:`\tfrac12 x^T K_x x`, the work of
every load of the integrated equations and the energy dissipated by ``C`` since the start, in
the coordinates ``x`` the form integrates (``q`` itself for the generalized-inverse form, with
the work of moving supports' reactions; :mod:`substruct.analysis.transient.integrators`); the
balance :math:`T + V - W + D` is constant to rounding for Newmark's average acceleration and
held to the tolerance (:func:`substruct.analysis.transient.record.require_energy_balance`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from substruct.analysis.results import DEFAULT_TOLERANCE

__all__ = ["ENERGY_LABELS", "Transient"]

#: The columns of :attr:`Transient.energy`.
ENERGY_LABELS = ("kinetic", "strain", "external_work", "dissipated")


@dataclass(kw_only=True)
class Transient:
    r"""Time histories of a constrained system.

    Attributes:
        method: the main form (``generalized-inverse``, ``null-space``, ``"modal"``).
        integrator: ``"newmark"`` or ``"generalized-alpha"``; ``rho_inf`` the spectral radius
            at infinite frequency the integrator used (1 for Newmark).
        dt: the step; ``t``: the recorded instants (``n_samples``).
        outputs: the names of the output points.
        displacement, velocity, acceleration: ``n_samples x n_outputs``.
        constraint_labels: the constraint rows; ``constraint_forces``: ``n_samples x m``, the
            multipliers :math:`\\lambda` of :math:`Q^c = A^T \\lambda` (eq 5) per row.
        constraint_residual: ``n_samples``, the largest equilibrated residual.
        drift: the residual over the largest coordinate (module docstring).
        energy: ``n_samples x 4`` (:data:`ENERGY_LABELS`).
        snapshot_t, snapshots: the full displacement every k steps (``n_fields x n``), or empty.
        agreement: check form -> ``max |y_check - y| / max |y|`` over the output displacements
            and the final field.
        tolerance: the largest agreement allowed.
        solver: how it was solved (factorization, notes).
        base_motion: ``n_samples x 3``, the ground's displacement, velocity and acceleration
            :math:`g, \dot g, \ddot g` at the recorded instants (empty without a moving ground,
            :mod:`substruct.analysis.transient.base`).
        base_influence: ``n_outputs``, the influence vector at the outputs, :math:`O r`.

    The histories are absolute; :meth:`relative` gives them relative to the moving ground.
    """

    method: str
    integrator: str
    rho_inf: float
    dt: float
    t: np.ndarray
    outputs: list[str]
    displacement: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    constraint_labels: list[str] = dataclasses.field(default_factory=list)
    constraint_forces: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((0, 0)))
    constraint_residual: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))
    drift: float = 0.0
    energy: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((0, 4)))
    snapshot_t: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))
    snapshots: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((0, 0)))
    agreement: dict[str, float] = dataclasses.field(default_factory=dict)
    tolerance: float = DEFAULT_TOLERANCE
    solver: str = ""
    base_motion: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((0, 3)))
    base_influence: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))

    def relative(self, name: str) -> np.ndarray:
        r"""``displacement``, ``velocity`` or ``acceleration`` relative to the ground,
        :math:`O (q - r g)` and its rates (the absolute history without a moving ground)."""
        k = ("displacement", "velocity", "acceleration").index(name)
        y = np.asarray(getattr(self, name))
        if not self.base_motion.size:
            return y
        return y - self.base_motion[:, k:k + 1] * self.base_influence[None, :]

    @property
    def steps(self) -> int:
        """The number of steps integrated."""
        return int(round(float(self.t[-1] - self.t[0]) / self.dt)) if self.t.size else 0

    def energy_balance(self) -> np.ndarray:
        r""":math:`T + V - W + D` at each recorded instant (constant for an energy-conserving
        integrator)."""
        e = self.energy
        return e[:, 0] + e[:, 1] - e[:, 2] + e[:, 3]
