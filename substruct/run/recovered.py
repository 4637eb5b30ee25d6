r"""Responses recovered inside superelements by their output transformation matrices
(:mod:`substruct.case.recovery`): what a result holds of them, plain arrays.

For a part with coordinates :math:`x` (its block of the coupled model's coordinates) and a
recovery matrix :math:`R = [R_{s_1} \dots]` acting on the histories :math:`s_i`,

* in a mode with root :math:`\lambda` and shape :math:`\phi`, :math:`x(t) = \phi e^{\lambda t}`
  gives :math:`y = \sum_i R_{s_i} \lambda^{p_i} \phi` (:math:`p` = 0, 1, 2 for displacement,
  velocity, acceleration): the recovered mode shape, per unit modal amplitude;
* in a receptance sweep, per unit force at input :math:`j` at the frequency :math:`\omega`,
  :math:`H_y[\omega, :, j] = \sum_i (i\omega)^{p_i} R_{s_i} H_x(\omega) e_j`, and its peaks:
  the largest :math:`|H_y|` of each row over the frequencies and inputs, where it is reached;
* in a transient response, :math:`y(t) = \sum_i R_{s_i} x_{s_i}(t)` at each recorded instant,
  and its peaks: the largest and smallest value of each row and their instants.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["Recovered", "Peaks", "FrfPeaks", "peaks_of", "frf_peaks_of"]


@dataclass
class Peaks:
    """Per row: the largest value ``max`` at ``t_max``, the smallest ``min`` at ``t_min``
    (the first instant where each is reached)."""

    max: np.ndarray
    t_max: np.ndarray
    min: np.ndarray
    t_min: np.ndarray

    def extreme(self) -> np.ndarray:
        """Per row, the value of largest magnitude (with its sign)."""
        return np.where(np.abs(self.max) >= np.abs(self.min), self.max, self.min)


def peaks_of(history: np.ndarray, t: np.ndarray) -> Peaks:
    """The :class:`Peaks` of ``history`` (``n_samples x n_rows``) over the instants ``t``."""
    h = np.asarray(history, dtype=float)
    if h.shape[0] == 0:
        z = np.zeros(h.shape[1])
        return Peaks(z, z.copy(), z.copy(), z.copy())
    kmax, kmin = np.argmax(h, axis=0), np.argmin(h, axis=0)
    cols = np.arange(h.shape[1])
    return Peaks(h[kmax, cols], np.asarray(t)[kmax], h[kmin, cols], np.asarray(t)[kmin])


@dataclass
class FrfPeaks:
    """Per row: the largest magnitude ``abs`` of its receptances, at the frequency ``omega``
    (rad/s) and the input ``input`` (index; the first such pair, frequencies first)."""

    abs: np.ndarray
    omega: np.ndarray
    input: np.ndarray


def frf_peaks_of(frf: np.ndarray, omega: np.ndarray) -> FrfPeaks:
    """The :class:`FrfPeaks` of ``frf`` (``n_omega x n_rows x n_inputs``) at ``omega``."""
    h = np.abs(np.asarray(frf))
    nw, rows, ni = h.shape
    if nw == 0 or ni == 0:
        z = np.zeros(rows)
        return FrfPeaks(z, z.copy(), np.zeros(rows, dtype=int))
    flat = h.transpose(1, 0, 2).reshape(rows, nw * ni)
    k = np.argmax(flat, axis=1)
    return FrfPeaks(flat[np.arange(rows), k], np.asarray(omega, dtype=float)[k // ni], k % ni)


@dataclass
class Recovered:
    """One recovery matrix of one superelement and what it recovered.

    Attributes:
        part: the superelement's name; ``name``: the recovery's name (``recovery.name``).
        of: the histories the column blocks act on.
        labels: one per recovered row.
        modes: ``n_rows x k``, the recovered mode shapes (empty without modes).
        history: ``n_samples x n_rows`` at the transient's instants ``t`` (empty without a
            transient response).
        t: the instants of ``history``.
        frf: ``n_omega x n_rows x n_inputs``, complex: the recovered quantities per unit
            force at each input (empty without receptances).
        omega: the frequencies of ``frf`` (rad/s); ``inputs``: the names of its inputs.
    """

    part: str
    name: str
    of: tuple[str, ...]
    labels: list[str]
    modes: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    history: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    frf: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 0), dtype=complex))
    omega: np.ndarray = field(default_factory=lambda: np.zeros(0))
    inputs: list[str] = field(default_factory=list)

    @property
    def title(self) -> str:
        """``<part>.<name>``, the prefix of the recovered quantities' names."""
        return f"{self.part}.{self.name}"

    def peaks(self) -> Peaks:
        """The peaks of the transient history (:func:`peaks_of`)."""
        return peaks_of(self.history, self.t)

    def frf_peaks(self) -> FrfPeaks:
        """The peaks of the receptances (:func:`frf_peaks_of`)."""
        return frf_peaks_of(self.frf, self.omega)
