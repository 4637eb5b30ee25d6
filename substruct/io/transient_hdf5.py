r"""The ``/transient/`` group of a results file (docs/results.md): the time histories of
:class:`substruct.analysis.transient.results.Transient`.

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
``snapshot_t``, ``snapshots`` the full displacement every k steps (empty if not asked)
``base_motion``               ``n_samples x 3``: ground :math:`g, \dot g, \ddot g`     per column
                              (only with a moving ground)
``base_influence``            ``n_outputs``: :math:`O r`, the influence vector
``relative_displacement``     ``displacement - base_motion[:, 0] base_influence``     ``length``
``relative_velocity``,        likewise with :math:`\dot g`, :math:`\ddot g`           ...
``relative_acceleration``
============================  ======================================================  =========

Attributes: ``method``, ``integrator``, ``rho_inf``, ``dt``, ``drift``, ``tolerance``,
``solver``, ``agreement_<form>``.  Units are those of the case (``units`` of the file root).

:func:`read_transient` reads the group back (through the checks of
:mod:`substruct.io.result_reader`), so that a result read back equals the one written.
"""

from __future__ import annotations

from typing import Protocol

import h5py
import numpy as np

from substruct.analysis.results import DEFAULT_TOLERANCE
from substruct.analysis.transient.results import ENERGY_LABELS, Transient
from substruct.io.blocks import BLOCK_BYTES, CHUNK_BYTES, DatasetSink, write_blocks

__all__ = ["write_transient", "read_transient", "ArrayReader"]


def _strings(g: h5py.Group, name: str, values: list[str]) -> None:
    g.create_dataset(name, data=np.array([str(v) for v in values], dtype=h5py.string_dtype()))


def write_transient(g: h5py.Group, tr: Transient, *, block_bytes: int = BLOCK_BYTES,
                    chunk_bytes: int = CHUNK_BYTES, compression: str | None = None,
                    streamed: DatasetSink | None = None) -> None:
    """Write ``tr`` into the group ``g`` (module docstring); the snapshots of the whole field
    as a chunked dataset written ``block_bytes`` at a time
    (:func:`substruct.io.blocks.write_blocks`), or, when the run already wrote them into
    ``streamed`` as it recorded them (``tr.snapshots`` read from that sink), that dataset
    moved into place (an HDF5 link: no copy; the same dataset either way)."""
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
    g.create_dataset("snapshot_t", data=np.asarray(tr.snapshot_t, dtype=float))
    written = getattr(tr.snapshots, "sink", None)  # the sink the run wrote them to, if any
    if isinstance(written, DatasetSink) and written is streamed:
        g.file.move(written.dataset.name, f"{g.name}/snapshots")
    else:
        write_blocks(g, "snapshots", np.asarray(tr.snapshots, dtype=float),
                     block_bytes=block_bytes, chunk_bytes=chunk_bytes, compression=compression)
    if tr.base_motion.size:
        d = g.create_dataset("base_motion", data=np.asarray(tr.base_motion, dtype=float))
        d.attrs["units"] = "length, length/time, length/time^2"
        d.attrs["columns"] = "displacement, velocity, acceleration"
        g.create_dataset("base_influence", data=np.asarray(tr.base_influence, dtype=float))
        for name in ("displacement", "velocity", "acceleration"):
            d = g.create_dataset(f"relative_{name}", data=tr.relative(name))
            d.attrs["units"] = units[name]


class ArrayReader(Protocol):
    """What :func:`read_transient` needs of the result reader
    (:mod:`substruct.io.result_reader`): datasets checked for rank, kind, declared size and
    shape before they are read, through hard links only."""

    def array(self, g: h5py.Group, name: str, kinds: str, ndim: int,
              shape: tuple[int | None, ...] | None = None) -> np.ndarray:
        """The dataset ``g/name`` (``kinds``: numpy kind letters, ``s`` for strings)."""
        ...

    def strings(self, g: h5py.Group, name: str, count: int | None = None) -> list[str]:
        """The 1-D string dataset ``g/name``."""
        ...


