"""What the specification analyses of a case produce, as plain arrays: the random response
(:class:`RandomResponse`) and the shock response spectra (:class:`ShockSpectra`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from substruct.analysis.frf.random import THREE_SIGMA_EXCEEDANCE

__all__ = ["RandomResponse", "BaseFrf", "ShockSpectra", "THREE_SIGMA_EXCEEDANCE"]


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
class BaseFrf:
    r"""Transmissibilities of ``analysis.base_frf``: :math:`T[k, i, j] = (i \omega_k)^p\,
    \hat u_i / \hat a_j`, output ``i``'s absolute motion (``p = 0, 1, 2``: displacement,
    velocity, acceleration) per unit acceleration :math:`\hat a_j` of base input ``j``.

    Attributes:
        omega: the circular frequencies (rad/s).
        outputs, inputs: the output points and the base inputs' names (``base`` or those of
            ``bases``).
        quantity: ``displacement``, ``velocity`` or ``acceleration`` (the transmissibility).
        T: ``n_w x q x p``, complex.
        method, agreement, tolerance: of the sweep behind it (``agreement`` holds the
            relative-coordinates check of every frequency).
    """

    omega: np.ndarray
    outputs: list[str]
    inputs: list[str]
    quantity: str
    T: np.ndarray
    method: str = ""
    agreement: dict[str, float] = field(default_factory=dict)
    tolerance: float = 0.0


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
