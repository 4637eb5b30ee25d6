r"""A substructure known only by its receptances: ``type: frf``.

.. code-block:: yaml

    - name: meas
      type: frf
      file: measured.uff        # UFF 58 (or 58b) or .npz (H, labels, omega | freq_hz)
      interpolate: none         # or linear: onto the grid of analysis.frf
      decouple: false           # true: a known part removed from the assembly it is joined to
      virtual_points: {...}     # optional: channels reduced to virtual points
                                # (substruct.case.virtual_points; coordinates meas@vp:J:ux ...)
                                # the file may then hold the sensors x impacts only

Its points are its labels, ``meas@3:z``.  It has no mass, damping or stiffness matrices: the
case is coupled by frequency-based substructuring (:mod:`substruct.analysis.frf.coupling`) on
the grid of ``analysis.frf``, after the other substructures' receptances are computed at the
coordinates joined to it (``docs/frf.md``).  With ``decouple: true`` its receptance enters
negated, :math:`Y = \operatorname{diag}(\dots, -Y_R)`: coupling it to a measured assembly at
all of its coordinates (the extended interface) removes it (decoupling).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Literal

import numpy as np
from pydantic import PrivateAttr, ValidationInfo, model_validator

from substruct.case.errors import FieldError
from substruct.case.fields import Name, StrictModel
from substruct.case.frf_files import read_frf_file, read_measured_file
from substruct.case.virtual_points import VirtualPointsSpec

__all__ = ["FrfSpec"]


def _channel_labels(omega: np.ndarray, outs: list[str], ins: list[str], H: np.ndarray,
                    path: Path) -> tuple[np.ndarray, list[str], list[str], np.ndarray]:
    """A Universal File's labels ``<node>:<dir>`` as the channel names ``<node>.<dir>`` of
    :func:`substruct.case.uff_geometry.channels_from_uff` (a channel name has no colon)."""
    if path.suffix.lower() not in (".uff", ".unv"):
        return omega, outs, ins, H

    def name(label: str) -> str:
        return label.replace(":", ".")

    rows = [name(x) for x in outs]
    return omega, rows, rows if ins is outs else [name(x) for x in ins], H


class FrfSpec(StrictModel):
    """Receptances on a frequency grid with labelled coordinates, from a file."""

    name: Name
    type: Literal["frf"]
    file: str
    #: frequency grids that differ from the analysis' are refused unless interpolated
    interpolate: Literal["none", "linear"] = "none"
    #: a known part to remove: its receptance enters the coupling negated
    decouple: bool = False
    #: measured channels reduced to virtual points (:mod:`substruct.case.virtual_points`)
    virtual_points: VirtualPointsSpec | None = None
    _data: tuple[np.ndarray, list[str], list[str], np.ndarray] | None = \
        PrivateAttr(default=None)

    @model_validator(mode="after")
    def _load(self, info: ValidationInfo) -> "FrfSpec":
        base = Path((info.context or {}).get("base_dir", "."))
        path = Path(self.file)
        path = path if path.is_absolute() else base / path
        try:
            if self.virtual_points is None:
                omega, labels, H = read_frf_file(path)
                self._data = (omega, labels, labels, H)
            else:
                self._data = _channel_labels(*read_measured_file(path), path)
        except ValueError as err:
            raise FieldError("file", " ".join(str(err).split()), self.file) from None
        if self.virtual_points is not None:
            if self.decouple:
                raise FieldError("decouple", "a part with virtual points is coupled, not "
                                 "decoupled", True)
            _, outs, ins, _ = self._data
            have = {"sensor": (set(outs), "outputs"), "impact": (set(ins), "inputs")}
            for c in self.virtual_points.table().channels:
                known, side = have[c.kind]
                if c.name not in known:
                    what = "labels" if outs is ins else side
                    raise FieldError(("virtual_points", "channels"), f"{c.kind} {c.name!r} is "
                                     f"not among the {what} of {Path(self.file).name}", c.name)
        return self

    def data(self) -> tuple[np.ndarray, list[str], np.ndarray]:
        """``(omega, labels, H)`` as read (rad/s; ``H[k, i, j] = u_i / F_j``), square.

        Raises:
            ValueError: the part's file is rectangular (a virtual-points part; see
                :meth:`measured`).
        """
        omega, outs, ins, H = self.measured()
        if outs != ins:
            raise ValueError(f"{self.name}: the receptances are not square")
        return omega, outs, H

    def measured(self) -> tuple[np.ndarray, list[str], list[str], np.ndarray]:
        """``(omega, outputs, inputs, H)`` as read: square (outputs equal to inputs) for a
        plain part; for a virtual-points part the file's rows and columns, which may be the
        sensors x impacts only (:func:`~substruct.case.frf_files.read_measured_file`)."""
        if self._data is None:  # set by the validator
            raise ValueError(f"{self.name}: receptances not loaded")
        return self._data

    def dof_labels(self) -> list[str]:
        """The labels of the coordinates (after the virtual point transformation, if any)."""
        if self.virtual_points is not None:
            return self.virtual_points.labels()
        return list(self.data()[1])

    def n_dof(self) -> Any:
        """``None``: an FRF substructure adds no coordinates to the assembled model."""
        return None

