r"""What the test-lab analyses of a case produce, as plain arrays on the grid of ``/frf/omega``:
transfer path analysis (:class:`TpaResult`, ``analysis.tpa``) and model mixing
(:class:`SemmOutcome`, ``analysis.semm``)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["TpaResult", "SemmOutcome"]


@dataclass
class TpaResult:
    r"""Blocked forces and their validation (:mod:`substruct.analysis.frf.tpa`).

    Attributes:
        method: ``in_situ``, ``matrix_inverse``, ``pseudo_forces`` or ``operational`` (with `` (tsvd)``/`` (tikhonov)`` when
            regularised).
        interface: the paths ``c`` (inputs of the receptance).
        indicators: the points whose operating responses found the forces (the interface
            itself by matrix inverse).
        targets: the validation points.
        forces: ``n_omega x n_c``, :math:`f^{bl}`.
        contributions: ``n_omega x n_t x n_c``, :math:`Y_{tc_j} f^{bl}_j`.
        predicted, measured: ``n_omega x n_t``, :math:`Y_{tc} f^{bl}` and :math:`u_t`.
        error: ``n_omega``, :math:`\lVert \hat u_t - u_t\rVert / \lVert u_t \rVert`.
        transmissibility: operational TPA only: ``n_omega x n_t x n_i``, :math:`T`; the paths
            (``interface``) are then the indicators and ``forces`` their responses under the
            validation condition.
        validation_condition: operational TPA only: the condition left out of ``T``.
    """

    method: str
    interface: list[str]
    indicators: list[str]
    targets: list[str]
    forces: np.ndarray
    contributions: np.ndarray
    predicted: np.ndarray
    measured: np.ndarray
    error: np.ndarray
    transmissibility: np.ndarray | None = None
    validation_condition: int | None = None


@dataclass
class SemmOutcome:
    r"""A mixed model (:mod:`substruct.analysis.frf.semm`).

    Attributes:
        outputs, inputs: the numerical model's coordinates (those of ``analysis.frf``).
        Y: ``n_omega x n_o x n_i`` the mixed receptance :math:`Y^S`.
        measured_outputs, measured_inputs: the measured coordinates.
        boundary_outputs, boundary_inputs: those the mix is imposed at.
        coherence: ``n_omega x m_o x m_i`` of :math:`Y^S` and the measurement.
        validation: ``m_o x m_i`` bool, the measured entries off the boundary.
        indicator: ``n_omega``, the mean coherence over them (``nan``: none).
    """

    outputs: list[str]
    inputs: list[str]
    Y: np.ndarray
    measured_outputs: list[str]
    measured_inputs: list[str]
    boundary_outputs: list[str]
    boundary_inputs: list[str]
    coherence: np.ndarray
    validation: np.ndarray
    indicator: np.ndarray
    #: ``standard`` or ``extended`` (:func:`~substruct.analysis.frf.semm.semm`)
    form: str = "standard"
    #: extended form with two or more measured outputs: ``n_omega x m_o``, each measured
    #: output's coherence left out of the boundary
    #: (:func:`~substruct.analysis.frf.semm.channel_coherence`)
    channel_coherence: np.ndarray | None = None
