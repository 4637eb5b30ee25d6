"""What the specification analyses of a case produce, as plain arrays: the random response
(:class:`RandomResponse`) and the shock response spectra (:class:`ShockSpectra`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from substruct.analysis.frf.random import THREE_SIGMA_EXCEEDANCE

__all__ = ["RandomResponse", "ShockSpectra", "THREE_SIGMA_EXCEEDANCE"]


@dataclass
class RandomResponse:
    r"""Response PSDs of ``analysis.random``: :math:`S_y(f) = H(f) S_f(f) H(f)^H`.

    Attributes:
        f: the frequency grid (Hz).
        outputs, inputs: the output points and the input names (force points, or ``base``).
        quantity: ``displacement``, ``velocity`` or ``acceleration`` (absolute).
        input_psd: ``n_f x p``, the input PSDs interpolated on the grid.
        input_csd: ``n_f x p x p``, the input cross-spectral matrix when inputs are correlated
            (``analysis.random.cross``), else ``None`` (diagonal: ``input_psd``).
        psd: ``n_f x q x q``, the response cross-spectral matrix (auto-PSDs on the diagonal).
        rms: ``q``, :math:`\sqrt{\int S_{ii}\, df}` (trapezoid rule on the grid).
        method, agreement, tolerance: of the receptance sweep behind it.
        base: the inputs are base accelerations (``base`` or ``bases``), not forces.
    """

    f: np.ndarray
    outputs: list[str]
    inputs: list[str]
    quantity: str
    input_psd: np.ndarray
    psd: np.ndarray
    rms: np.ndarray
    method: str = ""
    agreement: dict[str, float] = field(default_factory=dict)
    tolerance: float = 0.0
    input_csd: np.ndarray | None = None
    base: bool = False


@dataclass
class ShockSpectra:
    """Shock response spectra of ``analysis.srs`` (:func:`substruct.analysis.transient.srs.srs`).

    Attributes:
        fn: natural frequencies (Hz); ``zeta`` the damping ratio.
        outputs: the transient outputs whose absolute accelerations are the inputs.
        pos, neg, maxabs, pv: ``n_outputs x n_fn``: largest positive, negative (as a
            magnitude) and absolute acceleration, and pseudo-velocity.
        dt: the sampling step of the histories (s).
    """

    fn: np.ndarray
    zeta: float
    outputs: list[str]
    pos: np.ndarray
    neg: np.ndarray
    maxabs: np.ndarray
    pv: np.ndarray
    dt: float
