r"""The ``/recovery/`` group of a results file (docs/results.md): the responses recovered inside
superelements by their output transformation matrices (:mod:`substruct.run.recovered`).

One numbered group per matrix, ``/recovery/<i>/``, attributes ``part``, ``name``, ``of``
(the histories, comma-separated), and the datasets

==================  =====================================================================
``labels``          one per recovered row
``modes``           ``n_rows x k``: the recovered mode shapes (with ``/modes``)
``history``         ``n_samples x n_rows`` at ``/transient/t`` (with ``/transient``)
``peak_max``,       per row: the largest value and its first instant, the smallest and its
``peak_max_t``,     (with ``/transient``)
``peak_min``,
``peak_min_t``
``frf``             ``n_omega x n_rows x n_inputs``, complex: the recovered quantities per
                    unit force at each input (with ``/frf``), at ``omega`` (rad/s), for the
``omega``,          ``inputs`` (names); ``frf_peak``, ``frf_peak_omega``: per row the largest
``inputs``,         magnitude and its first frequency
``frf_peak``,
``frf_peak_omega``
==================  =====================================================================

:func:`read_recovery` reads it back through the result reader's checks.
"""

from __future__ import annotations

import h5py
import numpy as np

from substruct.io.transient_hdf5 import ArrayReader
from substruct.run.recovered import Recovered

__all__ = ["write_recovery", "read_recovery", "OF_NAMES"]

#: The histories a recovery acts on (``of``).
OF_NAMES = ("displacement", "velocity", "acceleration")


def write_recovery(g: h5py.Group, recovered: list[Recovered]) -> None:
    """Write each :class:`Recovered` into ``g/<i>`` (module docstring)."""
    for i, rec in enumerate(recovered):
        sub = g.create_group(str(i), track_order=True)
        sub.attrs["part"] = rec.part
        sub.attrs["name"] = rec.name
        sub.attrs["of"] = ",".join(rec.of)
        sub.create_dataset("labels", data=np.array(rec.labels, dtype=h5py.string_dtype()),
                           shape=(len(rec.labels),))
        if rec.modes.size:
            sub.create_dataset("modes", data=rec.modes)
        if rec.t.size:
            sub.create_dataset("history", data=np.asarray(rec.history, dtype=float))
            p = rec.peaks()
            for name, values in (("peak_max", p.max), ("peak_max_t", p.t_max),
                                 ("peak_min", p.min), ("peak_min_t", p.t_min)):
                sub.create_dataset(name, data=np.asarray(values, dtype=float))
        if rec.omega.size:
            sub.create_dataset("frf", data=np.asarray(rec.frf, dtype=complex))
            sub.create_dataset("omega", data=np.asarray(rec.omega, dtype=float))
            sub.create_dataset("inputs", data=np.array(rec.inputs, dtype=h5py.string_dtype()),
                               shape=(len(rec.inputs),))
            fp = rec.frf_peaks()
            sub.create_dataset("frf_peak", data=np.asarray(fp.abs, dtype=float))
            sub.create_dataset("frf_peak_omega", data=np.asarray(fp.omega, dtype=float))


def _text(value: object) -> str:
    return value.decode("utf-8", "replace") if isinstance(value, bytes) else str(value)


def read_recovery(rd: ArrayReader, groups: list[h5py.Group], k: int | None,
                  t: np.ndarray | None) -> list[Recovered]:
    """The :class:`Recovered` of the numbered groups ``groups`` (in order), checked: the
    attributes present, ``of`` a list of known histories, ``k`` columns of modes (the
    result's modes), one history row per instant of ``t`` (the transient's), one column per
    label, finite values.  The peaks are recomputed from the history.

    Raises:
        ValueError: one line naming the dataset or attribute that breaks the layout.
    """
    out = []
    for g in groups:
        attrs = {str(key): g.attrs[key] for key in g.attrs if g.attrs.get_id(key).shape == ()}
        for key in ("part", "name", "of"):
            if key not in attrs:
                raise ValueError(f"{g.name} has no attribute {key!r}")
        of = tuple(_text(attrs["of"]).split(","))
        if not of or any(s not in OF_NAMES for s in of) or len(set(of)) != len(of):
            raise ValueError(f"{g.name} attribute of is {_text(attrs['of'])[:60]!r}, not a "
                             f"list of {', '.join(OF_NAMES)}")
        labels = rd.strings(g, "labels")
        rec = Recovered(_text(attrs["part"]), _text(attrs["name"]), of, labels)
        if "modes" in g:
            if k is None:
                raise ValueError(f"{g.name}/modes without /modes")
            rec.modes = rd.array(g, "modes", "fc", 2, (len(labels), k))
        if "history" in g:
            if t is None:
                raise ValueError(f"{g.name}/history without /transient")
            rec.history = rd.array(g, "history", "f", 2, (len(t), len(labels)))
            rec.t = np.asarray(t)
        if "frf" in g:
            rec.omega = rd.array(g, "omega", "f", 1)
            rec.inputs = rd.strings(g, "inputs")
            rec.frf = rd.array(g, "frf", "c", 3, (len(rec.omega), len(labels),
                                                  len(rec.inputs)))
        for name in ("modes", "history", "frf", "omega"):
            if not np.all(np.isfinite(getattr(rec, name))):
                raise ValueError(f"{g.name}/{name} holds values that are not finite")
        out.append(rec)
    return out
