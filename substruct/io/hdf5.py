"""Results files: a :class:`~substruct.run.result.Result` to HDF5 and back.

The layout is documented in ``docs/results.md``; in short::

    /                      attrs: format, format_version, substruct_version, case_name,
                                  case_yaml, created, units (+ scalar entries of Result.attrs)
    /modes/                omega, eigenvalues, damping_ratio, shapes, constraint_residual,
                           spurious_eigenvalues, spurious_reason; attrs method, agreement_<m>,
                           solver, tolerance
    /variants/<name>/      same as /modes (attr ``name`` holds the name verbatim)
    /frf/                  omega, H, inputs, outputs; attrs method, agreement_<m>,
                           constraint_residual, tolerance
    /model/                dof_labels, substructure_names, substructure_kinds, offsets,
                           A (CSR group), b, R (CSR group), constraint_labels
    /model/drawings/<i>/   points, interp (CSR group), cells/<k> (attr cell_type),
                           glyph_names, glyph_indices; attrs name, kind

:func:`save` writes to a temporary file in the target directory and renames it over the
target, so an interrupted run never leaves a broken (or half-overwritten) result.
:func:`load` returns the same objects that were saved.
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import os
import tempfile
from pathlib import Path
from typing import Any, Iterator

import h5py
import numpy as np
import scipy.sparse as sp

from substruct import __version__
from substruct.builder.drawing import Drawing
from substruct.analysis.results import DEFAULT_TOLERANCE, Modes, Receptance
from substruct.run.result import ModelInfo, Result

__all__ = ["save", "load", "atomic_path", "FORMAT", "FORMAT_VERSION"]

#: Value of the root attribute ``format`` that marks a substruct result file.
FORMAT = "substruct-result"
#: Layout version; bumped when the layout changes incompatibly.
FORMAT_VERSION = 1
#: Root attributes that :func:`load` turns into fields (not into ``Result.attrs``).
_RESERVED = ("format", "format_version", "case_name", "case_yaml")
#: Root attributes :func:`save` always writes itself (never taken from ``Result.attrs``).
_OWN = _RESERVED + ("substruct_version", "created")
_DEFAULT_UNITS = "consistent units of the case file; omega in rad/s"

_STR = h5py.string_dtype("utf-8")


# ----------------------------------------------------------------------------- writing


def save(result: Result, path: str | os.PathLike) -> Path:
    """Write ``result`` to the HDF5 file ``path`` atomically; return the path.

    The file is written under a temporary name (``*.h5.part``) in the target directory and
    renamed over ``path`` only once complete.  On any error the temporary file is removed and
    an existing file at ``path`` is left untouched.  Missing parent directories are created.
    """
    path = Path(path)
    with atomic_path(path, suffix=".h5.part") as tmp:
        with h5py.File(tmp, "w", track_order=True) as f:
            _write_root(f, result)
            _write_model(f.create_group("model", track_order=True), result.model)
            if result.modes is not None:
                _write_modes(f.create_group("modes", track_order=True), result.modes)
            if result.variants:
                group = f.create_group("variants", track_order=True)
                used: set[str] = set()
                for name, modes in result.variants.items():
                    g = group.create_group(_group_name(str(name), used), track_order=True)
                    g.attrs["name"] = str(name)
                    _write_modes(g, modes)
            if result.frf is not None:
                _write_frf(f.create_group("frf", track_order=True), result.frf)
    return path


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, suffix: str = ".part") -> Iterator[Path]:
    """Yield a temporary path beside ``path``; rename it to ``path`` if the block succeeds.

    The temporary file is created in the target directory (so the final ``os.replace`` is an
    atomic rename on the same file system) with the permissions a new file would get.  If the
    block raises, the temporary file is removed and ``path`` is untouched.  Missing parent
    directories are created.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, name = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=suffix)
    os.close(fd)
    tmp = Path(name)
    try:
        yield tmp
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _group_name(name: str, used: set[str]) -> str:
    """An HDF5-safe, unique group name for ``name`` ('/' and '.' alone are not allowed)."""
    safe = name.replace("/", "_") or "_"
    if safe in (".", ".."):
        safe = "_" + safe
    candidate, k = safe, 1
    while candidate in used:
        k += 1
        candidate = f"{safe}_{k}"
    used.add(candidate)
    return candidate


def _attr_value(value: Any) -> Any | None:
    """``value`` if it can be a root attribute (a string or a real number), else ``None``."""
    if isinstance(value, (str, bool, np.bool_)):
        return value if isinstance(value, str) else bool(value)
    if isinstance(value, (int, float, np.integer, np.floating)):
        return value
    return None


