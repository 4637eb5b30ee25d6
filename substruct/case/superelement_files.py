"""The files a superelement's matrices come from: OP4 (:mod:`substruct.case.op4`), NPZ
(:mod:`substruct.case.npz_files`) or Nastran bulk data holding DMIG entries
(:mod:`substruct.case.dmig`, which also gives the DOF map), an Ansys ``.full`` file
(:mod:`substruct.case.ansys_full`, with its DOF map), or one Abaqus ``.mtx`` file per
matrix (:mod:`substruct.case.abaqus_mtx`, :func:`read_abaqus_files`).

Every problem is a :class:`~substruct.case.errors.FieldError` at the field that names the
file or the matrix, one line naming the file, the matrix and what is wrong.
"""

from __future__ import annotations

import stat
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from substruct.case.abaqus_mtx import abaqus_matrices
from substruct.case.ansys_full import read_full
from substruct.case.dmig import dmig_matrices
from substruct.case.errors import CaseError, FieldError
from substruct.case.fields import MEMORY_LIMIT
from substruct.case.numbers import entry_problem
from substruct.machine import gigabytes
from substruct.case.npz_files import npz_members, read_npz
from substruct.case.op4 import Op4Error, read_op4

__all__ = ["MatrixFile", "read_matrix_file", "read_abaqus_files", "MATRIX_SUFFIXES",
           "UNITS_MEMBER", "BULK_SUFFIXES", "ABAQUS_SUFFIXES", "FULL_SUFFIXES"]

#: Endings of the bulk data files read for DMIG entries.
BULK_SUFFIXES = (".bdf", ".dat", ".nas", ".blk", ".pch")
#: Endings of Ansys FULL files (assembled stiffness and mass).
FULL_SUFFIXES = (".full",)
#: Endings of the files a superelement's matrices are read from.
MATRIX_SUFFIXES = (".op4", ".npz") + BULK_SUFFIXES + FULL_SUFFIXES
#: Endings of Abaqus matrix files (one matrix a file).
ABAQUS_SUFFIXES = (".mtx",)
#: The NPZ member that declares the units of the matrices (``substruct export`` writes it).
UNITS_MEMBER = "units"


@dataclass
class MatrixFile:
    """What :func:`read_matrix_file` read.

    Attributes:
        path: the file.
        matrices: by the key the caller gave (a field name): dense, real ``float64``.
        nbytes: bytes per number of the data (4 single, 8 double precision).
        members: the other members asked for, by name, as stored (numbers or, from an NPZ,
            strings).
        dofs: the ``(grid, component)`` of each coordinate, from DMIG entries or an Ansys
            FULL file; ``None`` otherwise.
        units: the units an NPZ archive declares in its member ``units`` (one string, as
            ``substruct export`` writes the case's), ``None`` if it declares none.
    """

    path: Path
    matrices: dict[str, np.ndarray]
    nbytes: int
    members: dict[str, np.ndarray] = field(default_factory=dict)
    dofs: list[tuple[int, int]] | None = None
    units: str | None = None


def _path(file: str, base: Path, loc: Any, suffixes: Sequence[str]) -> Path:
    path = Path(file)
    path = path if path.is_absolute() else base / path
    if path.suffix.lower() not in suffixes:
        raise FieldError(loc, f"superelement matrices are in a file ending in "
                         f"{', '.join(suffixes)}", file)
    try:
        mode = path.stat().st_mode
    except OSError:
        raise FieldError(loc, f"no such file ({path})", file) from None
    if not stat.S_ISREG(mode):
        raise FieldError(loc, f"{path} is not a regular file", file)
    return path


