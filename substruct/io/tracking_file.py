"""The ``/tracking`` group of a study file (:class:`~substruct.studies.study_tracking.
TrackedStudy`)::

    /tracking   attrs parameter, frequency_weight; values (samples), order, frequency
                (samples x modes, rad/s), mac (samples - 1 x modes), crossings, veerings
                (rows: sample, track, track), damping_ratio and frequency_derivative (samples x
                modes, along the tracks) when collected

A study whose modes could not be tracked has the root attribute ``tracking`` (why) instead.
"""

from __future__ import annotations

import h5py
import numpy as np

from substruct.studies.study_tracking import FREQUENCY_WEIGHT, TrackedStudy

__all__ = ["write_tracking", "read_tracking"]


def write_tracking(g: h5py.Group, t: TrackedStudy) -> None:
    """Write ``t`` into the group ``g`` (module docstring)."""
    g.attrs.update({"parameter": t.parameter, "frequency_weight": FREQUENCY_WEIGHT})
    for name in ("values", "order", "frequency", "mac"):
        g.create_dataset(name, data=getattr(t, name))
    for name in ("crossings", "veerings"):
        g.create_dataset(name, data=np.array(getattr(t, name), dtype=np.int64).reshape(-1, 3))
    for name, values in t.tracked.items():
        g.create_dataset(name, data=values)


def read_tracking(g: h5py.Group) -> TrackedStudy:
    """The :class:`TrackedStudy` of a ``/tracking`` group."""
    rows = (lambda name: [tuple(int(v) for v in r) for r in g[name][()]])
    return TrackedStudy(parameter=str(g.attrs["parameter"]), values=g["values"][()],
                        order=g["order"][()], frequency=g["frequency"][()], mac=g["mac"][()],
                        crossings=rows("crossings"), veerings=rows("veerings"),  # type: ignore
                        tracked={k: g[k][()] for k in ("damping_ratio",
                                                         "frequency_derivative") if k in g})
