r"""The test-lab analyses of a case, read from the receptances ``analysis.frf`` computes:
``analysis.tpa`` (transfer path analysis with blocked forces) and ``analysis.semm`` (system
equivalent model mixing).  Both name coordinates among ``analysis.frf``'s inputs and outputs
and a measurement file on the same frequency grid.

.. code-block:: yaml

    analysis:
      frf: {omega: ..., inputs: [A@vp:J:ux, ...], outputs: [B@ch:I1, ..., B@ch:T1, ...]}
      tpa:
        responses: operating.npz   # omega (rad/s) or freq_hz, labels (points), u (freq x labels)
        interface: [A@vp:J:ux, A@vp:J:uy, ...]   # the paths c: inputs of analysis.frf
        method: in_situ            # or matrix_inverse (the responses at the interface itself)
                                   # or pseudo_forces (interface: points of the source off it)
        indicators: [B@ch:I1, ...] # in_situ: at least as many as interface coordinates
        targets: [B@ch:T1, ...]    # on-board validation and path contributions
        regularization: {method: tsvd, rtol: 1.0e-2, length: 0.3}   # not matrix_inverse
      # or operational TPA, from responses under several operating conditions:
      # tpa: {method: operational, responses: operating.npz (u: freq x labels x conditions),
      #       indicators: [...], targets: [...], validation_condition: 0}
      semm:
        measured: measured.npz     # omega or freq_hz, outputs, inputs, H (freq x out x in)
        boundary: {outputs: [...], inputs: [...]}   # optional: default every measured one
        form: extended             # optional: standard (default) or extended

The responses of ``tpa`` are operating responses of the assembly in the quantity of
``analysis.frf`` (a receptance's displacements by default); in situ,
:math:`f^{bl} = (Y_{bc})^{+} u_b`; by matrix inverse, :math:`f^{bl} = Y_{cc}^{-1} u_c`
(:mod:`substruct.analysis.frf.tpa`); with pseudo-forces at points ``p`` of the source
(given as ``interface``), :math:`F_{ps} = (Y_{bp})^{+} u_b`
(:mod:`substruct.analysis.frf.tpa_operational`); operationally, the transmissibility
:math:`T = U_t U_i^{+}` from the indicators to the targets over every operating condition but
the ``validation_condition``, which it predicts, :math:`\hat u_t = T u_i` (the receptances are
not used; ``analysis.frf`` gives the grid).  SEMM mixes ``analysis.frf``'s receptance
(the numerical model) with the measured one (:mod:`substruct.analysis.frf.semm`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Literal, Protocol, Sequence

import numpy as np
from pydantic import Field, PrivateAttr, ValidationInfo, model_validator

from substruct.case.errors import FieldError
from substruct.case.fields import Point, StrictModel
from substruct.case.frf_files import GRID_DIGITS_RTOL, MAX_FRF_FILE
from substruct.case.npz_files import npz_members, read_npz
from substruct.case.numbers import MAX_MAGNITUDE, RANGE
from substruct.case.virtual_points import VpRegularization



class ComputedReceptances(Protocol):
    """What a test-lab analysis reads of ``analysis.frf`` (its
    :class:`~substruct.case.analysis.FrfAnalysis`): the computed points and the grid."""

    inputs: list[str]
    outputs: list[str]

    def omegas(self) -> np.ndarray:
        """The frequencies of the receptances (rad/s)."""
        ...

__all__ = ["TpaAnalysis", "SemmBoundary", "SemmAnalysis", "check_against_frf"]


def _path(name: str, info: ValidationInfo) -> Path:
    base = Path((info.context or {}).get("base_dir", "."))
    p = Path(name)
    return p if p.is_absolute() else base / p


def _read(path: Path, arrays: dict[str, str]) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """The grid (rad/s) and the ``arrays`` (name -> ``"c"`` complex or ``"U"`` strings) of an
    ``.npz`` file, every size checked before it is read."""
    if path.suffix.lower() != ".npz":
        raise ValueError(f"{path.name}: a measurement file is .npz")
    if not path.is_file():
        raise ValueError(f"no file {path.name}")
    if path.stat().st_size > MAX_FRF_FILE:
        raise ValueError(f"{path.name} has more than the {MAX_FRF_FILE} bytes accepted")
    names = npz_members(path)
    grid = "omega" if "omega" in names else "freq_hz"
    missing = [k for k in [*arrays, grid] if k not in names]
    if missing:
        raise ValueError(f"{path.name} needs arrays {', '.join(arrays)} and omega (or "
                         f"freq_hz); it has {', '.join(sorted(names)) or 'none'}")
    for key, kind in [*arrays.items(), (grid, "f")]:
        ok = "U" if kind == "U" else "biuf" + ("c" if kind == "c" else "")
        if names[key].dtype.kind not in ok:
            raise ValueError(f"{path.name}: {key} holds {names[key].dtype} entries, not "
                             f"{'strings' if kind == 'U' else 'numbers'}")
    conv = {k: np.complex128 for k, v in arrays.items() if v == "c"}
    z = read_npz(path, [*arrays, grid], {**conv, grid: np.float64})
    w = z[grid] if grid == "omega" else 2 * np.pi * z[grid]
    if w.ndim != 1 or w.size == 0 or not np.all(np.isfinite(w)) or np.any(w <= 0) \
            or np.any(np.diff(w) <= 0):
        raise ValueError(f"{path.name}: {grid} must be positive, ascending and finite")
    return w, z


def _labels(path: Path, z: dict[str, np.ndarray], key: str) -> list[str]:
    arr = z[key]
    if arr.ndim != 1:
        raise ValueError(f"{path.name}: {key} must be a 1-D array, got shape {list(arr.shape)}")
    out = [str(s) for s in arr]
    if len(set(out)) != len(out):
        raise ValueError(f"{path.name}: {key} repeat a name")
    return out


def _finite(path: Path, name: str, values: np.ndarray, labels: Sequence[Sequence[str]]
            ) -> None:
    bad = ~np.isfinite(values)
    if bad.any():
        at = [int(v) for v in np.argwhere(bad)[0]]
        where = "/".join(lab[i] for lab, i in zip(labels, at[1:]))
        raise ValueError(f"{path.name}: {name} at {where} is {values[tuple(at)]} at "
                         f"frequency index {at[0]}")
    size = np.abs(values)
    if size.size and size.max() > MAX_MAGNITUDE:
        at = [int(v) for v in np.unravel_index(int(np.argmax(size)), size.shape)]
        where = "/".join(lab[i] for lab, i in zip(labels, at[1:]))
        raise ValueError(f"{path.name}: {name} at {where} has magnitude "
                         f"{size[tuple(at)]:.3g} at frequency index {at[0]} ({RANGE})")


def _distinct(key: str, names: Sequence[str]) -> None:
    seen: set[str] = set()
    for i, n in enumerate(names):
        if n in seen:
            raise FieldError((key, i), "repeated", n)
        seen.add(n)


class TpaAnalysis(StrictModel):
    """Blocked forces at the interface, their on-board validation and path contributions, or
    operational TPA (module docstring)."""

    responses: str
    interface: list[Point] = Field(default_factory=list)
    method: Literal["in_situ", "matrix_inverse", "pseudo_forces", "operational"] = "in_situ"
    indicators: list[Point] = Field(default_factory=list)
    targets: list[Point] = Field(min_length=1)
    #: in situ, pseudo-forces: the pseudo-inverse of Y_bc; ``length`` scales the moments
    regularization: VpRegularization | None = None
    #: operational: the operating condition (index in the file) left out of the
    #: transmissibility and predicted by it
    validation_condition: int | None = Field(default=None, ge=0)
    _omega: np.ndarray | None = PrivateAttr(default=None)
    _u: dict[str, np.ndarray] = PrivateAttr(default_factory=dict)

    @model_validator(mode="after")
    def _load(self, info: ValidationInfo) -> "TpaAnalysis":
        for key in ("interface", "indicators", "targets"):
            _distinct(key, getattr(self, key))
        operational = self.method == "operational"
        if operational:
            self._operational_keys()
        elif self.validation_condition is not None:
            raise FieldError("validation_condition", "belongs to method: operational",
                             self.validation_condition)
        elif not self.interface:
            raise FieldError("interface", f"{self.method} needs the interface coordinates "
                             "(at least one)", [])
        if self.method == "matrix_inverse":
            if self.indicators:
                raise FieldError("indicators", "matrix_inverse uses the responses at the "
                                 "interface itself: give no indicators (or method: in_situ)",
                                 list(self.indicators))
            if self.regularization is not None:
                raise FieldError("regularization", "matrix_inverse is a solve; "
                                 "regularization belongs to in_situ", self.regularization.method)
        elif not operational and len(self.indicators) < len(self.interface):
            what = "pseudo-forces need at least as many indicators as pseudo-force points" \
                if self.method == "pseudo_forces" else \
                "in situ needs at least as many indicators as interface coordinates"
            raise FieldError("indicators", f"{what} ({len(self.interface)})",
                             list(self.indicators))
        for i, t in enumerate(self.targets):
            if t in self.indicators or t in self.interface:
                raise FieldError(("targets", i), "a validation target must not be used to "
                                 "find the forces", t)
        path = _path(self.responses, info)
        try:
            w, z = _read(path, {"labels": "U", "u": "c"})
            labels = _labels(path, z, "labels")
            u = z["u"]
            if operational:
                ok = u.ndim == 3 and u.shape[:2] == (len(w), len(labels)) and u.shape[2] > 0
                expect = f"[{len(w)}, {len(labels)}, conditions] (frequencies, labels, " \
                    "operating conditions)"
            else:
                ok = u.shape == (len(w), len(labels))
                expect = f"[{len(w)}, {len(labels)}] (frequencies, labels)"
            if not ok:
                raise ValueError(f"{path.name}: u has shape {list(u.shape)}, expected {expect}")
            axes = [labels] + ([[f"condition {k}" for k in range(u.shape[2])]]
                               if operational else [])
            _finite(path, "the response", u, axes)
        except ValueError as err:
            raise FieldError("responses", " ".join(str(err).split()), self.responses) from None
        if operational:
            self._conditions(path, u.shape[2])
        for key in ("interface" if self.method == "matrix_inverse" else "indicators",
                    "targets"):
            for i, p in enumerate(getattr(self, key)):
                if p not in labels:
                    raise FieldError((key, i), f"no response at it in {path.name}", p)
        self._omega = w
        self._u = {lab: u[:, j] for j, lab in enumerate(labels)}
        return self

    def _operational_keys(self) -> None:
        """Refuse the keys operational TPA does not use and a missing validation condition."""
        if self.interface:
            raise FieldError("interface", "operational TPA has no interface: its paths are the "
                             "indicators", list(self.interface))
        if self.regularization is not None:
            raise FieldError("regularization", "belongs to in_situ and pseudo_forces",
                             self.regularization.method)
        if self.validation_condition is None:
            raise FieldError("validation_condition", "operational TPA predicts one operating "
                             "condition left out of the transmissibility: give its index")
        if not self.indicators:
            raise FieldError("indicators", "operational TPA needs indicators (its paths)", [])

    def _conditions(self, path: Path, n_o: int) -> None:
        """Refuse a validation condition the file lacks or too few conditions left."""
        k = self.validation_condition
        assert k is not None
        if k >= n_o:
            raise FieldError("validation_condition", f"{path.name} has {n_o} operating "
                             f"condition(s), indexed from 0", k)
        if n_o - 1 < len(self.indicators):
            raise FieldError("indicators", f"operational TPA needs at least as many operating "
                             f"conditions (besides the validation condition) as indicators: "
                             f"{n_o - 1} < {len(self.indicators)} in {path.name}",
                             list(self.indicators))

    def omega(self) -> np.ndarray:
        """The responses' grid (rad/s)."""
        if self._omega is None:
            raise ValueError("responses not loaded")
        return self._omega

    def responses_at(self, points: Sequence[str]) -> np.ndarray:
        """``(n_omega, len(points))`` operating responses (operational:
        ``(n_omega, len(points), conditions)``)."""
        return np.stack([self._u[p] for p in points], axis=1)

    def measured_points(self) -> list[str]:
        """The points whose responses find the forces."""
        return list(self.interface if self.method == "matrix_inverse" else self.indicators)


