"""Case-file Nastran models: ``type: nastran``, a substructure read from a bulk data file
(:mod:`substruct.case.bdf`).

.. code-block:: yaml

    - name: bracket
      type: nastran
      file: bracket.bdf          # relative to the case file

Points are ``bracket@12:3`` (grid 12, component 3; components ``1`` - ``6`` or ``ux`` ...
``rz``), nodes of links ``bracket@12``.  The file is read and checked when the case is
validated, so that any problem in it is reported before anything is built; its rigid elements
and MPC set become rows of ``A`` (:mod:`substruct.builder.links`), its EIGRL is not used (the
case's ``analysis`` says what to compute).
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Literal

import yaml
from pydantic import Field, PrivateAttr, ValidationInfo, model_validator

from substruct.case.errors import CaseError, FieldError
from substruct.case.fields import Name, StrictModel

if TYPE_CHECKING:  # the bulk data reader is imported when a Nastran file is read
    from substruct.case.bdf import BulkData

__all__ = ["NastranSpec", "BDF_SUFFIXES", "bdf_case"]

#: File name endings read as Nastran bulk data by ``substruct run``.
BDF_SUFFIXES = (".bdf", ".dat", ".nas", ".bulk")


class NastranSpec(StrictModel):
    """A substructure from a Nastran bulk data file."""

    name: Name
    type: Literal["nastran"]
    file: Annotated[str, Field(min_length=1)]

    _bulk: Any = PrivateAttr(default=None)

    @model_validator(mode="after")
    def _read(self, info: ValidationInfo) -> "NastranSpec":
        from substruct.case.bdf import read_bulk

        context = info.context or {}
        base = Path(context.get("base_dir", "."))
        source = context.get("source", "")
        if Path(source).suffix.lower() in BDF_SUFFIXES:  # substruct run MODEL.bdf
            source = str(source)  # the file as given on the command line
        else:
            source = self.file  # as written in the case
        try:
            self._bulk = read_bulk(base / self.file, source)
        except CaseError as err:
            raise FieldError("file", str(err)) from None
        return self

    @property
    def bulk(self) -> BulkData:
        """The bulk data read."""
        assert self._bulk is not None
        return self._bulk

    def n_dof(self) -> None:
        """Known once built (supports decide it)."""
        return None


def bdf_case(path: Path, source: str) -> str:
    """The case text of ``substruct run MODEL.bdf``: the model as its only substructure (named
    after the file) and the normal modes its EIGRL asks for: the lowest ``ND``, or (with
    ``V1``, ``V2`` in Hz) those in the band, ``ND`` at most (all of them when ``ND`` is
    blank), as ``analysis.modes.band`` in rad/s.

    Raises:
        BdfError: the file cannot be read or has no EIGRL.
    """
    from substruct.case.bdf import read_bulk
    from substruct.case.bdf_fields import BdfError
    from substruct.case.fields import MAX_COUNT

    bulk = read_bulk(path, source)
    eig = bulk.eigrl
    if eig is None:
        raise BdfError(source, "no EIGRL: substruct run of a bulk data file computes the "
                       "normal modes its EIGRL asks for")
    if eig.norm != "MASS":
        raise BdfError(source, "substruct run writes shapes of unit modal mass (EIGRL NORM "
                       "MASS)", eig.norm, line=eig.line, card="EIGRL", ident=eig.sid)
    name = re.sub(r"[^A-Za-z0-9_.-]", "_", path.stem)[:100] or "model"
    modes: dict[str, Any] = {"count": eig.nd if eig.nd is not None else MAX_COUNT}
    if eig.v1 is not None or eig.v2 is not None:
        band: dict[str, float] = {"min": 2 * math.pi * max(eig.v1 or 0.0, 0.0)}
        if eig.v2 is not None:
            band["max"] = 2 * math.pi * eig.v2
        modes["band"] = band
    data = {"name": name, "description": f"normal modes of {path.name} (EIGRL {eig.sid})",
            "substructures": [{"name": name, "type": "nastran", "file": path.name}],
            "analysis": {"modes": modes}}
    return yaml.safe_dump(data, sort_keys=False)
