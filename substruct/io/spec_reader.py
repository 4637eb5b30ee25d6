"""Reading ``/random`` and ``/srs`` back from a result file (the layout of
:mod:`substruct.io.spec_hdf5`), trusting nothing in it.

Every dataset goes through the result reader's checks (rank, kind, declared size and shape
before it is read, hard links only); the parts must agree (one PSD column per input, a
``q x q`` response matrix per frequency for ``q`` outputs, one spectrum row per output on the
``fn`` grid), and every number must be finite, the frequencies positive and increasing, the
RMS values and the spectra ``>= 0``: the writer stores nothing else, so anything else is a
corrupt file, a one-line :class:`ValueError` naming the dataset.
"""

from __future__ import annotations

import math

import h5py
import numpy as np

from substruct.io.transient_hdf5 import ArrayReader
from substruct.run.spec_results import RandomResponse, ShockSpectra

__all__ = ["read_random", "read_srs"]


def _finite(g: h5py.Group, name: str, a: np.ndarray, nonnegative: bool = False
            ) -> np.ndarray:
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{g.name}/{name} holds values that are not finite")
    if nonnegative and a.size and float(np.min(a)) < 0:
        raise ValueError(f"{g.name}/{name} holds the negative value {float(np.min(a))}")
    return a


def _grid(rd: ArrayReader, g: h5py.Group, name: str) -> np.ndarray:
    """A frequency grid in Hz: finite, positive, increasing."""
    f = _finite(g, name, rd.array(g, name, "f", 1))
    if f.size and (float(f.min()) <= 0 or np.any(np.diff(f) <= 0)):
        raise ValueError(f"{g.name}/{name} is not a grid of increasing positive frequencies")
    return f


def _attr_number(g: h5py.Group, key: str, default: float | None = None) -> float:
    if key not in g.attrs:
        if default is None:
            raise ValueError(f"damaged or incomplete: {g.name} has no attribute {key}")
        return default
    value = float(g.attrs[key])
    if not math.isfinite(value):
        raise ValueError(f"{g.name} attribute {key} is not finite, got {value}")
    return value


def _attr_text(g: h5py.Group, key: str, default: str) -> str:
    value = g.attrs.get(key, default)
    return value.decode("utf-8", "replace") if isinstance(value, bytes) else str(value)


def read_random(rd: ArrayReader, g: h5py.Group) -> RandomResponse:
    """``/random`` (:func:`substruct.io.spec_hdf5.write_random`).

    Raises:
        ValueError: a part missing, of the wrong shape, or holding a value that is not finite.
    """
    f = _grid(rd, g, "f")
    outputs, inputs = rd.strings(g, "outputs"), rd.strings(g, "inputs")
    n, q, p = len(f), len(outputs), len(inputs)
    input_psd = _finite(g, "input_psd", rd.array(g, "input_psd", "f", 2, (n, p)),
                        nonnegative=True)
    input_csd = None
    if g.get("input_csd", getlink=True) is not None:
        input_csd = _finite(g, "input_csd", rd.array(g, "input_csd", "fc", 3, (n, p, p)))
    psd = _finite(g, "psd", rd.array(g, "psd", "fc", 3, (n, q, q)))
    rms = _finite(g, "rms", rd.array(g, "rms", "f", 1, (q,)), nonnegative=True)
    quantity = _attr_text(g, "quantity", "")
    if quantity not in ("displacement", "velocity", "acceleration"):
        raise ValueError(f"{g.name} attribute quantity is {quantity!r}, not displacement, "
                         "velocity or acceleration")
    agreement: dict[str, float] = {}
    if g.get("agreement", getlink=True) is not None:
        a = g["agreement"]
        if not isinstance(a, h5py.Group):
            raise ValueError(f"{g.name}/agreement is not a group")
        agreement = {str(k): _attr_number(a, k) for k in a.attrs}
    inputs_kind = _attr_text(g, "inputs_kind", "")
    if inputs_kind not in ("", "force", "base acceleration"):
        raise ValueError(f"{g.name} attribute inputs_kind is {inputs_kind!r}, not force or "
                         "base acceleration")
    return RandomResponse(f=f, outputs=outputs, inputs=inputs, quantity=quantity,
                          input_psd=input_psd, psd=psd, rms=rms,
                          method=_attr_text(g, "method", ""), agreement=agreement,
                          tolerance=_attr_number(g, "tolerance", 0.0),
                          input_csd=input_csd, base=inputs_kind == "base acceleration")


def read_srs(rd: ArrayReader, g: h5py.Group) -> ShockSpectra:
    """``/srs`` (:func:`substruct.io.spec_hdf5.write_srs`).

    Raises:
        ValueError: a part missing, of the wrong shape, a value that is not finite or is
            negative, or a damping ratio outside (0, 1).
    """
    fn = _grid(rd, g, "fn")
    outputs = rd.strings(g, "outputs")
    spectra = {name: _finite(g, name, rd.array(g, name, "f", 2, (len(outputs), len(fn))),
                             nonnegative=True)
               for name in ("pos", "neg", "maxabs", "pv")}
    zeta, dt = _attr_number(g, "zeta"), _attr_number(g, "dt")
    if not 0 < zeta < 1 or not dt > 0:
        raise ValueError(f"{g.name}: damping ratio {zeta} not in (0, 1) or time step {dt} "
                         "not > 0")
    return ShockSpectra(fn=fn, zeta=zeta, outputs=outputs, dt=dt, **spectra)