class SemmBoundary(StrictModel):
    """The measured coordinates the mix is imposed at (the rest validate it)."""

    outputs: list[Point] = Field(min_length=1)
    inputs: list[Point] = Field(min_length=1)


class SemmAnalysis(StrictModel):
    """System equivalent model mixing of ``analysis.frf``'s receptance with a measured one
    (module docstring)."""

    measured: str
    boundary: SemmBoundary | None = None
    #: ``extended``: the removed model is the whole numerical model (every measured channel
    #: may be on the boundary), with the channel coherence criterion
    form: Literal["standard", "extended"] = "standard"
    _omega: np.ndarray | None = PrivateAttr(default=None)
    _H: np.ndarray | None = PrivateAttr(default=None)
    _outputs: list[str] = PrivateAttr(default_factory=list)
    _inputs: list[str] = PrivateAttr(default_factory=list)

    @model_validator(mode="after")
    def _load(self, info: ValidationInfo) -> "SemmAnalysis":
        path = _path(self.measured, info)
        try:
            w, z = _read(path, {"outputs": "U", "inputs": "U", "H": "c"})
            outs, ins = _labels(path, z, "outputs"), _labels(path, z, "inputs")
            H = z["H"]
            if H.shape != (len(w), len(outs), len(ins)):
                raise ValueError(f"{path.name}: H has shape {list(H.shape)}, expected "
                                 f"[{len(w)}, {len(outs)}, {len(ins)}]")
            _finite(path, "the receptance", H, [outs, ins])
        except ValueError as err:
            raise FieldError("measured", " ".join(str(err).split()), self.measured) from None
        if self.boundary is not None:
            for key, have in (("outputs", outs), ("inputs", ins)):
                names = getattr(self.boundary, key)
                _distinct(key, names)
                for i, p in enumerate(names):
                    if p not in have:
                        raise FieldError(("boundary", key, i), f"not measured (not among the "
                                         f"{key} of {path.name})", p)
        self._omega, self._H, self._outputs, self._inputs = w, H, outs, ins
        return self

    def data(self) -> tuple[np.ndarray, list[str], list[str], np.ndarray]:
        """``(omega, outputs, inputs, H)`` as measured."""
        if self._omega is None or self._H is None:
            raise ValueError("measurement not loaded")
        return self._omega, self._outputs, self._inputs, self._H


