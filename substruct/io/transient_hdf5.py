r"""The ``/transient/`` group of a results file (docs/results.md): the time histories of
:class:`substruct.analysis.transient_results.Transient`.

============================  ======================================================  =========
dataset                       contents                                                units attr
============================  ======================================================  =========
``t``                         recorded instants                                       ``time``
``displacement``              ``n_samples x n_outputs`` at the output points          ``length``
``velocity``                  same                                                    ``length/time``
``acceleration``              same                                                    ``length/time^2``
``outputs``                   the output point names
``constraint_forces``         ``n_samples x m``: multipliers of :math:`Q^c = A^T\lambda` ``force``
``constraint_labels``         the constraint rows
``constraint_residual``       largest equilibrated :math:`|A q - b|` per sample
``energy``                    ``n_samples x 4``; ``energy_labels``                    ``energy``
``snapshot_t``, ``snapshots`` the full displacement every k steps (if asked)
============================  ======================================================  =========

Attributes: ``method``, ``integrator``, ``rho_inf``, ``dt``, ``drift``, ``tolerance``,
``solver``, ``agreement_<form>``.  Units are those of the case (``units`` of the file root).
"""

from __future__ import annotations

import h5py
import numpy as np

from substruct.analysis.transient_results import ENERGY_LABELS, Transient

__all__ = ["write_transient"]


def _strings(g: h5py.Group, name: str, values: list[str]) -> None:
    g.create_dataset(name, data=np.array([str(v) for v in values], dtype=h5py.string_dtype()))


def write_transient(g: h5py.Group, tr: Transient) -> None:
    """Write ``tr`` into the group ``g`` (module docstring)."""
    for key in ("method", "integrator", "solver"):
        g.attrs[key] = str(getattr(tr, key))
    for key in ("rho_inf", "dt", "drift", "tolerance"):
        g.attrs[key] = float(getattr(tr, key))
    for name, value in tr.agreement.items():
        g.attrs[f"agreement_{name}"] = float(value)
    units = {"t": "time", "displacement": "length", "velocity": "length/time",
             "acceleration": "length/time^2", "constraint_forces": "force",
             "constraint_residual": "", "energy": "energy"}
    for name, unit in units.items():
        d = g.create_dataset(name, data=np.asarray(getattr(tr, name), dtype=float))
        if unit:
            d.attrs["units"] = unit
    _strings(g, "outputs", tr.outputs)
    _strings(g, "constraint_labels", tr.constraint_labels)
    _strings(g, "energy_labels", list(ENERGY_LABELS))
    if tr.snapshots.size:
        g.create_dataset("snapshot_t", data=np.asarray(tr.snapshot_t, dtype=float))
        g.create_dataset("snapshots", data=np.asarray(tr.snapshots, dtype=float))
