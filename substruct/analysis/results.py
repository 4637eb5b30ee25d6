r"""What the analyses return: one :class:`Modes` type for coupled modes (eqs 28-34) and one
:class:`Receptance` type for receptances (eqs 11-15), whichever formulation and solver made them.

Both are plain data (arrays, strings, numbers): a result read back from a results file
(:mod:`substruct.io.hdf5`) is the same object as the one computed.  Both carry their
cross-checks, ``agreement``: for each check formulation, the largest relative difference from
the main formulation,

.. math::  \delta_{modes} = \max_j \frac{|\lambda^{check}_j - \lambda_j|}{|\lambda_j|}, \qquad
           \delta_{receptance} = \frac{\max_{k,i,j} |H^{check}_{kij} - H_{kij}|}
                                      {\max_{k,i,j} |H_{kij}|},

and the ``tolerance`` the figures were held to (:mod:`substruct.analysis.api`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from substruct.vocabulary import DEFAULT_TOLERANCE

__all__ = ["Modes", "Receptance", "DEFAULT_TOLERANCE"]

# DEFAULT_TOLERANCE (substruct.vocabulary): the largest relative disagreement between the main
# formulation and a check that a result may have (``analysis.modes.tolerance``,
# ``analysis.frf.tolerance`` in a case file).


@dataclass(kw_only=True)
class Modes:
    """Physical modes of a constrained system, the roots set aside, and the cross-checks.

    How roots are reported (the same for every formulation and solver):

    * a complex root stands for its conjugate pair: one entry, ``Im lambda > 0``;
    * a real root (over-damped, or critically damped within
      :data:`substruct.analysis.modes.roots.REAL_TOL`) is an entry of its own, with ``Im lambda = 0``
      exactly, ``omega = |lambda|`` and ``damping_ratio = 1``; an over-damped pair
      ``-zeta w +- w sqrt(zeta^2 - 1)`` therefore gives two entries, neither of which has the
      classical ``zeta > 1`` (pair them by hand if that is wanted);
    * a rigid-body mode (``K u = 0``, ``A u = 0``) is one entry ``lambda = 0`` with its exact
      vector; if the damping acts on it (``C u != 0``) its decay root ``~ -c/m`` is a further
      real entry;
    * infinite roots (massless coordinates that no constraint reaches, Lagrange multipliers)
      and the ``2 rank(A)`` zero roots of eqs (30)/(34) are not modes: they are listed in
      ``spurious`` with a reason each (the sparse solvers never compute them).

    Attributes:
        method: the formulation that computed them (``generalized-inverse``, ``null-space``,
            ``kkt``; ``"<method>/sparse"`` from the sparse solvers).
        eigenvalues: complex roots ``lambda`` (one of each conjugate pair, ``Im >= 0``),
            ascending in ``|lambda|``.
        omega: ``|lambda|`` in rad/s (the undamped natural frequency for proportional damping).
        damping_ratio: ``-Re(lambda) / |lambda|`` (0 for a zero root, 1 for a decaying real
            root).
        shapes: ``n x k`` mode shapes (phase set so the largest entry is real positive; scaled
            to ``u^H M u = 1`` where that is positive).
        residual: ``|A u| / (|A| |u|)`` for each mode.
        spurious: roots set aside, complex.
        spurious_reason: one explanation per spurious root.
        agreement: check formulation -> largest relative eigenvalue difference from the main
            one (:func:`substruct.analysis.api.modes_agreement`).
        solver: the strategy that ran (``"dense"``, ``"sparse"``, ``"sparse-damped"``), and why
            if it is not the one asked for.
        tolerance: the largest ``agreement`` the result was allowed.
    """

    method: str
    eigenvalues: np.ndarray
    omega: np.ndarray
    damping_ratio: np.ndarray
    shapes: np.ndarray
    residual: np.ndarray
    spurious: np.ndarray = field(default_factory=lambda: np.zeros(0, complex))
    spurious_reason: list[str] = field(default_factory=list)
    agreement: dict[str, float] = field(default_factory=dict)
    solver: str = ""
    tolerance: float = DEFAULT_TOLERANCE

    @property
    def freq_hz(self) -> np.ndarray:
        """Natural frequencies in Hz."""
        return self.omega / (2 * np.pi)

    def __len__(self) -> int:
        return int(np.size(self.omega))

    def lowest(self, count: int | None) -> "Modes":
        """The first ``count`` modes (all if ``None``); spurious roots and checks kept."""
        if count is None:
            return self
        k = min(int(count), len(self))
        return dataclasses.replace(self, eigenvalues=self.eigenvalues[:k],
                                   omega=self.omega[:k], damping_ratio=self.damping_ratio[:k],
                                   shapes=self.shapes[:, :k], residual=self.residual[:k])


@dataclass(kw_only=True)
class Receptance:
    r"""Receptances ``H[k, i, j]``: output ``i`` per unit force at input ``j``, at ``omega[k]``.

    .. math::  H[k, i, j] = o_i\, \hat H(\omega_k)\, e_j \qquad (\hat H = G^{-1} D,\ \text{eq 15})

    Attributes:
        method: the formulation of ``H`` (``generalized-inverse``, ``null-space``, ``kkt``).
        omega: circular frequencies (rad/s).
        H: complex ``(n_omega, n_outputs, n_inputs)`` (a sweep that wrote its blocks to a
            sink gives a :class:`~substruct.analysis.frf.stream.StreamedArray` instead: the
            shape, the summary and selections of what the sink holds).
        inputs, outputs: the names of the input and output points, verbatim.
        agreement: check formulation -> ``max |H_check - H| / max |H|``.
        constraint_residual: :math:`\max |D (A \hat q - R F)| / \max |H|` over all
            frequencies (``D``: the rows of ``A`` scaled to unit norm; on the sparse null-space
            path both maxima at the checked frequencies).
        tolerance: the largest ``agreement`` the result was allowed.
        quantity: what ``H`` is: ``"receptance"`` (u / F), ``"mobility"`` (velocity / F) or
            ``"accelerance"`` (acceleration / F) (:mod:`substruct.analysis.frf.quantity`).
    """

    method: str
    omega: np.ndarray
    H: np.ndarray
    inputs: list[str]
    outputs: list[str]
    agreement: dict[str, float] = field(default_factory=dict)
    constraint_residual: float = 0.0
    tolerance: float = DEFAULT_TOLERANCE
    quantity: str = "receptance"

    def at(self, input: str, output: str) -> np.ndarray:
        r"""The curve ``H[:, i, j]`` from a unit force at point ``input`` to point ``output``
        (names as the case wrote them), one complex value per frequency of ``omega``.

        .. math::  H_{ij}(\omega_k) = o_i\, \hat H(\omega_k)\, e_j

        Raises:
            KeyError: ``input`` is not an input or ``output`` not an output of the sweep
                (the message lists them).
        """
        if input not in self.inputs:
            raise KeyError(f"{input!r} is not an input of the receptances "
                           f"(inputs: {', '.join(self.inputs)})")
        if output not in self.outputs:
            raise KeyError(f"{output!r} is not an output of the receptances "
                           f"(outputs: {', '.join(self.outputs)})")
        return self.H[:, self.outputs.index(output), self.inputs.index(input)]