def _write_root(f: h5py.File, result: Result) -> None:
    f.attrs["format"] = FORMAT
    f.attrs["format_version"] = FORMAT_VERSION
    f.attrs["substruct_version"] = __version__
    f.attrs["created"] = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")
    f.attrs["units"] = _DEFAULT_UNITS
    for key, value in result.attrs.items():
        v = _attr_value(value)
        if v is not None and str(key) not in _OWN:
            f.attrs[str(key)] = v
    f.attrs["case_name"] = str(result.case_name)
    f.attrs["case_yaml"] = str(result.case_yaml)


def _strings(group: h5py.Group, name: str, values) -> None:
    group.create_dataset(name, data=np.array([str(v) for v in values], dtype=object),
                         dtype=_STR, shape=(len(values),))


def _array(group: h5py.Group, name: str, values, units: str | None = None) -> None:
    ds = group.create_dataset(name, data=np.asarray(values))
    if units:
        ds.attrs["units"] = units


def _csr(group: h5py.Group, name: str, matrix) -> None:
    m = sp.csr_array(matrix)
    g = group.create_group(name)
    g.attrs["format"] = "csr"
    g.create_dataset("data", data=m.data)
    g.create_dataset("indices", data=m.indices.astype(np.int64))
    g.create_dataset("indptr", data=m.indptr.astype(np.int64))
    g.create_dataset("shape", data=np.asarray(m.shape, dtype=np.int64))


def _write_agreement(group: h5py.Group, agreement: dict[str, float]) -> None:
    for method, value in agreement.items():
        group.attrs[f"agreement_{method}"] = float(value)


def _write_modes(g: h5py.Group, modes: Modes) -> None:
    g.attrs["method"] = str(modes.method)
    g.attrs["solver"] = str(modes.solver)
    g.attrs["tolerance"] = float(modes.tolerance)
    _write_agreement(g, modes.agreement)
    _array(g, "omega", np.asarray(modes.omega, dtype=float), "rad/s")
    _array(g, "eigenvalues", np.asarray(modes.eigenvalues, dtype=complex), "rad/s")
    _array(g, "damping_ratio", np.asarray(modes.damping_ratio, dtype=float), "1")
    _array(g, "shapes", np.asarray(modes.shapes))
    _array(g, "constraint_residual", np.asarray(modes.residual, dtype=float), "1")
    _array(g, "spurious_eigenvalues", np.asarray(modes.spurious, dtype=complex), "rad/s")
    _strings(g, "spurious_reason", list(modes.spurious_reason))


def _write_frf(g: h5py.Group, frf: Receptance) -> None:
    g.attrs["method"] = str(frf.method)
    g.attrs["constraint_residual"] = float(frf.constraint_residual)
    g.attrs["tolerance"] = float(frf.tolerance)
    _write_agreement(g, frf.agreement)
    _array(g, "omega", np.asarray(frf.omega, dtype=float), "rad/s")
    _array(g, "H", np.asarray(frf.H))
    _strings(g, "inputs", list(frf.inputs))
    _strings(g, "outputs", list(frf.outputs))


def _write_model(g: h5py.Group, model: ModelInfo) -> None:
    _strings(g, "dof_labels", model.dof_labels)
    _strings(g, "substructure_names", model.substructure_names)
    _strings(g, "substructure_kinds", model.substructure_kinds)
    _array(g, "offsets", np.asarray(model.offsets, dtype=np.int64))
    _csr(g, "A", model.A)
    _array(g, "b", np.asarray(model.b))
    _csr(g, "R", model.R)
    _strings(g, "constraint_labels", model.constraint_labels)
    drawings = g.create_group("drawings", track_order=True)
    for i, d in enumerate(model.drawings):
        dg = drawings.create_group(str(i), track_order=True)
        dg.attrs["name"] = str(d.name)
        dg.attrs["kind"] = str(d.kind)
        _array(dg, "points", np.asarray(d.points, dtype=float).reshape(-1, 3))
        _csr(dg, "interp", d.interp)
        cells = dg.create_group("cells", track_order=True)
        for k, (cell_type, conn) in enumerate(d.cells):
            ds = cells.create_dataset(str(k), data=np.asarray(conn, dtype=np.int64))
            ds.attrs["cell_type"] = str(cell_type)
        _strings(dg, "glyph_names", list(d.glyphs))
        _array(dg, "glyph_indices", np.asarray(list(d.glyphs.values()), dtype=np.int64))


# ----------------------------------------------------------------------------- reading


class _Foreign(Exception):
    """Raised inside :func:`load` for anything that is not a substruct result."""