def _text(value: object) -> str:
    return value.decode("utf-8", "replace") if isinstance(value, bytes) else str(value)


def _finite(g: h5py.Group, name: str, a: np.ndarray) -> np.ndarray:
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{g.name}/{name} holds values that are not finite")
    return a


def read_transient(rd: ArrayReader, g: h5py.Group, n: int) -> Transient:
    """The :class:`Transient` written by :func:`write_transient` into ``g``, checked: every
    history has one row per instant of ``t`` and one column per output, constraint row or
    energy label; ``t`` strictly increasing; every value finite; snapshots of the model's
    ``n`` coordinates.

    Raises:
        ValueError: one line naming the dataset or attribute that breaks the layout (the
            reader's own refusals, e.g. a declared size past its budget, pass through).
    """
    attrs = {str(k): g.attrs[k] for k in g.attrs if g.attrs.get_id(k).shape == ()}
    for key in ("method", "integrator", "dt"):
        if key not in attrs:
            raise ValueError(f"{g.name} has no attribute {key!r}")
    num = {}
    for key in ("rho_inf", "dt", "drift", "tolerance"):
        try:
            num[key] = float(attrs.get(key, DEFAULT_TOLERANCE if key == "tolerance" else 0.0))
        except (TypeError, ValueError):
            raise ValueError(f"{g.name} attribute {key} is not a number") from None
        if not np.isfinite(num[key]):
            raise ValueError(f"{g.name} attribute {key} is not finite")
    if not num["dt"] > 0:
        raise ValueError(f"{g.name} attribute dt is {num['dt']!r}, not > 0")
    t = _finite(g, "t", rd.array(g, "t", "f", 1))
    if np.any(np.diff(t) <= 0):
        raise ValueError(f"{g.name}/t is not strictly increasing")
    k = len(t)
    outputs = rd.strings(g, "outputs")
    labels = rd.strings(g, "constraint_labels")
    hist = {name: _finite(g, name, rd.array(g, name, "f", 2, (k, len(outputs))))
            for name in ("displacement", "velocity", "acceleration")}
    lam = _finite(g, "constraint_forces", rd.array(g, "constraint_forces", "f", 2,
                                                   (None, len(labels))))
    if lam.shape[0] not in (0, k):
        raise ValueError(f"{g.name}/constraint_forces has {lam.shape[0]} rows for {k} instants")
    rd.strings(g, "energy_labels", len(ENERGY_LABELS))
    snap_t, snaps = np.zeros(0), np.zeros((0, n))
    if "snapshot_t" in g or "snapshots" in g:
        snap_t = _finite(g, "snapshot_t", rd.array(g, "snapshot_t", "f", 1))
        snaps = _finite(g, "snapshots", rd.array(g, "snapshots", "f", 2,
                                                   (len(snap_t), n if len(snap_t) else None)))
    base, infl = np.zeros((0, 3)), np.zeros(0)
    if "base_motion" in g or "base_influence" in g:
        base = _finite(g, "base_motion", rd.array(g, "base_motion", "f", 2, (k, 3)))
        infl = _finite(g, "base_influence", rd.array(g, "base_influence", "f", 1,
                                                       (len(outputs),)))
    agreement = {key[len("agreement_"):]: float(v) for key, v in attrs.items()
                 if key.startswith("agreement_")}
    return Transient(
        method=_text(attrs["method"]), integrator=_text(attrs["integrator"]),
        rho_inf=num["rho_inf"], dt=num["dt"], t=t, outputs=outputs, **hist,
        constraint_labels=labels, constraint_forces=lam,
        constraint_residual=_finite(g, "constraint_residual",
                                    rd.array(g, "constraint_residual", "f", 1, (k,))),
        drift=num["drift"],
        energy=_finite(g, "energy", rd.array(g, "energy", "f", 2, (k, len(ENERGY_LABELS)))),
        snapshot_t=snap_t, snapshots=snaps, agreement=agreement,
        tolerance=num["tolerance"], solver=_text(attrs.get("solver", "")),
        base_motion=base, base_influence=infl)
