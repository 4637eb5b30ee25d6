r"""The ``/tpa`` and ``/semm`` groups of a results file, on the frequencies of ``/frf/omega``.

``/tpa`` (:class:`~substruct.run.testlab_results.TpaResult`), attribute ``method``:

=====================  =================================================================
``interface``          the paths ``c`` (``n_c`` names)
``indicators``         the points whose operating responses found the forces
``targets``            the validation points (``n_t`` names)
``blocked_forces``     ``n_omega x n_c`` complex, :math:`f^{bl}`
``contributions``      ``n_omega x n_t x n_c`` complex, :math:`Y_{tc_j} f^{bl}_j`
``predicted``          ``n_omega x n_t`` complex, :math:`Y_{tc} f^{bl}`
``measured``           ``n_omega x n_t`` complex, the operating responses at the targets
``error``              ``n_omega``, relative validation error
``transmissibility``   operational TPA only: ``n_omega x n_t x n_i`` complex, :math:`T`
                       (attribute ``validation_condition``: the condition it predicts;
                       ``interface`` are then the indicators, ``blocked_forces`` their
                       responses under that condition)
=====================  =================================================================

``/semm`` (:class:`~substruct.run.testlab_results.SemmOutcome`): ``outputs``, ``inputs``, ``Y``
(``n_omega x n_o x n_i`` complex, the mixed receptance), ``measured_outputs``,
``measured_inputs``, ``boundary_outputs``, ``boundary_inputs``, ``coherence``
(``n_omega x m_o x m_i``), ``validation`` (``m_o x m_i``, 0/1), ``indicator`` (``n_omega``,
NaN where nothing validates); attribute ``form`` (``standard`` or ``extended``) and, with the
extended form and two or more measured outputs, ``channel_coherence`` (``n_omega x m_o``).
"""

from __future__ import annotations

import h5py
import numpy as np

from substruct.io.transient_hdf5 import ArrayReader
from substruct.run.testlab_results import SemmOutcome, TpaResult

__all__ = ["write_tpa", "read_tpa", "write_semm", "read_semm"]

_STR = h5py.string_dtype("utf-8")


def _names(g: h5py.Group, key: str, names: list[str]) -> None:
    g.create_dataset(key, data=np.array(names, dtype=object), dtype=_STR, shape=(len(names),))


def write_tpa(g: h5py.Group, r: TpaResult) -> None:
    """Write ``r`` into the group ``g`` (module docstring)."""
    g.attrs["method"] = r.method
    for key in ("interface", "indicators", "targets"):
        _names(g, key, getattr(r, key))
    for key, name in (("forces", "blocked_forces"), ("contributions", "contributions"),
                      ("predicted", "predicted"), ("measured", "measured"), ("error", "error")):
        g.create_dataset(name, data=getattr(r, key))
    if r.transmissibility is not None:
        g.create_dataset("transmissibility", data=r.transmissibility)
        g.attrs["validation_condition"] = int(r.validation_condition or 0)


def _finite(g: h5py.Group, name: str, a: np.ndarray) -> np.ndarray:
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{g.name}/{name} holds values that are not finite")
    return a


def read_tpa(rd: ArrayReader, g: h5py.Group, k: int) -> TpaResult:
    """The :class:`TpaResult` written by :func:`write_tpa`, checked: shapes agree with the
    names and ``k`` frequencies, values finite.

    Raises:
        ValueError: an attribute missing, a shape that disagrees, values not finite.
    """
    method = g.attrs.get("method")
    if not isinstance(method, (str, bytes)):
        raise ValueError(f"{g.name} has no attribute method")
    c, b, t = (rd.strings(g, key) for key in ("interface", "indicators", "targets"))

    def arr(name: str, kinds: str, shape: tuple[int, ...]) -> np.ndarray:
        return _finite(g, name, rd.array(g, name, kinds, len(shape), shape))

    T, held = None, None
    if "transmissibility" in g:
        T = arr("transmissibility", "fc", (k, len(t), len(b)))
        held_attr = g.attrs.get("validation_condition")
        if not isinstance(held_attr, (int, np.integer)) or int(held_attr) < 0:
            raise ValueError(f"{g.name} has a transmissibility but no validation_condition")
        held = int(held_attr)
    return TpaResult(
        method.decode() if isinstance(method, bytes) else method, c, b, t,
        transmissibility=T, validation_condition=held,
        forces=arr("blocked_forces", "fc", (k, len(c))),
        contributions=arr("contributions", "fc", (k, len(t), len(c))),
        predicted=arr("predicted", "fc", (k, len(t))),
        measured=arr("measured", "fc", (k, len(t))),
        error=arr("error", "f", (k,)))


def write_semm(g: h5py.Group, r: SemmOutcome) -> None:
    """Write ``r`` into the group ``g`` (module docstring)."""
    for key in ("outputs", "inputs", "measured_outputs", "measured_inputs", "boundary_outputs",
                "boundary_inputs"):
        _names(g, key, getattr(r, key))
    g.create_dataset("Y", data=r.Y)
    g.create_dataset("coherence", data=r.coherence)
    g.create_dataset("validation", data=r.validation.astype(np.uint8))
    g.create_dataset("indicator", data=r.indicator)
    g.attrs["form"] = r.form
    if r.channel_coherence is not None:
        g.create_dataset("channel_coherence", data=r.channel_coherence)


def read_semm(rd: ArrayReader, g: h5py.Group, k: int) -> SemmOutcome:
    """The :class:`SemmOutcome` written by :func:`write_semm`, checked: shapes agree with the
    names and ``k`` frequencies, values finite (the indicator may be NaN where nothing
    validates), coherences in ``[0, 1]``, boundary names among the measured ones.

    Raises:
        ValueError: a shape that disagrees, values out of range or not finite.
    """
    o, i, mo, mi, bo, bi = (rd.strings(g, key) for key in (
        "outputs", "inputs", "measured_outputs", "measured_inputs", "boundary_outputs",
        "boundary_inputs"))
    if not (set(bo) <= set(mo) and set(bi) <= set(mi) and set(mo) <= set(o)
            and set(mi) <= set(i)):
        raise ValueError(f"{g.name}: the boundary is not among the measured coordinates, or "
                         "those not among the model's")
    Y = _finite(g, "Y", rd.array(g, "Y", "fc", 3, (k, len(o), len(i))))
    coh = _finite(g, "coherence", rd.array(g, "coherence", "f", 3, (k, len(mo), len(mi))))
    if np.any(coh < -1e-9) or np.any(coh > 1 + 1e-9):
        raise ValueError(f"{g.name}/coherence holds values outside [0, 1]")
    valid = rd.array(g, "validation", "biu", 2, (len(mo), len(mi)))
    if np.any((valid != 0) & (valid != 1)):
        raise ValueError(f"{g.name}/validation holds values other than 0 and 1")
    ind = rd.array(g, "indicator", "f", 1, (k,))
    if np.any(np.isinf(ind)) or (valid.any() and np.any(np.isnan(ind))):
        raise ValueError(f"{g.name}/indicator holds values that are not finite")
    form = g.attrs.get("form", "standard")
    form = form.decode() if isinstance(form, bytes) else form
    if form not in ("standard", "extended"):
        raise ValueError(f"{g.name}: form is standard or extended, got {form!r}")
    chan = None
    if "channel_coherence" in g:
        chan = _finite(g, "channel_coherence",
                       rd.array(g, "channel_coherence", "f", 2, (k, len(mo))))
    return SemmOutcome(o, i, Y, mo, mi, bo, bi, coh, valid.astype(bool), ind, str(form), chan)
