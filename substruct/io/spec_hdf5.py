"""HDF5 groups of the specification analyses (:mod:`substruct.run.spec_results`)::

    /random    f (Hz), outputs, inputs, input_psd (n_f x p), input_csd (n_f x p x p, complex,
               only with correlated inputs), psd (n_f x q x q, complex),
               rms (q); attrs quantity, method, tolerance, three_sigma_exceedance,
               inputs_kind (force or base acceleration);
               agreement/ (attrs: check -> relative difference)
    /base_frf  omega (rad/s), f (Hz), outputs, inputs, transmissibility (n_w x q x p,
               complex: output motion per base acceleration); attrs quantity, per, method,
               tolerance; agreement/ (attrs: check -> relative difference)
    /srs       fn (Hz), outputs, pos, neg, maxabs, pv (n_outputs x n_fn); attrs zeta, Q, dt
"""

from __future__ import annotations

import h5py
import numpy as np

from substruct.run.spec_results import (
    THREE_SIGMA_EXCEEDANCE,
    BaseFrf,
    RandomResponse,
    ShockSpectra,
)

__all__ = ["write_random", "write_base_frf", "write_srs"]


def _strings(group: h5py.Group, name: str, values: list[str]) -> None:
    group.create_dataset(name, data=np.array(values, dtype=object),
                         dtype=h5py.string_dtype())


def write_random(g: h5py.Group, r: RandomResponse) -> None:
    """Write a random response to the group ``g`` (module docstring)."""
    g.create_dataset("f", data=r.f).attrs["units"] = "Hz"
    _strings(g, "outputs", r.outputs)
    _strings(g, "inputs", r.inputs)
    g.create_dataset("input_psd", data=r.input_psd)
    if r.input_csd is not None:
        g.create_dataset("input_csd", data=r.input_csd)
    g.create_dataset("psd", data=r.psd)
    g.create_dataset("rms", data=r.rms)
    g.attrs.update({"quantity": r.quantity, "method": r.method, "tolerance": r.tolerance,
                    "three_sigma_exceedance": THREE_SIGMA_EXCEEDANCE,
                    "inputs_kind": "base acceleration" if r.base else "force"})
    agreement = g.create_group("agreement")
    for key, value in r.agreement.items():
        agreement.attrs[key] = float(value)


def write_base_frf(g: h5py.Group, r: BaseFrf) -> None:
    """Write the transmissibilities of ``analysis.base_frf`` to the group ``g`` (module
    docstring)."""
    g.create_dataset("omega", data=r.omega).attrs["units"] = "rad/s"
    g.create_dataset("f", data=r.omega / (2 * np.pi)).attrs["units"] = "Hz"
    _strings(g, "outputs", r.outputs)
    _strings(g, "inputs", r.inputs)
    g.create_dataset("transmissibility", data=r.T)
    g.attrs.update({"quantity": r.quantity, "per": "acceleration", "method": r.method,
                    "tolerance": r.tolerance})
    agreement = g.create_group("agreement")
    for key, value in r.agreement.items():
        agreement.attrs[key] = float(value)


def write_srs(g: h5py.Group, s: ShockSpectra) -> None:
    """Write shock response spectra to the group ``g`` (module docstring)."""
    g.create_dataset("fn", data=s.fn).attrs["units"] = "Hz"
    _strings(g, "outputs", s.outputs)
    for name in ("pos", "neg", "maxabs", "pv"):
        g.create_dataset(name, data=getattr(s, name))
    g.attrs.update({"zeta": s.zeta, "Q": 1 / (2 * s.zeta), "dt": s.dt})
