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
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import h5py
import numpy as np

from substruct.io.transient_hdf5 import ArrayReader

if TYPE_CHECKING:  # the writer is imported by every result write: the analysis only when used
    from substruct.analysis.frf.virtual_point import VptResult

__all__ = ["write_virtual_points", "read_virtual_points"]

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
