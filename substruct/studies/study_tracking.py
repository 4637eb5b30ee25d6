r"""Modes followed through a one-parameter study (``collect: track``).

The samples of a grid of one parameter (or a zip, row after row) are consecutive values of the
parameter; the modes of neighbouring samples are paired by the assignment of least total
:math:`1 - \mathrm{MAC}` (:func:`substruct.analysis.modes.tracking.track_modes`, the Hungarian
algorithm on the MAC of the shapes; the relative frequency difference, weighted by
:data:`FREQUENCY_WEIGHT`, breaks ties between modes of the same shape), so a track keeps one
mode's identity where frequencies cross.  Crossings (two tracks exchange their frequency
order) and veerings (neighbouring tracks approach to a least gap without crossing while their
shapes exchange) are marked by sample.  The frequencies, damping ratios and derivatives
collected per sample are reordered track by track.

Tracking needs every sample: a failed sample, or samples with different numbers of
coordinates or of modes, leave the study without tracks and a note saying why.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from substruct.analysis.modes.tracking import track_modes

__all__ = ["FREQUENCY_WEIGHT", "TrackedStudy", "track_study"]

#: ``w_f`` of the pairing cost: shape first, frequency to break ties.
FREQUENCY_WEIGHT = 0.1


@dataclass
class TrackedStudy:
    """The modes of a one-parameter study followed by shape.

    Attributes:
        parameter: the parameter's name; ``values`` its value at each sample.
        order: ``(samples, modes)``: ``order[s, t]`` the mode (ascending frequency) of sample
            ``s`` on track ``t`` (track ``t`` starts as mode ``t`` of the first sample).
        frequency: ``(samples, modes)`` natural frequency (rad/s) along each track.
        mac: ``(samples - 1, modes)`` MAC of each track between neighbouring samples.
        crossings, veerings: ``(sample, track, track)``: after ``sample`` the two tracks have
            exchanged their order; at ``sample`` the two approach closest without crossing.
        tracked: other per-mode arrays reordered along the tracks (``damping_ratio``,
            ``frequency_derivative``).
    """

    parameter: str
    values: np.ndarray
    order: np.ndarray
    frequency: np.ndarray
    mac: np.ndarray
    crossings: list[tuple[int, int, int]]
    veerings: list[tuple[int, int, int]]
    tracked: dict[str, np.ndarray] = field(default_factory=dict)


def track_study(parameter: str, values: np.ndarray, frequency: np.ndarray,
                shapes: list[np.ndarray | None], others: dict[str, np.ndarray]
                ) -> TrackedStudy | str:
    """Track the modes of the samples (module docstring); a one-line note instead when they
    cannot be tracked."""
    if any(p is None for p in shapes) or not np.all(np.isfinite(frequency)):
        return "not tracked: a sample failed or has fewer modes than collected"
    shaped = [np.asarray(p) for p in shapes if p is not None]
    if len({p.shape for p in shaped}) > 1:
        return ("not tracked: the samples' modes have different numbers of coordinates "
                "(the parameter changes the model's size)")
    t = track_modes(list(frequency), shaped, frequency_weight=FREQUENCY_WEIGHT)
    tracked = {name: np.take_along_axis(np.asarray(a), t.order, axis=1)
               for name, a in others.items()}
    return TrackedStudy(parameter=parameter, values=np.asarray(values, dtype=float),
                        order=t.order, frequency=t.frequency, mac=t.mac,
                        crossings=list(t.crossings), veerings=list(t.veerings),
                        tracked=tracked)