def load(path: str | os.PathLike) -> Result:
    """Read a result written by :func:`save`.

    Raises:
        FileNotFoundError: ``path`` does not exist.
        ValueError: ``"<path>: not a substruct result: <why>"`` for a file that is not HDF5,
            is truncated, or lacks the substruct layout.
    """
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such file")
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        raise ValueError(f"{path}: not a substruct result: not a readable HDF5 file "
                         f"({exc})") from None
    try:
        with f:
            return _read(f)
    except _Foreign as exc:
        raise ValueError(f"{path}: not a substruct result: {exc}") from None
    except (KeyError, OSError, TypeError, ValueError) as exc:
        raise ValueError(f"{path}: not a substruct result: damaged or incomplete "
                         f"({type(exc).__name__}: {exc})") from None


def _read(f: h5py.File) -> Result:
    fmt = f.attrs.get("format")
    if fmt != FORMAT:
        raise _Foreign(f"root attribute 'format' is {fmt!r}, expected {FORMAT!r}")
    version = int(f.attrs.get("format_version", -1))
    if version > FORMAT_VERSION:
        raise _Foreign(f"format_version {version} is newer than this program reads "
                       f"({FORMAT_VERSION}); upgrade substruct")
    if "model" not in f:
        raise _Foreign("no /model group")
    attrs = {k: _plain(v) for k, v in f.attrs.items() if k not in _RESERVED}
    variants = {}
    if "variants" in f:
        for gname, g in f["variants"].items():
            variants[str(g.attrs.get("name", gname))] = _read_modes(g)
    return Result(
        case_name=str(f.attrs["case_name"]),
        case_yaml=str(f.attrs["case_yaml"]),
        model=_read_model(f["model"]),
        modes=_read_modes(f["modes"]) if "modes" in f else None,
        frf=_read_frf(f["frf"]) if "frf" in f else None,
        variants=variants,
        attrs=attrs,
    )


def _plain(value: Any) -> Any:
    """h5py attribute values as plain Python scalars."""
    if isinstance(value, bytes):
        return value.decode("utf-8")
    if isinstance(value, np.generic):
        return value.item()
    return value


def _read_strings(g: h5py.Group, name: str) -> list[str]:
    return [str(s) for s in g[name].asstr()[()]]


def _read_csr(g: h5py.Group) -> sp.csr_array:
    shape = tuple(int(s) for s in g["shape"][()])
    return sp.csr_array((g["data"][()], g["indices"][()], g["indptr"][()]), shape=shape)


def _read_agreement(g: h5py.Group) -> dict[str, float]:
    prefix = "agreement_"
    return {k[len(prefix):]: float(v) for k, v in g.attrs.items() if k.startswith(prefix)}


def _read_modes(g: h5py.Group) -> Modes:
    return Modes(
        method=str(g.attrs["method"]),
        eigenvalues=g["eigenvalues"][()],
        omega=g["omega"][()],
        damping_ratio=g["damping_ratio"][()],
        shapes=g["shapes"][()],
        residual=g["constraint_residual"][()],
        spurious=g["spurious_eigenvalues"][()],
        spurious_reason=_read_strings(g, "spurious_reason"),
        agreement=_read_agreement(g),
        solver=str(g.attrs.get("solver", "")),
        tolerance=float(g.attrs.get("tolerance", DEFAULT_TOLERANCE)),
    )


def _read_frf(g: h5py.Group) -> Receptance:
    return Receptance(
        method=str(g.attrs["method"]),
        omega=g["omega"][()],
        H=g["H"][()],
        inputs=_read_strings(g, "inputs"),
        outputs=_read_strings(g, "outputs"),
        agreement=_read_agreement(g),
        constraint_residual=float(g.attrs["constraint_residual"]),
        tolerance=float(g.attrs.get("tolerance", DEFAULT_TOLERANCE)),
    )


def _numbered(g: h5py.Group):
    return [g[k] for k in sorted(g, key=int)]


def _read_model(g: h5py.Group) -> ModelInfo:
    drawings = []
    for dg in _numbered(g["drawings"]):
        cells = [(str(ds.attrs["cell_type"]), ds[()]) for ds in _numbered(dg["cells"])]
        names = _read_strings(dg, "glyph_names")
        indices = dg["glyph_indices"][()]
        drawings.append(Drawing(
            name=str(dg.attrs["name"]), kind=str(dg.attrs["kind"]), points=dg["points"][()],
            cells=cells, interp=_read_csr(dg["interp"]),
            glyphs={n: int(i) for n, i in zip(names, indices)},
        ))
    return ModelInfo(
        dof_labels=_read_strings(g, "dof_labels"),
        substructure_names=_read_strings(g, "substructure_names"),
        substructure_kinds=_read_strings(g, "substructure_kinds"),
        offsets=g["offsets"][()],
        A=_read_csr(g["A"]),
        b=g["b"][()],
        R=_read_csr(g["R"]),
        constraint_labels=_read_strings(g, "constraint_labels"),
        drawings=drawings,
    )