def read_matrix_file(file: str, base: Path, loc: Any, names: Mapping[str, str],
                     members: Sequence[str] = (), where: Mapping[str, Any] | None = None,
                     suffixes: Sequence[str] = MATRIX_SUFFIXES) -> MatrixFile:
    """Read the matrices ``names`` (key -> name in the file) and the ``members`` of ``file``.

    Args:
        file: as written in the case (relative to ``base``).
        loc: the field that names the file (its errors).
        names: the real matrices wanted, by key; OP4 and DMIG names match without regard to
            case.
        members: more members read as stored (a DOF map, row labels); not from bulk data.
        where: the field of each key (complex-matrix errors), the key itself if absent.
        suffixes: the endings accepted.

    Raises:
        FieldError: at ``loc`` for a file that cannot be read or lacks a member; at the key's
            field for a complex matrix.
    """
    path = _path(file, base, loc, suffixes)
    suffix = path.suffix.lower()
    wanted = list(dict.fromkeys(list(names.values()) + list(members)))
    where = where or {}
    try:
        if suffix == ".op4":
            got = {k.upper(): m for k, m in read_op4(path, wanted).items()}
            out = {}
            for key, name in names.items():
                m = got[name.upper()]
                if m.is_complex:
                    raise FieldError(where.get(key, key), f"matrix {name!r} of {path.name} is "
                                     "complex; a superelement's matrices are real", name)
                out[key] = m.dense()
                found = entry_problem(out[key])
                if found is not None:
                    (i, j), value, problem = found
                    raise FieldError(where.get(key, key), f"matrix {name!r} of {path.name}: "
                                     f"entry ({i + 1}, {j + 1}): {problem}", value)
            nbytes = 4 if any(got[n.upper()].type == 1 for n in names.values()) else 8
            extra = {m: got[m.upper()].dense() for m in members}
            return MatrixFile(path, out, nbytes, extra)
        if suffix == ".npz":
            declared = UNITS_MEMBER in npz_members(path) and UNITS_MEMBER not in wanted
            arrays = read_npz(path, wanted + [UNITS_MEMBER] * declared,
                              {n: np.float64 for n in names.values()})
            units = _npz_units(path, arrays[UNITS_MEMBER]) if declared else None
            return MatrixFile(path, {k: arrays[n] for k, n in names.items()}, 8,
                              {m: arrays[m] for m in members}, units=units)
    except (Op4Error, ValueError) as err:
        if isinstance(err, FieldError):
            raise
        raise FieldError(loc, " ".join(str(err).split()), file) from None
    if suffix in FULL_SUFFIXES:
        return _read_full(path, file, loc, names, members, where)
    if members:
        raise FieldError(loc, f"{path.name} is bulk data: its DMIG entries hold square "
                         f"matrices only, not {', '.join(members)}", file)
    try:
        dofs, mats, nbytes = dmig_matrices(path, path.name, list(names.values()))
    except CaseError as err:
        raise FieldError(loc, str(err)) from None
    return MatrixFile(path, {k: mats[n] for k, n in names.items()}, nbytes, {}, dofs)


def _npz_units(path: Path, value: np.ndarray) -> str:
    if value.dtype.kind != "U" or value.ndim != 0 or len(str(value)) > 200:
        raise ValueError(f"{path.name}: member {UNITS_MEMBER!r} (the units of the matrices) is "
                         f"one string, got {value.dtype} {' x '.join(map(str, value.shape))}")
    return str(value).strip()


def _read_full(path: Path, file: str, loc: Any, names: Mapping[str, str],
               members: Sequence[str], where: Mapping[str, Any]) -> MatrixFile:
    """The stiffness ``K`` and mass ``M`` of an Ansys FULL file, dense, with its DOF map."""
    if members:
        raise FieldError(loc, f"{path.name} is an Ansys FULL file: it holds K and M with "
                         f"their DOF map, not {', '.join(members)}", file)
    for key, name in names.items():
        if key not in ("M", "K") or name.upper() != key:
            raise FieldError(where.get(key, key), f"an Ansys FULL file holds the matrices K "
                             f"and M only: {key} of {path.name} must be {key!r}"
                             if key in ("M", "K") else f"an Ansys FULL file holds the "
                             f"matrices K and M only, not {key}", name)
    try:
        got = read_full(path, path.name)
    except CaseError as err:
        raise FieldError(loc, str(err)) from None
    n = len(got.dofs)
    need = 2 * 8.0 * n * n
    if need > MEMORY_LIMIT:
        raise FieldError(loc, f"{path.name}: {n} coordinates: its dense K and M would need "
                         f"{gigabytes(need)}, more than the {gigabytes(MEMORY_LIMIT)} allowed",
                         file)
    return MatrixFile(path, {"K": got.K.toarray(), "M": got.M.toarray()}, 8, {}, got.dofs)


def read_abaqus_files(files: Mapping[str, str], base: Path,
                      dofs: Sequence[tuple[int, int]] | None) -> MatrixFile:
    """Read one Abaqus matrix file per key (a field name: ``M``, ``K`` ...; the file as
    written in the case, relative to ``base``).

    Args:
        dofs: the DOF map of files in the coordinate layout (``None`` for the nodes layout,
            whose DOF map is read from the files and returned as ``dofs``).

    Raises:
        FieldError: at the key of the file at fault, one line naming the file, the line and
            the problem.
    """
    paths = {key: _path(file, base, key, ABAQUS_SUFFIXES) for key, file in files.items()}
    try:
        table, mats = abaqus_matrices(paths, {k: p.name for k, p in paths.items()}, dofs)
    except CaseError as err:
        key = next((k for k, p in paths.items() if p.name == err.source), next(iter(paths)))
        raise FieldError(key, str(err)) from None
    first = next(iter(paths.values()))
    return MatrixFile(first, mats, 8, {}, table if dofs is None else None)
