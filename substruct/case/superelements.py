r"""Case-file superelements: ``type: superelement``, a reduced model delivered as matrices
(a Craig-Bampton model written by Nastran or another code) with the map of its coordinates.

.. code-block:: yaml

    - name: sc
      type: superelement
      file: sc.op4              # or .npz, bulk data with DMIG entries (.bdf, .dat ...), .full
      M: MAA                    # matrix names in the file (OP4, any case) or keys (NPZ)
      K: KAA
      C: BAA                    # optional viscous damping
      K4: K4AA                  # optional structural damping, entering as K4 / W4
      W4: 125.6                 # rad/s, needed with K4 (Nastran's PARAM,W4)
      dofs: {file: sc_dofs.csv} # or {key: DOFS} (a member of file), or inline:
      #     [[100, "123456"], [200, "123456"], {modes: 20}]
      grids: {100: [0, 0, 0], 200: [0, 0, 1.2]}   # optional: rigid-body checks
      reference: [0, 0, 0]      # point the rigid-body mass matrix is taken about
      free: true                # the model has six rigid-body modes (K D = 0 checked)
      recovery: [{name: dtm, matrix: DTM, of: displacement, labels: {file: rows.csv}}]

The DOF map gives, row by row, the grid and the component of each coordinate: components 1-6
(``ux uy uz rx ry rz``) of boundary grids, 0 for a modal (fixed-interface) coordinate, which is
labelled ``mode:<k>`` in order.  A CSV file has one ``grid, component`` line per coordinate
(an optional header line and ``#`` comments); a member (OP4 matrix or NPZ array) is ``n x 2``.
Points are ``sc@100:uz`` (or ``sc@100:3``) and ``sc@mode:2``.  From bulk data the map is
that of the DMIG entries (:mod:`substruct.case.dmig`: rows and columns in ascending ``(grid,
component)``, scalar points modal), and ``dofs`` is left out; so it is from an Ansys ``.full``
file (:mod:`substruct.case.ansys_full`: ``M: M``, ``K: K``, the free equations by node and
``UX..ROTZ``).  Without ``file``, ``M``, ``K``
(``C``, ``K4``) name Abaqus ``.mtx`` files (:mod:`substruct.case.abaqus_mtx`), whose DOF map is
their ``(node, dof)`` pairs, or ``dofs`` for files of equation numbers.  ``recovery`` lists output
transformation matrices (:mod:`substruct.case.recovery`).

Checked while the case is read (:mod:`substruct.case.rigid_body`): the matrices square, of one
size, real, finite, ``M`` and ``K`` symmetric and positive semidefinite (to the precision of
the data: :data:`SYMMETRY_RTOL`); the map one distinct row per coordinate; with ``grids``, a
position for every boundary grid and none other, the boundary moving in all six rigid-body
directions, the rigid-body mass matrix ``D^T M D``, mass, centre of gravity and inertia
computed, and, for a free model, the rigid-body "frequencies" of ``(D^T K D, D^T M D)`` below
``rigid_tolerance`` (1e-3) times the first elastic frequency.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import Field, PrivateAttr, ValidationInfo, model_validator

from substruct.case.errors import FieldError
from substruct.case.fields import (
    DENSE_CHECK,
    MAX_MATRIX_SIZE,
    Name,
    Number,
    Positive,
    StrictModel,
)
from substruct.case.numbers import array_problem
from substruct.case.recovery import RecoverySpec, load_recovery
from substruct.case.rigid_body import (
    rigid_body_properties,
    rigid_body_frequency_ratio,
    rigid_body_vectors,
)

__all__ = ["SuperelementSpec", "SE_COMPONENTS", "SYMMETRY_RTOL", "MAX_DOF_FILE"]

#: Names of the components 1-6 of a grid, as coordinate labels use them.
SE_COMPONENTS = ("ux", "uy", "uz", "rx", "ry", "rz")
#: Relative asymmetry of ``M`` and ``K`` accepted, by the precision of the data (bytes).
SYMMETRY_RTOL = {8: 1e-10, 4: 1e-5}
#: Largest CSV DOF map read (bytes).
MAX_DOF_FILE = 50_000_000
_MATRICES = ("M", "K", "C", "K4")


def _grid(value: Any, loc: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or \
            not 1 <= int(value) <= 999_999_999:
        raise FieldError(loc, "a grid id is an integer from 1 to 999999999", value)
    return int(value)


class SuperelementSpec(StrictModel):
    """A superelement: matrices from an OP4 or NPZ file and the map of their coordinates."""

    name: Name
    type: Literal["superelement"]
    file: Annotated[str, Field(min_length=1)] | None = None
    M: Annotated[str, Field(min_length=1)]
    K: Annotated[str, Field(min_length=1)]
    C: str | None = None
    K4: str | None = None
    W4: Positive | None = None
    dofs: Any = None
    grids: dict[int, tuple[Number, Number, Number]] | None = None
    reference: tuple[Number, Number, Number] = (0.0, 0.0, 0.0)
    free: bool = True
    rigid_tolerance: Annotated[Number, Field(gt=0, lt=1)] = 1e-3
    recovery: list[RecoverySpec] = Field(default_factory=list)
    _matrices: dict[str, np.ndarray] = PrivateAttr(default_factory=dict)
    _dofs: list[tuple[int, int]] = PrivateAttr(default_factory=list)
    _rigid: dict[str, Any] | None = PrivateAttr(default=None)

    # ----------------------------------------------------------------- reading

    def _read(self, base: Path, case_units: str
              ) -> tuple[dict[str, np.ndarray], int, Any, list[tuple[int, int]] | None]:
        """The named matrices (dense float64), the bytes per number of the data, the DOF-map
        member if ``dofs: {key: ...}`` and the DOF map of DMIG entries."""
        from substruct.case.superelement_files import BULK_SUFFIXES, read_matrix_file

        names = {f: getattr(self, f) for f in _MATRICES if getattr(self, f) is not None}
        if self.file is None:
            return self._read_abaqus(base, names)
        member = self.dofs.get("key") if isinstance(self.dofs, dict) else None
        got = read_matrix_file(self.file, base, "file", names,
                               [member] if isinstance(member, str) else [])
        if got.dofs is not None and self.dofs is not None:
            bulk = got.path.suffix.lower() in BULK_SUFFIXES
            kind, source = ("bulk data", "its DMIG entries") if bulk else \
                ("an Ansys FULL file", "its equations")
            raise FieldError("dofs", f"{got.path.name} is {kind}: the DOF map is that of "
                             f"{source} (leave dofs out)", self._shown_dofs())
        if got.dofs is None and self.dofs is None:
            raise FieldError("dofs", "a DOF map is required for matrices from an OP4 or NPZ "
                             "file ({file: map.csv}, {key: <member>} or a list)")
        extra = got.members[member] if isinstance(member, str) else None
        if got.units is not None:
            self._check_units(got.path.name, got.units, case_units)
        return got.matrices, got.nbytes, extra, got.dofs

    def _check_units(self, file: str, units: str, case_units: str) -> None:
        """The units an NPZ file declares must be the case's (nothing converts them)."""
        def norm(text: str) -> list[str]:
            return [u.strip() for u in text.split(",")]

        if not case_units.strip():
            raise FieldError("file", f"{file} declares its units {units!r} (member 'units') "
                             f"and the case none: declare the case's units: (the same) so that "
                             f"they are not mixed", self.file)
        if norm(units) != norm(case_units):
            raise FieldError("file", f"{file} declares its units {units!r} (member 'units'), "
                             f"not the case's {case_units!r}: nothing converts them (convert "
                             f"the matrices, or use the units of the file)", self.file)

    def _read_abaqus(self, base: Path, names: dict[str, str]
                     ) -> tuple[dict[str, np.ndarray], int, Any, list[tuple[int, int]] | None]:
        """Without ``file``: ``M``, ``K`` (``C``, ``K4``) name Abaqus ``.mtx`` files."""
        for field, value in names.items():
            if not value.lower().endswith(".mtx"):
                raise FieldError("file", "the file of the matrices is required (.op4, .npz or "
                                 "bulk data); without it M, K, C and K4 name Abaqus matrix "
                                 f"files (.mtx), but {field} is {value!r}")
        if isinstance(self.dofs, dict) and "key" in self.dofs:
            raise FieldError(("dofs", "key"), "names a member of file; Abaqus matrix files "
                             "hold one matrix each (give {file: map.csv} or a list)",
                             self.dofs["key"])
        from substruct.case.superelement_files import read_abaqus_files  # when a file is read

        given = self._dof_rows(base, None) if self.dofs is not None else None
        got = read_abaqus_files(names, base, given)
        return got.matrices, got.nbytes, None, got.dofs

    def _check_matrices(self, mats: dict[str, np.ndarray], nbytes: int) -> None:
        n = mats["M"].shape[0] if mats["M"].ndim == 2 else -1
        for field, X in mats.items():
            key = getattr(self, field)
            if X.ndim != 2 or X.shape[0] != X.shape[1]:
                raise FieldError(field, f"matrix {key!r} must be square, is "
                                 f"{' x '.join(map(str, X.shape))}", key)
            if X.shape[0] != n:
                raise FieldError(field, f"matrix {key!r} must be {n} x {n} like M, is "
                                 f"{X.shape[0]} x {X.shape[1]}", key)
            problem = array_problem(X)
            if problem is not None:
                raise FieldError(field, f"matrix {key!r} {problem}", key)
            scale = max(float(np.abs(X).max()), 1e-300)
            asym = float(np.abs(X - X.T).max())
            if asym > SYMMETRY_RTOL[nbytes] * scale:
                raise FieldError(field, f"matrix {key!r} must be symmetric: max |{field} - "
                                 f"{field}^T| = {asym:.3g}, {asym / scale:.2g} of its largest "
                                 f"entry", key)
            mats[field] = (X + X.T) / 2
        if n > MAX_MATRIX_SIZE:
            raise FieldError("M", f"{n} coordinates, more than the {MAX_MATRIX_SIZE} "
                             f"accepted", self.M)
        for field in ("M", "K"):
            X = mats[field]
            floor = -1e3 * SYMMETRY_RTOL[nbytes] * max(float(np.abs(X).max()), 1e-300)
            if np.any(np.diag(X) < floor):  # a statically determinate boundary: K_bb ~ 0
                raise FieldError(field, f"matrix {getattr(self, field)!r} must be positive "
                                 f"semidefinite: diagonal entry {float(np.diag(X).min()):g}",
                                 getattr(self, field))
            if n <= DENSE_CHECK:
                eig = np.linalg.eigvalsh(X)
                top = max(float(np.abs(eig).max()), 1e-300)
                if eig[0] < -1e3 * SYMMETRY_RTOL[nbytes] * top:
                    raise FieldError(field, f"matrix {getattr(self, field)!r} must be positive "
                                     f"semidefinite: smallest eigenvalue {eig[0]:.6g}, "
                                     f"{-eig[0] / top:.2g} of the largest", getattr(self, field))

    def _dof_rows(self, base: Path, member: Any) -> list[tuple[int, int]]:
        """``(grid, component)`` of every coordinate, from the map in any of its forms."""
        value = self.dofs
        if isinstance(value, list):
            rows: list[tuple[int, int]] = []
            for k, item in enumerate(value):
                if isinstance(item, dict) and set(item) == {"modes"}:
                    count = item["modes"]
                    if isinstance(count, bool) or not isinstance(count, int) or \
                            not 1 <= count <= MAX_MATRIX_SIZE:
                        raise FieldError(("dofs", k, "modes"), "a count of modal coordinates "
                                         f"from 1 to {MAX_MATRIX_SIZE}", count)
                    rows += [(0, 0)] * count
                    continue
                if not isinstance(item, list) or len(item) != 2:
                    raise FieldError(("dofs", k), "a DOF map item is [grid, components] "
                                     "(components digits 1-6, such as \"123456\") or "
                                     "{modes: count}", item)
                grid = _grid(item[0], ("dofs", k, 0))
                comps = str(item[1]).strip()
                if not re.fullmatch(r"[1-6]{1,6}", comps) or len(set(comps)) != len(comps):
                    raise FieldError(("dofs", k, 1), "components are digits 1-6, each once",
                                     item[1])
                rows += [(grid, int(c)) for c in comps]
            return rows
        if not isinstance(value, dict) or len(value) != 1 or \
                not isinstance(next(iter(value.values())), str) or \
                next(iter(value)) not in ("file", "key"):
            raise FieldError("dofs", "the DOF map is {file: map.csv}, {key: <member of "
                             "file>} or a list of [grid, components] and {modes: count}",
                             value)
        if "key" in value:
            where: Any = ("dofs", "key")
            shown = value["key"]
            raw = np.asarray(member)
            if raw.dtype.kind in "bc":  # a complex part or a truth value is not an id
                raise FieldError(where, f"a DOF map is n x 2 integers (grid, component), got "
                                 f"{raw.dtype} entries", shown)
            table = np.asarray(raw, dtype=float)
        else:
            table, where, shown = self._csv(base, value["file"]), ("dofs", "file"), \
                value["file"]
        if table.ndim != 2 or table.shape[1] != 2 or \
                not np.all(np.isfinite(table)) or not np.all(table == np.round(table)):
            raise FieldError(where, f"a DOF map is n x 2 integers (grid, component), got "
                             f"{' x '.join(map(str, table.shape))}", shown)
        out = []
        for k, (g, c) in enumerate(table.tolist()):  # checked before it becomes an integer
            if not 0 <= c <= 6:
                raise FieldError(where, f"row {k + 1}: component {c:g} is not 0-6", shown)
            if c and not 1 <= g <= 999_999_999:
                raise FieldError(where, f"row {k + 1}: grid {g:g} is not 1 to 999999999",
                                 shown)
            out.append((0 if c == 0 else int(g), int(c)))
        return out

    def _csv(self, base: Path, file: str) -> np.ndarray:
        path = Path(file)
        path = path if path.is_absolute() else base / path
        try:
            if not path.is_file():
                raise FieldError(("dofs", "file"), f"no such file ({path})", file)
            if path.stat().st_size > MAX_DOF_FILE:
                raise FieldError(("dofs", "file"), f"more than {MAX_DOF_FILE} bytes", file)
            text = path.read_bytes().decode("utf-8", errors="replace")
        except OSError as err:
            raise FieldError(("dofs", "file"), f"cannot be read ({err.strerror})",
                             file) from None
        rows: list[tuple[int, int]] = []
        for k, line in enumerate(text.splitlines(), start=1):
            line = line.split("#", 1)[0].strip()
            if not line:
                continue
            parts = [p for p in re.split(r"[,;\s]+", line) if p]
            if len(parts) != 2 or not all(re.fullmatch(r"\d{1,9}", p) for p in parts):
                if not rows and not any(c.isdigit() for c in line):
                    continue  # a header line
                raise FieldError(("dofs", "file"), f"line {k} of {file}: expected 'grid, "
                                 f"component' (two integers)", line[:40])
            rows.append((int(parts[0]), int(parts[1])))
        if not rows:
            raise FieldError(("dofs", "file"), "no rows 'grid, component': the file is empty "
                             "(or holds only a header or comments)", file)
        return np.asarray(rows, dtype=float).reshape(-1, 2)

    # -------------------------------------------------------------------- checks

    @model_validator(mode="after")
    def _load(self, info: ValidationInfo) -> "SuperelementSpec":
        base = Path((info.context or {}).get("base_dir", "."))
        if (self.K4 is None) != (self.W4 is None):
            raise FieldError("W4" if self.K4 is not None else "K4", "K4 (structural "
                             "damping) and W4 (rad/s) go together: K4 enters as the viscous "
                             "damping K4 / W4 (Nastran's PARAM,W4)",
                             self.K4 if self.K4 is not None else self.W4)
        units = (info.context or {}).get("units")
        mats, nbytes, member, dmig = self._read(base, units if isinstance(units, str) else "")
        self._check_matrices(mats, nbytes)
        n = mats["M"].shape[0]
        dofs = [(0, 0) if c == 0 else (g, c) for g, c in dmig] if dmig is not None else \
            self._dof_rows(base, member)
        if len(dofs) != n:
            raise FieldError("dofs", f"the DOF map has {len(dofs)} rows for the {n} "
                             f"coordinates of the matrices", self._shown_dofs())
        seen: set[tuple[int, int]] = set()
        for g, c in dofs:
            if c and (g, c) in seen:
                raise FieldError("dofs", f"grid {g} component {c} is mapped twice",
                                 self._shown_dofs())
            seen.add((g, c))
        if self.K4 is not None:
            mats["C"] = mats.get("C", np.zeros((n, n))) + mats.pop("K4") / float(self.W4 or 1)
        self._matrices, self._dofs = mats, dofs
        load_recovery(self.recovery, base, self.file, n)
        if self.grids is not None:
            self._rigid_body(mats, dofs)
        return self

    def _shown_dofs(self) -> Any:
        return self.dofs if not isinstance(self.dofs, list) else f"{len(self.dofs)} items"

    def _rigid_body(self, mats: dict[str, np.ndarray], dofs: list[tuple[int, int]]) -> None:
        grids = self.grids or {}
        boundary = sorted({g for g, c in dofs if c})
        for g in boundary:
            if g not in grids:
                raise FieldError("grids", f"boundary grid {g} of the DOF map has no position",
                                 f"{len(grids)} grids")
        for g in grids:
            if g not in boundary:
                raise FieldError(("grids", g), "not a boundary grid of the DOF map",
                                 list(grids[g]))
        D = rigid_body_vectors(dofs, grids, self.reference)
        sv = np.linalg.svd(D, compute_uv=False)
        rank = int(np.sum(sv > 1e-10 * max(float(sv.max()), 1e-300)))
        if rank < 6:
            raise FieldError("grids", f"the boundary moves in only {rank} of the 6 rigid-body "
                             f"directions (translations and rotations); rigid-body properties "
                             f"need all six (leave grids out to skip them)",
                             f"{len(grids)} grids")
        try:
            props = rigid_body_properties(mats["M"], D, self.reference)
        except ValueError as err:
            raise FieldError("M", str(err), self.M) from None
        modal = np.array([k for k, (_, c) in enumerate(dofs) if c == 0], dtype=np.int64)
        ratio = rigid_body_frequency_ratio(mats["K"], mats["M"], D, modal, DENSE_CHECK)
        props["frequency_ratio"], props["free"] = ratio, self.free
        if self.free and ratio is not None and ratio > self.rigid_tolerance:
            raise FieldError("K", f"matrix {self.K!r} holds the rigid-body motion of the "
                             f"boundary grids: its rigid-body frequencies reach {ratio:.3g} of "
                             f"the first elastic frequency, more than rigid_tolerance "
                             f"{self.rigid_tolerance:g} (a supported model: free: false)",
                             self.K)
        self._rigid = props

    # ------------------------------------------------------------------- results

    def matrix(self, name: str) -> np.ndarray | None:
        """``M``, ``K`` or ``C`` (with ``K4 / W4`` added), ``None`` for an absent ``C``."""
        return self._matrices.get(name)

    def dof_table(self) -> list[tuple[int, int]]:
        """``(grid, component)`` of each coordinate (component 0: modal)."""
        return list(self._dofs)

    def dof_labels(self) -> list[str]:
        """``"<grid>:<ux..rz>"`` for boundary coordinates, ``"mode:<k>"`` for modal ones."""
        out, k = [], 0
        for g, c in self._dofs:
            if c == 0:
                k += 1
                out.append(f"mode:{k}")
            else:
                out.append(f"{g}:{SE_COMPONENTS[c - 1]}")
        return out

    def rigid_body(self) -> dict[str, Any] | None:
        """The rigid-body properties (:func:`~substruct.case.rigid_body.rigid_body_properties`
        and ``residual``), ``None`` without ``grids``."""
        return self._rigid

    def n_dof(self) -> int:
        """Number of coordinates."""
        return self._matrices["M"].shape[0]

