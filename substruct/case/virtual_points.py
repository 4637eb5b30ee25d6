r"""The ``virtual_points:`` block of a ``type: frf`` substructure: measured channels reduced to
6-DOF virtual points (:mod:`substruct.analysis.frf.virtual_point`) before the coupling.

.. code-block:: yaml

    - name: A
      type: frf
      file: a_channels.npz      # labels: channel names; rows of sensors x columns of impacts used
      virtual_points:
        channels: a_channels.csv  # the channel table (substruct.case.channels)
        points:
          - name: J
            position: [0, 0, 0]
            sensors: [S1x, S1y, ...]
            impacts: [H1, H2, ...]
            extra_modes: {sensors: [[...], ...], impacts: [[...], ...]}   # optional
            weights: {sensors: [...], impacts: [...]}                     # optional
        weaken: [rx, ry, rz]      # dropped from compatibility and equilibrium at this part's pairs
        regularization: {method: tikhonov, alpha: 1.0e-2, length: 0.025}   # or tsvd, rtol | rank
        interface: {reduction: svd, keep: 6, length: 0.025}   # or tolerance: instead of keep
        monte_carlo: {level: 1.0e-2, samples: 200, seed: 0}   # optional (one part of the case)

The part's coordinates are then ``vp:<point>:<ux|uy|uz|rx|ry|rz>`` (``vp:<point>:e<k>`` for
extra modes) and ``ch:<channel>`` for the channels given to no virtual point (they pass
through: a sensor as an output, an impact as an input).  The receptance of the part is
:math:`Y_{qm} = T_u Y T_f^T` with :math:`Y` the file's rows at the sensors and columns at the
impacts (other entries are not read), so the file may hold those only
(:func:`substruct.case.frf_files.read_measured_file`: an ``.npz`` with ``outputs`` and
``inputs``, or a Universal File's responses x references, whose labels ``<node>:<dir>`` are
read as the channel names ``<node>.<dir>`` that a channel table from the same file gives).
"""

from __future__ import annotations

from pathlib import Path
from typing import Literal

import numpy as np
from pydantic import Field, PrivateAttr, ValidationInfo, model_validator

from substruct.case.channel_files import read_channels
from substruct.case.channels import ChannelTable
from substruct.case.errors import FieldError
from substruct.case.fields import Name, StrictModel

__all__ = ["VP_LABEL_COMPONENTS", "ChannelLists", "VirtualPointSpec", "VpRegularization",
           "VpInterface", "VpMonteCarlo", "VirtualPointsSpec", "vp_label"]

#: The components of a virtual point in case-file labels (library order x, y, z, rx, ry, rz).
VP_LABEL_COMPONENTS = ("ux", "uy", "uz", "rx", "ry", "rz")


def vp_label(point: str, component: str) -> str:
    """The case-file label ``vp:<point>:<component>``."""
    return f"vp:{point}:{component}"


class ChannelLists(StrictModel):
    """Per-channel numbers of a virtual point, for its sensors and its impacts."""

    sensors: list[list[float]] | list[float]
    impacts: list[list[float]] | list[float]


class VirtualPointSpec(StrictModel):
    """One virtual point: its place and the channels that observe and load it."""

    name: Name
    position: tuple[float, float, float]
    sensors: list[Name] = Field(min_length=1)
    impacts: list[Name] = Field(min_length=1)
    #: extra (flexible) interface modes: one row of ``k`` numbers per sensor and per impact
    extra_modes: ChannelLists | None = None
    #: positive channel weights (the diagonal of ``W``), one per sensor and per impact
    weights: ChannelLists | None = None

    @model_validator(mode="after")
    def _shapes(self) -> "VirtualPointSpec":
        for key in ("extra_modes", "weights"):
            block = getattr(self, key)
            if block is None:
                continue
            for side in ("sensors", "impacts"):
                rows = np.asarray(getattr(block, side), dtype=float)
                n = len(getattr(self, side))
                want = 2 if key == "extra_modes" else 1
                if rows.ndim != want or rows.shape[0] != n:
                    what = "a list of rows, one per" if want == 2 else "one number per"
                    raise FieldError((key, side), f"{what} {side[:-1]} ({n})",
                                     getattr(block, side))
                if key == "weights" and not np.all(rows > 0):
                    raise FieldError((key, side), "weights must be positive",
                                     getattr(block, side))
        if self.extra_modes is not None:
            ks = {np.asarray(self.extra_modes.sensors).shape[1],
                  np.asarray(self.extra_modes.impacts).shape[1]}
            if len(ks) != 1 or 0 in ks:
                raise FieldError(("extra_modes",), "the same number (at least 1) of extra "
                                 "modes for the sensors and the impacts", sorted(ks))
        return self

    def n_extra(self) -> int:
        """The number of extra modes."""
        return 0 if self.extra_modes is None else \
            int(np.asarray(self.extra_modes.sensors).shape[1])