def _grid(key: tuple[str, str], w: np.ndarray, grid: np.ndarray, file: str) -> None:
    if w.shape != grid.shape or not np.allclose(w, grid, rtol=GRID_DIGITS_RTOL, atol=0):
        raise FieldError(key, f"the measured frequencies ({len(w)}, {w.min():g} to "
                         f"{w.max():g} rad/s) are not those of analysis.frf.omega "
                         f"({len(grid)}, {grid.min():g} to {grid.max():g})", file)


def check_against_frf(tpa: TpaAnalysis | None, semm: SemmAnalysis | None,
                      frf: ComputedReceptances | None) -> None:
    """Refuse (:class:`FieldError` relative to ``analysis``) a test-lab analysis whose
    coordinates are not computed by ``frf`` or whose grid is not ``frf``'s."""
    if tpa is None and semm is None:
        return
    if frf is None:
        raise FieldError("tpa" if tpa is not None else "semm", "reads the receptances of "
                         "analysis.frf: add analysis.frf")
    grid = frf.omegas()
    if tpa is not None:
        for i, p in enumerate(tpa.interface):
            if p not in frf.inputs:
                raise FieldError(("tpa", "interface", i), "not an input of analysis.frf", p)
        for key in ("interface", "indicators", "targets") if tpa.method == "matrix_inverse" \
                else () if tpa.method == "operational" else ("indicators", "targets"):
            for i, p in enumerate(getattr(tpa, key)):
                if p not in frf.outputs:
                    raise FieldError(("tpa", key, i), "not an output of analysis.frf", p)
        _grid(("tpa", "responses"), tpa.omega(), grid, tpa.responses)
    if semm is not None:
        w, outs, ins, _ = semm.data()
        for key, have, want in (("outputs", outs, frf.outputs), ("inputs", ins, frf.inputs)):
            for p in have:
                if p not in want:
                    raise FieldError(("semm", "measured"), f"measured {key[:-1]} {p!r} is "
                                     f"not among the {key} of analysis.frf", semm.measured)
        _grid(("semm", "measured"), w, grid, semm.measured)
