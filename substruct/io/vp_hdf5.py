r"""The ``/virtual_points/`` group of a results file: the consistency indicators of every part
transformed to virtual points (:func:`substruct.analysis.frf.virtual_point.consistency`),
frequency functions on ``/frf/omega``.

One numbered group per part, ``/virtual_points/<i>/``, attribute ``part``, and the datasets

=====================  =================================================================
``points``             the virtual points' names
``overall_u``          ``n_points x n_omega``: sensor consistency :math:`\rho_u`
``overall_f``          ``n_points x n_omega``: impact consistency :math:`\rho_f`
``sensors``            the sensor channels' names
``specific_u``         ``n_sensors x n_omega``: :math:`\rho_{u,i}`
``impacts``            the impact channels' names
``specific_f``         ``n_impacts x n_omega``: :math:`\rho_{f,j}`
=====================  =================================================================

and ``/virtual_points/monte_carlo`` the coupled result's sensitivity to noise
(:func:`write_monte_carlo`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import h5py
import numpy as np

from substruct.io.transient_hdf5 import ArrayReader

if TYPE_CHECKING:  # the writer is imported by every result write: the analysis only when used
    from substruct.analysis.frf.virtual_point import VptResult
    from substruct.analysis.frf.vp_noise import MonteCarloResult

__all__ = ["write_virtual_points", "read_virtual_points", "write_monte_carlo",
           "read_monte_carlo"]

_STR = h5py.string_dtype("utf-8")


def _table(g: h5py.Group, names_key: str, values_key: str, data: dict[str, np.ndarray]
           ) -> None:
    names = list(data)
    g.create_dataset(names_key, data=np.array(names, dtype=object), dtype=_STR,
                     shape=(len(names),))
    values = np.array([np.asarray(data[n], dtype=float) for n in names]) if names else \
        np.zeros((0, 0))
    ds = g.create_dataset(values_key, data=values)
    ds.attrs["units"] = "1"


def write_virtual_points(group: h5py.Group, parts: dict[str, VptResult]) -> None:
    """Write the indicators of each part (module docstring) under ``group``."""
    for i, (part, ind) in enumerate(parts.items()):
        g = group.create_group(str(i), track_order=True)
        g.attrs["part"] = str(part)
        _table(g, "points", "overall_u", ind.overall_u)
        g.create_dataset("overall_f", data=np.array(
            [np.asarray(ind.overall_f[n], dtype=float) for n in ind.overall_u]))
        _table(g, "sensors", "specific_u", ind.specific_u)
        _table(g, "impacts", "specific_f", ind.specific_f)


def read_virtual_points(rd: ArrayReader, groups: list[h5py.Group], k: int
                        ) -> dict[str, VptResult]:
    """The indicators written by :func:`write_virtual_points` in the numbered ``groups`` (in
    order), checked: one row per name, ``k`` frequencies (those of ``/frf``), values finite
    and in ``[0, 1]`` up to round-off.

    Raises:
        ValueError: a dataset of the wrong shape, values outside that range or not finite, a
            part named twice.
    """
    from substruct.analysis.frf.virtual_point import VptResult

    out: dict[str, VptResult] = {}
    for g in groups:
        part = g.attrs.get("part")
        if not isinstance(part, (str, bytes)):
            raise ValueError(f"{g.name} has no attribute part")
        name = part.decode("utf-8", "replace") if isinstance(part, bytes) else part
        if name in out:
            raise ValueError(f"{g.name}: part {name!r} twice in /virtual_points")
        tables = []
        for names_key, keys in (("points", ("overall_u", "overall_f")),
                                ("sensors", ("specific_u",)), ("impacts", ("specific_f",))):
            names = rd.strings(g, names_key)
            for key in keys:
                v = rd.array(g, key, "f", 2, (len(names), k if names else None))
                if not np.all(np.isfinite(v)) or np.any(v < -1e-9) or np.any(v > 1 + 1e-9):
                    raise ValueError(f"{g.name}/{key} holds values that are not consistency "
                                     f"indicators (finite, in [0, 1])")
                tables.append(dict(zip(names, v)))
        out[name] = VptResult(*tables)
    return out


def write_monte_carlo(group: h5py.Group, mc: MonteCarloResult) -> None:
    """The Monte Carlo study (:mod:`substruct.analysis.frf.vp_noise`) under ``group``
    (``/virtual_points/monte_carlo``): attributes ``level``, ``samples``, ``seed``; datasets
    ``outputs``, ``inputs``, ``percentiles``, ``nominal`` and ``mean`` (complex), ``std``
    (frequencies x outputs x inputs), ``bands`` (percentiles x frequencies x outputs x inputs,
    of the magnitude)."""
    group.attrs["level"] = float(mc.level)
    group.attrs["samples"] = int(mc.samples)
    group.attrs["seed"] = int(mc.seed)
    for key in ("outputs", "inputs"):
        names = list(getattr(mc, key))
        group.create_dataset(key, data=np.array(names, dtype=object), dtype=_STR,
                             shape=(len(names),))
    group.create_dataset("percentiles", data=np.asarray(mc.percentiles, dtype=float))
    for key in ("nominal", "mean", "std", "bands"):
        group.create_dataset(key, data=getattr(mc, key))


def read_monte_carlo(rd: ArrayReader, g: h5py.Group, omega: np.ndarray) -> MonteCarloResult:
    """The study written by :func:`write_monte_carlo`, checked: shapes that agree with the
    names and the ``k`` frequencies of ``/frf``, values finite, spreads and bands not negative.

    Raises:
        ValueError: as above, or an attribute missing or of the wrong kind.
    """
    from substruct.analysis.frf.vp_noise import MAX_SAMPLES, MonteCarloResult

    vals = []
    for key, kind in (("level", float), ("samples", int), ("seed", int)):
        v = g.attrs.get(key)
        if not isinstance(v, (np.integer, np.floating, int, float)) or isinstance(v, bool) \
                or (kind is int and not isinstance(v, (np.integer, int))):
            raise ValueError(f"{g.name} has no {kind.__name__} attribute {key}")
        vals.append(kind(v))
    level, samples, seed = vals
    if not (np.isfinite(level) and level >= 0 and 2 <= samples <= MAX_SAMPLES and seed >= 0):
        raise ValueError(f"{g.name}: level, samples or seed out of range, got "
                         f"{[level, samples, seed]}")
    outs, ins = rd.strings(g, "outputs"), rd.strings(g, "inputs")
    q = rd.array(g, "percentiles", "f", 1, (None,))
    shape = (len(omega), len(outs), len(ins))
    arrays = {key: rd.array(g, key, kinds, 3, shape) for key, kinds in
              (("nominal", "c"), ("mean", "c"), ("std", "f"))}
    bands = rd.array(g, "bands", "f", 4, (len(q), *shape))
    for key, v in [*arrays.items(), ("bands", bands), ("percentiles", q)]:
        if not np.all(np.isfinite(v)):
            raise ValueError(f"{g.name}/{key} holds values that are not finite")
    if np.any(arrays["std"] < 0) or np.any(bands < 0) or np.any((q < 0) | (q > 100)):
        raise ValueError(f"{g.name}: a negative spread or band, or a percentile outside "
                         f"[0, 100]")
    return MonteCarloResult(np.asarray(omega, dtype=float), outs, ins, level, int(samples),
                            int(seed),
                            arrays["nominal"], arrays["mean"], arrays["std"],
                            tuple(float(x) for x in q), bands)