class VpRegularization(StrictModel):
    """How the interface receptance is inverted (:mod:`substruct.analysis.frf.vp_coupling`)."""

    method: Literal["tsvd", "tikhonov"]
    #: ``tsvd``: singular values at or below ``rtol`` times the largest are dropped
    rtol: float | None = Field(default=None, ge=0.0, lt=1.0)
    #: ``tsvd``: keep this many singular values instead
    rank: int | None = Field(default=None, ge=1)
    #: ``tikhonov``: :math:`\lambda = \alpha \sigma_1`
    alpha: float | None = Field(default=None, ge=0.0)
    #: a length of the joint: the rotation rows are scaled by it before the inversion
    length: float = Field(gt=0.0)

    @model_validator(mode="after")
    def _keys(self) -> "VpRegularization":
        given = [k for k in ("rtol", "rank", "alpha") if getattr(self, k) is not None]
        allowed = ("rtol", "rank") if self.method == "tsvd" else ("alpha",)
        for k in given:
            if k not in allowed:
                raise FieldError((k,), f"not a setting of {self.method} (it takes "
                                 f"{' or '.join(allowed)})", getattr(self, k))
        if len(given) != 1:
            raise FieldError(("method",), f"{self.method} needs exactly one of "
                             f"{', '.join(allowed)}", self.method)
        return self


class VpInterface(StrictModel):
    """The interface reduced to the dominant singular vectors of its receptance over the band
    (:mod:`substruct.analysis.frf.vp_reduction`)."""

    reduction: Literal["svd"]
    #: keep this many singular vectors
    keep: int | None = Field(default=None, ge=1)
    #: or those above ``tolerance`` times the largest singular value
    tolerance: float | None = Field(default=None, ge=0.0, lt=1.0)
    #: a length of the joint: the rotation rows are scaled by it before the SVD
    length: float = Field(gt=0.0)

    @model_validator(mode="after")
    def _one(self) -> "VpInterface":
        if (self.keep is None) == (self.tolerance is None):
            raise FieldError(("reduction",), "svd needs exactly one of keep, tolerance",
                             self.reduction)
        return self


class VpMonteCarlo(StrictModel):
    """The coupled result's sensitivity to noise (:mod:`substruct.analysis.frf.vp_noise`):
    relative complex Gaussian noise of ``level`` on every measured FRF of the case (every
    ``type: frf`` part), ``samples`` couplings, sample ``k`` seeded by ``[seed, k]``."""

    level: float = Field(ge=0.0, le=1.0)
    samples: int = Field(ge=2, le=100_000)
    seed: int = Field(default=0, ge=0)
    #: the coupled receptances kept (points as in ``analysis.frf``; default: its outputs)
    outputs: list[str] | None = Field(default=None, min_length=1)
    #: default: the inputs of ``analysis.frf``
    inputs: list[str] | None = Field(default=None, min_length=1)
    #: percentile bands of the magnitude
    percentiles: list[float] = Field(default_factory=lambda: [5.0, 50.0, 95.0], max_length=99)

    @model_validator(mode="after")
    def _bands(self) -> "VpMonteCarlo":
        for i, q in enumerate(self.percentiles):
            if not 0.0 <= q <= 100.0:
                raise FieldError(("percentiles", i), "a percentile is in [0, 100]", q)
        return self


class VirtualPointsSpec(StrictModel):
    """The virtual points of a measured part (module docstring)."""

    channels: str
    points: list[VirtualPointSpec] = Field(min_length=1)
    #: virtual-point components dropped from compatibility and equilibrium at this part's
    #: connections (``[rx, ry, rz]``: a ball joint)
    weaken: list[Literal["ux", "uy", "uz", "rx", "ry", "rz"]] = Field(default_factory=list)
    regularization: VpRegularization | None = None
    interface: VpInterface | None = None
    monte_carlo: VpMonteCarlo | None = None
    _table: ChannelTable | None = PrivateAttr(default=None)

    @model_validator(mode="after")
    def _load(self, info: ValidationInfo) -> "VirtualPointsSpec":
        base = Path((info.context or {}).get("base_dir", "."))
        path = Path(self.channels)
        path = path if path.is_absolute() else base / path
        try:
            table = read_channels(path)
        except ValueError as err:
            raise FieldError("channels", " ".join(str(err).split()), self.channels) from None
        names = [p.name for p in self.points]
        if len(set(names)) != len(names):
            raise FieldError("points", "virtual point names repeated", names)
        if len(set(self.weaken)) != len(self.weaken):
            raise FieldError("weaken", "a component is repeated", list(self.weaken))
        known = {c.name: c.kind for c in table.channels}
        owner: dict[str, str] = {}
        for i, p in enumerate(self.points):
            for side, kind in (("sensors", "sensor"), ("impacts", "impact")):
                for j, name in enumerate(getattr(p, side)):
                    if name not in known:
                        raise FieldError(("points", i, side, j), f"no channel {name!r} in "
                                         f"{path.name}", name)
                    if known[name] != kind:
                        raise FieldError(("points", i, side, j), f"channel {name!r} is a "
                                         f"{known[name]}, not a {kind}", name)
                    if name in owner:
                        raise FieldError(("points", i, side, j), f"channel {name!r} already "
                                         f"belongs to virtual point {owner[name]}", name)
                    owner[name] = p.name
        self._table = table
        return self

    def table(self) -> ChannelTable:
        """The channel table as read."""
        if self._table is None:  # set by the validator
            raise ValueError("channel table not loaded")
        return self._table

    def labels(self) -> list[str]:
        """Every coordinate of the transformed part: the virtual points', then the channels
        that pass through (``ch:<name>``)."""
        out = [vp_label(p.name, c) for p in self.points
               for c in [*VP_LABEL_COMPONENTS, *(f"e{k + 1}" for k in range(p.n_extra()))]]
        used = {n for p in self.points for n in [*p.sensors, *p.impacts]}
        return out + [f"ch:{c.name}" for c in self.table().channels if c.name not in used]
