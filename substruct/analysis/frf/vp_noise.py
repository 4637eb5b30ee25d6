r"""The coupled result's sensitivity to noise in the measured receptances: Monte Carlo.

Every measured receptance (a part's channel FRFs, sensors x impacts) is perturbed by relative
complex Gaussian noise of level :math:`\varepsilon`,

.. math::  \tilde Y_{ij}(\omega) = Y_{ij}(\omega)\,\big(1 + \varepsilon\,
           (\xi + \mathrm i\,\eta)/\sqrt 2\big), \qquad \xi, \eta \sim N(0, 1)
           \text{ independent},

so that :math:`E|\tilde Y_{ij} - Y_{ij}|^2 = \varepsilon^2 |Y_{ij}|^2`; each sample is
transformed to the virtual points (:math:`T_u \tilde Y T_f^T`) and coupled exactly as the
nominal (:func:`~substruct.analysis.frf.vp_coupling.couple_virtual_points`, with the same
regularisation and weakening).  Over :math:`N` samples the chosen coupled receptances
:math:`Y_c^{(k)}` give the mean, the standard deviation of the complex value

.. math::  s = \Big(\frac{1}{N-1} \sum_k |Y_c^{(k)} - \bar Y_c|^2\Big)^{1/2},

and percentile bands of the magnitude :math:`|Y_c^{(k)}|` (entry by entry and frequency by
frequency).  Sample ``k`` draws its noise from ``numpy.random.default_rng([seed, k])``: a
sample's numbers do not depend on which process runs it or in what order, so a ``map`` that
runs the samples as tasks (the Dask study backend's ``Session.map``) gives the same result bit
for bit as the loop in process.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from substruct.analysis.frf.virtual_point import VirtualPointTransform
from substruct.analysis.frf.vp_coupling import Regularisation, VpPart, couple_virtual_points
from substruct.analysis.frf.vp_reduction import InterfaceReduction
from substruct.linalg.task_runner import IN_PROCESS, TaskMap

__all__ = ["sample_task", "MeasuredPart", "NoiseStudy", "MonteCarloResult", "add_relative_noise",
           "coupled_sample", "monte_carlo_coupling", "MAX_SAMPLES"]

#: The largest number of samples a study may ask for.
MAX_SAMPLES = 100_000


@dataclass(frozen=True)
class MeasuredPart:
    """A part known by measured receptances.

    Attributes:
        name: the part's name (its coupled labels are ``"<name>@<label>"``).
        omega: circular frequencies (rad/s).
        Y: the measured receptances, ``(n_omega, rows, columns)``: sensors x impacts of
            ``vpt`` when it is given, else already at the part's coordinates.
        vpt: the virtual point transformation, or ``None``.
        out_labels, in_labels: the coordinates (required when ``vpt`` is ``None``; with it,
            they rename ``vpt``'s labels, one for one, when given).
        noisy: whether the noise is applied to this part (a finite-element part is not).
    """

    name: str
    omega: np.ndarray
    Y: np.ndarray
    vpt: VirtualPointTransform | None = None
    out_labels: tuple[str, ...] = ()
    in_labels: tuple[str, ...] = ()
    noisy: bool = True

    def part(self, Y: np.ndarray) -> VpPart:
        """The part at its coordinates from receptances ``Y`` (transformed if ``vpt``)."""
        if self.vpt is not None:
            return VpPart(self.name, self.omega, list(self.out_labels or self.vpt.out_labels),
                          list(self.in_labels or self.vpt.in_labels), self.vpt.apply(Y))
        return VpPart(self.name, self.omega, list(self.out_labels), list(self.in_labels), Y)


@dataclass(frozen=True)
class NoiseStudy:
    """The coupling of a Monte Carlo study and what it keeps (module docstring).

    Attributes:
        parts: the measured parts.
        pairs: the joined coordinates, as for ``couple_virtual_points``.
        outputs, inputs: the coupled receptances kept (stacked labels).
        level: the relative noise level :math:`\\varepsilon` (``>= 0``).
        reg, weaken_compatibility, weaken_equilibrium, length, reduction: as for
            ``couple_virtual_points``.
    """

    parts: tuple[MeasuredPart, ...]
    pairs: tuple[tuple[str, str], ...]
    outputs: tuple[str, ...]
    inputs: tuple[str, ...]
    level: float
    reg: Regularisation = Regularisation()
    weaken_compatibility: tuple[str, ...] = ()
    weaken_equilibrium: tuple[str, ...] = ()
    length: float = 1.0
    reduction: InterfaceReduction | None = None

    def __post_init__(self) -> None:
        if not (np.isfinite(self.level) and self.level >= 0):
            raise ValueError(f"the noise level must be finite and >= 0, got {self.level!r}")


def add_relative_noise(Y: np.ndarray, level: float, rng: np.random.Generator) -> np.ndarray:
    r""":math:`Y (1 + \varepsilon (\xi + i \eta)/\sqrt 2)` entry by entry (module docstring);
    ``level == 0`` returns ``Y`` unchanged (no draw)."""
    if level == 0:
        return Y
    xi = rng.standard_normal(Y.shape)
    eta = rng.standard_normal(Y.shape)
    return Y * (1 + level * (xi + 1j * eta) / np.sqrt(2))


def _coupled(study: NoiseStudy, parts: list[VpPart]) -> np.ndarray:
    res = couple_virtual_points(parts, study.pairs, study.reg, study.weaken_compatibility,
                                study.weaken_equilibrium, length=study.length, check=False,
                                reduction=study.reduction)
    return res.part.block(list(study.outputs), list(study.inputs))


def coupled_sample(study: NoiseStudy, seed: int, k: int) -> np.ndarray:
    """Sample ``k``: the chosen coupled receptances from noisy measurements drawn from
    ``default_rng([seed, k])`` (the parts in order, each ``Y`` one draw)."""
    rng = np.random.default_rng([seed, k])
    parts = [m.part(add_relative_noise(m.Y, study.level, rng) if m.noisy else m.Y)
             for m in study.parts]
    return _coupled(study, parts)


def sample_task(item: tuple[NoiseStudy, int, int]) -> np.ndarray:
    """:func:`coupled_sample` of ``(study, seed, k)``: one task of a map."""
    return coupled_sample(*item)


@dataclass(frozen=True)
class MonteCarloResult:
    """The nominal and the statistics over the samples, each ``(n_omega, outputs, inputs)``
    (``bands``: ``(len(percentiles), n_omega, outputs, inputs)``, of the magnitude)."""

    omega: np.ndarray
    outputs: list[str]
    inputs: list[str]
    level: float
    samples: int
    seed: int
    nominal: np.ndarray
    mean: np.ndarray
    std: np.ndarray
    percentiles: tuple[float, ...]
    bands: np.ndarray

    def relative_spread(self) -> np.ndarray:
        """``||std||_F / ||nominal||_F`` per frequency."""
        den = np.linalg.norm(self.nominal, axis=(1, 2))
        return np.linalg.norm(self.std, axis=(1, 2)) / np.where(den > 0, den, 1.0)


def monte_carlo_coupling(study: NoiseStudy, samples: int, seed: int,
                         percentiles: Sequence[float] = (5.0, 50.0, 95.0),
                         map: TaskMap | None = None) -> MonteCarloResult:
    """Run ``samples`` noisy couplings of ``study`` (module docstring) through ``map``
    (``map(function, items) -> results`` in order, in process by default; the Dask study
    backend's ``Session.map`` runs each sample as a task) and reduce them.

    Raises:
        ValueError: fewer than 2 or more than :data:`MAX_SAMPLES` samples, a negative seed,
            a percentile outside [0, 100].
    """
    if isinstance(samples, bool) or not 2 <= samples <= MAX_SAMPLES:
        raise ValueError(f"samples must be 2 to {MAX_SAMPLES}, got {samples!r}")
    if isinstance(seed, bool) or seed < 0:
        raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
    q = tuple(float(p) for p in percentiles)
    if any(not 0 <= p <= 100 for p in q):
        raise ValueError(f"percentiles must be in [0, 100], got {list(q)}")
    nominal = _coupled(study, [m.part(m.Y) for m in study.parts])
    run = map if map is not None else IN_PROCESS.map
    draws = run(sample_task, [(study, seed, k) for k in range(samples)])
    stack = np.stack(draws)
    dev = stack - nominal  # about the nominal: exactly 0 without noise
    dmean = dev.mean(axis=0)
    mean = nominal + dmean
    std = np.sqrt((np.abs(dev - dmean) ** 2).sum(axis=0) / (samples - 1))
    bands = np.percentile(np.abs(stack), q, axis=0) if q else np.zeros((0, *mean.shape))
    return MonteCarloResult(np.asarray(study.parts[0].omega, dtype=float), list(study.outputs),
                            list(study.inputs), study.level, samples, seed, nominal, mean,
                            std, q, bands)
