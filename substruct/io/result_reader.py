"""Reading a result file back, trusting nothing in it.

:func:`load` reads only the objects of the documented layout (``docs/results.md``), through
hard links only (a soft or external link is refused: it could loop or lead to another file),
and checks every dataset's rank, kind and declared size from its metadata before reading it:
all datasets together at most :data:`MAX_RESULT_BYTES`, groups at most :data:`MAX_MEMBERS`
members.  Once read, the parts must agree: ``n`` coordinates in ``dof_labels``, ``offsets``,
the columns of ``A``, ``R``, the drawings' interpolations and the rows of the mode shapes;
``k`` modes in every per-mode dataset; CSR matrices with ordered row pointers and column
indices in range; cells of a known type, with their number of nodes, pointing at points that
exist; every value finite (no NaN, no inf) in the frequencies, eigenvalues, damping ratios,
shapes and residuals of the modes, the frequencies and receptances of ``/frf``, the
transient histories, every matrix, ``b`` and the drawings' points, and in the numbers of the
checks (agreements, tolerances): a result is written with finite values only, so anything
else is a corrupt file, refused by every command that reads results (``info``, ``export``,
``compare``) before it prints or writes a number.  Anything else is a one-line
:class:`ValueError` naming the file and the dataset.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

import h5py
import numpy as np
import scipy.sparse as sp

from substruct.analysis.results import DEFAULT_TOLERANCE, Modes, Receptance
from substruct.builder.drawing import Drawing
from substruct.io.channels_hdf5 import read_channel_geometry
from substruct.io.recovery_hdf5 import read_recovery
from substruct.io.result_format import FORMAT, FORMAT_VERSION, RESERVED_ATTRS
from substruct.io.spec_reader import read_random, read_srs
from substruct.io.tpa_hdf5 import read_semm, read_tpa
from substruct.io.transient_hdf5 import read_transient
from substruct.io.vp_hdf5 import read_monte_carlo, read_virtual_points
from substruct.run.result import ModelInfo, Result
from substruct.run.spec_results import BaseFrf

__all__ = ["load", "FORMAT", "FORMAT_VERSION", "RESERVED_ATTRS", "MAX_RESULT_BYTES",
           "MAX_MEMBERS", "CELL_NODES"]

#: Bytes all datasets of a result may declare together (checked before reading any).
MAX_RESULT_BYTES = 1_000_000_000
#: Members a group of the layout may have (variants, drawings, cell blocks).
MAX_MEMBERS = 10_000
#: Cell types a drawing may hold and their number of nodes (meshio names).
CELL_NODES = {"vertex": 1, "line": 2, "line3": 3, "triangle": 3, "triangle6": 6, "quad": 4,
              "quad8": 8, "quad9": 9, "tetra": 4, "tetra10": 10, "hexahedron": 8,
              "hexahedron20": 20, "hexahedron27": 27, "wedge": 6, "pyramid": 5}


class _Bad(Exception):
    """A file that is not a (whole) substruct result; the message says what and where."""


class _Reader:
    def __init__(self) -> None:
        self.budget = MAX_RESULT_BYTES

    def node(self, g: h5py.Group, name: str, kind: type) -> Any:
        where = f"{g.name.rstrip('/')}/{name}"
        link = g.get(name, getlink=True)
        if link is None:
            raise _Bad(f"damaged or incomplete: no {where}")
        if not isinstance(link, h5py.HardLink):
            raise _Bad(f"{where} is a {type(link).__name__}; a result file holds no links")
        obj = g[name]
        if not isinstance(obj, kind):
            raise _Bad(f"{where} is not a {'group' if kind is h5py.Group else 'dataset'}")
        return obj

    def members(self, g: h5py.Group, name: str) -> list[tuple[str, h5py.Group]]:
        group = self.node(g, name, h5py.Group)
        if len(group) > MAX_MEMBERS:
            raise _Bad(f"{group.name} has {len(group)} members, more than {MAX_MEMBERS}")
        return [(k, self.node(group, k, h5py.Group)) for k in group]

    def array(self, g: h5py.Group, name: str, kinds: str, ndim: int,
              shape: tuple[int | None, ...] | None = None, finite: bool = False
              ) -> np.ndarray:
        """The dataset ``g/name`` checked (rank, kind, declared size, shape) before it is
        read; ``finite``: every value must be finite (no NaN, no inf)."""
        ds = self.node(g, name, h5py.Dataset)
        if ds.shape is None or len(ds.shape) != ndim:
            raise _Bad(f"{ds.name} has shape {ds.shape}, expected {ndim} dimension(s)")
        is_str = h5py.check_string_dtype(ds.dtype) is not None
        kind = "s" if is_str else ds.dtype.kind
        if kind not in kinds:
            raise _Bad(f"{ds.name} holds {ds.dtype} values")
        size = math.prod(ds.shape) * (16 if is_str else ds.dtype.itemsize)
        if size > self.budget:
            raise _Bad(f"{ds.name} declares {ds.shape} x {ds.dtype} ({size / 1e9:.3g} GB), "
                       f"more than the {MAX_RESULT_BYTES / 1e9:g} GB a result file may hold "
                       "(MAX_RESULT_BYTES in substruct/io/result_reader.py)")
        self.budget -= size
        if shape is not None:
            for got, want in zip(ds.shape, shape):
                if want is not None and got != want:
                    raise _Bad(f"{ds.name} has shape {ds.shape}, expected "
                               f"{tuple('*' if w is None else w for w in shape)}")
        data = np.asarray(ds.asstr()[()] if is_str else ds[()])
        if finite:
            _require_finite(ds.name, data)
        return data

    def strings(self, g: h5py.Group, name: str, count: int | None = None) -> list[str]:
        """Labels: each at most :data:`MAX_RESULT_LABEL` characters (the writer stores the names of
        a case, which are short; control characters are escaped where they are shown)."""
        out = [str(s) for s in self.array(g, name, "s", 1, (count,))]
        for k, s in enumerate(out):
            if len(s) > MAX_RESULT_LABEL:
                raise _Bad(f"{g.name}/{name}[{k}] is a label of {len(s)} characters, more "
                           f"than {MAX_RESULT_LABEL}")
        return out

    def csr(self, g: h5py.Group, name: str, rows: int | None, cols: int) -> sp.csr_array:
        m = self.node(g, name, h5py.Group)
        shape = self.array(m, "shape", "iu", 1, (2,))
        data = self.array(m, "data", "fiuc", 1, finite=True)
        indices = self.array(m, "indices", "iu", 1, (len(data),))
        indptr = self.array(m, "indptr", "iu", 1)
        r, c = int(shape[0]), int(shape[1])
        if c != cols or (rows is not None and r != rows) or len(indptr) != r + 1:
            raise _Bad(f"{m.name} is {r} x {c} with {len(indptr)} row pointers, expected "
                       f"{'*' if rows is None else rows} x {cols}")
        if len(indptr) and (indptr[0] != 0 or indptr[-1] != len(data)
                            or np.any(np.diff(indptr.astype(np.int64)) < 0)):
            raise _Bad(f"{m.name}/indptr is not a row pointer of {len(data)} entries")
        if len(indices) and (indices.min() < 0 or indices.max() >= c):
            raise _Bad(f"{m.name}/indices holds column {int(indices.max())} of a matrix of "
                       f"{c} columns")
        return sp.csr_array((data, indices.astype(np.int64), indptr.astype(np.int64)),
                            shape=(r, c))


def _no_negative_frequency(g: h5py.Group, omega: np.ndarray) -> None:
    """Refuse a negative frequency of a response grid (the writer stores the case's grid,
    whose frequencies are never negative)."""
    if omega.size and float(omega.min()) < 0:
        raise _Bad(f"{g.name}/omega holds the negative frequency {float(omega.min())}")


def _require_finite(where: str, values: np.ndarray) -> None:
    """Refuse an array with a NaN or an infinite value (a corrupt file: the writer stores
    finite results only), naming the first one and how many there are."""
    bad = ~np.isfinite(values)
    if bad.any():
        first = int(np.flatnonzero(bad.ravel())[0])
        raise _Bad(f"{where} holds values that are not finite: {values.ravel()[first]} at "
                   f"index {first} ({int(bad.sum())} of {values.size})")


def _number(attrs: dict[str, Any], key: str, where: str, default: float | None = None
            ) -> float:
    """The attribute ``key`` as a finite float."""
    value = float(attrs[key] if default is None else attrs.get(key, default))
    if not math.isfinite(value):
        raise _Bad(f"{where} attribute {key} is not finite, got {value}")
    return value


#: Longest label read from a result file (characters).
MAX_RESULT_LABEL = 1000


def _text(value: Any) -> str:
    return value.decode("utf-8", "replace") if isinstance(value, bytes) else str(value)


def _plain(value: Any) -> Any:
    """h5py attribute values as plain Python scalars."""
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace")
    if isinstance(value, np.generic):
        return value.item()
    return value


def _scalar_attrs(obj: h5py.HLObject) -> dict[str, Any]:
    out = {}
    for key in obj.attrs:
        if obj.attrs.get_id(key).shape == ():  # arrays are not part of the layout
            out[str(key)] = _plain(obj.attrs[key])
    return out


def _agreement(attrs: dict[str, Any], where: str) -> dict[str, float]:
    prefix = "agreement_"
    return {k[len(prefix):]: _number(attrs, k, where) for k in attrs if k.startswith(prefix)}


def _modes(rd: _Reader, g: h5py.Group, n: int) -> Modes:
    attrs = _scalar_attrs(g)
    omega = rd.array(g, "omega", "f", 1, finite=True)
    k = len(omega)
    spurious = rd.array(g, "spurious_eigenvalues", "fc", 1)  # roots set aside: may be inf
    return Modes(
        method=_text(attrs["method"]), omega=omega,
        eigenvalues=rd.array(g, "eigenvalues", "fc", 1, (k,), finite=True),
        damping_ratio=rd.array(g, "damping_ratio", "f", 1, (k,), finite=True),
        shapes=rd.array(g, "shapes", "fc", 2, (n, k), finite=True),
        residual=rd.array(g, "constraint_residual", "f", 1, (k,), finite=True),
        spurious=spurious, spurious_reason=rd.strings(g, "spurious_reason", len(spurious)),
        agreement=_agreement(attrs, g.name), solver=_text(attrs.get("solver", "")),
        tolerance=_number(attrs, "tolerance", g.name, DEFAULT_TOLERANCE))


def _frf(rd: _Reader, g: h5py.Group) -> Receptance:
    attrs = _scalar_attrs(g)
    omega = rd.array(g, "omega", "f", 1, finite=True)
    _no_negative_frequency(g, omega)
    inputs, outputs = rd.strings(g, "inputs"), rd.strings(g, "outputs")
    return Receptance(
        method=_text(attrs["method"]), omega=omega,
        H=rd.array(g, "H", "fc", 3, (len(omega), len(outputs), len(inputs)), finite=True),
        inputs=inputs, outputs=outputs, agreement=_agreement(attrs, g.name),
        constraint_residual=_number(attrs, "constraint_residual", g.name),
        tolerance=_number(attrs, "tolerance", g.name, DEFAULT_TOLERANCE),
        quantity=_text(attrs.get("quantity", "receptance")))


def _base_frf(rd: _Reader, g: h5py.Group) -> BaseFrf:
    """``/base_frf`` (:func:`substruct.io.spec_hdf5.write_base_frf`)."""
    attrs = _scalar_attrs(g)
    omega = rd.array(g, "omega", "f", 1, finite=True)
    _no_negative_frequency(g, omega)
    inputs, outputs = rd.strings(g, "inputs"), rd.strings(g, "outputs")
    agreement = {}
    if g.get("agreement", getlink=True) is not None:
        agreement = {k: _number(_scalar_attrs(a), k, a.name)
                     for a in [rd.node(g, "agreement", h5py.Group)] for k in a.attrs}
    return BaseFrf(
        omega=omega, outputs=outputs, inputs=inputs,
        quantity=_text(attrs.get("quantity", "acceleration")),
        T=rd.array(g, "transmissibility", "fc", 3, (len(omega), len(outputs), len(inputs)),
                   finite=True),
        method=_text(attrs.get("method", "")), agreement=agreement,
        tolerance=_number(attrs, "tolerance", g.name, DEFAULT_TOLERANCE))


def _numbered(members: list[tuple[str, h5py.Group]], where: str) -> list[h5py.Group]:
    if any(not k.isdigit() for k, _ in members):
        raise _Bad(f"{where} holds a member that is not numbered")
    return [g for _, g in sorted(members, key=lambda kv: int(kv[0]))]


def _drawing(rd: _Reader, dg: h5py.Group, n: int) -> Drawing:
    attrs = _scalar_attrs(dg)
    points = rd.array(dg, "points", "fiu", 2, (None, 3)).astype(float)
    if not np.all(np.isfinite(points)):
        raise _Bad(f"{dg.name}/points holds values that are not finite")
    N = len(points)
    cells = []
    blocks = rd.node(dg, "cells", h5py.Group)
    if len(blocks) > MAX_MEMBERS:
        raise _Bad(f"{blocks.name} has {len(blocks)} members, more than {MAX_MEMBERS}")
    for name in sorted(blocks, key=lambda k: int(k) if k.isdigit() else -1):
        if not name.isdigit():
            raise _Bad(f"{blocks.name} holds a member that is not numbered")
        ds = rd.node(blocks, name, h5py.Dataset)
        cell_type = _text(ds.attrs.get("cell_type", ""))
        if cell_type not in CELL_NODES:
            raise _Bad(f"{ds.name}: unknown cell type {cell_type[:40]!r} (known: "
                       f"{', '.join(CELL_NODES)})")
        conn = rd.array(blocks, name, "iu", 2, (None, CELL_NODES[cell_type])).astype(np.int64)
        if conn.size and (conn.min() < 0 or conn.max() >= N):
            bad = int(conn.max() if conn.max() >= N else conn.min())
            raise _Bad(f"{ds.name}: a {cell_type} cell points at point {bad}, of {N} points")
        cells.append((cell_type, conn))
    names = rd.strings(dg, "glyph_names")
    indices = rd.array(dg, "glyph_indices", "iu", 1, (len(names),)).astype(np.int64)
    if indices.size and (indices.min() < 0 or indices.max() >= N):
        raise _Bad(f"{dg.name}/glyph_indices points past the {N} points")
    return Drawing(name=_text(attrs["name"]), kind=_text(attrs["kind"]), points=points,
                   cells=cells, interp=rd.csr(dg, "interp", 3 * N, n),
                   glyphs={a: int(i) for a, i in zip(names, indices)},
                   rotations=rd.csr(dg, "rotations", 3 * N, n) if "rotations" in dg else None)


def _model(rd: _Reader, g: h5py.Group) -> ModelInfo:
    labels = rd.strings(g, "dof_labels")
    n = len(labels)
    names = rd.strings(g, "substructure_names")
    kinds = rd.strings(g, "substructure_kinds", len(names))
    offsets = rd.array(g, "offsets", "iu", 1, (len(names) + 1,)).astype(np.int64)
    if offsets[0] != 0 or offsets[-1] != n or np.any(np.diff(offsets) < 0):
        raise _Bad(f"{g.name}/offsets does not split the {n} coordinates, got "
                   f"{offsets[:8].tolist()}")
    A = rd.csr(g, "A", None, n)
    m = A.shape[0]
    drawings = _numbered(rd.members(g, "drawings"), f"{g.name}/drawings")
    return ModelInfo(
        dof_labels=labels, substructure_names=names, substructure_kinds=kinds,
        offsets=offsets, A=A, b=rd.array(g, "b", "fiu", 1, (m,), finite=True),
        R=rd.csr(g, "R", m, n),
        constraint_labels=rd.strings(g, "constraint_labels", m),
        drawings=[_drawing(rd, dg, n) for dg in drawings],
        matrices={k: rd.csr(g, k, n, n) for k in ("M", "K", "C") if k in g})


def _read(f: h5py.File) -> Result:
    root = _scalar_attrs(f)
    fmt = root.get("format")
    if fmt != FORMAT:
        raise _Bad(f"root attribute 'format' is {fmt!r}, expected {FORMAT!r}")
    version = int(root.get("format_version", -1))
    if version > FORMAT_VERSION:
        raise _Bad(f"format_version {version} is newer than this program reads "
                   f"({FORMAT_VERSION}); upgrade substruct")
    if "model" not in f:
        raise _Bad("no /model group")
    rd = _Reader()
    model = _model(rd, rd.node(f, "model", h5py.Group))
    n = len(model.dof_labels)
    modes = _modes(rd, rd.node(f, "modes", h5py.Group), n) if "modes" in f else None
    variants = {}
    if f.get("variants", getlink=True) is not None:
        for gname, g in rd.members(f, "variants"):
            variants[_text(g.attrs.get("name", gname))] = _modes(rd, g, n)
    frf = _frf(rd, rd.node(f, "frf", h5py.Group)) if "frf" in f else None
    transient = None
    if "transient" in f:
        try:
            transient = read_transient(rd, rd.node(f, "transient", h5py.Group), n)
        except ValueError as exc:
            raise _Bad(str(exc)) from None
    recovery = []
    if f.get("recovery", getlink=True) is not None:
        groups = _numbered(rd.members(f, "recovery"), "/recovery")
        try:
            recovery = read_recovery(rd, groups, None if modes is None else len(modes.omega),
                                     None if transient is None else transient.t)
        except ValueError as exc:
            raise _Bad(str(exc)) from None
    result = Result(case_name=_text(root["case_name"]), case_yaml=_text(root["case_yaml"]),
                    model=model, modes=modes, frf=frf, transient=transient, variants=variants,
                    recovery=recovery,
                    base_frf=_base_frf(rd, rd.node(f, "base_frf", h5py.Group))
                    if "base_frf" in f else None,
                    attrs={k: v for k, v in root.items() if k not in RESERVED_ATTRS})
    try:
        if "random" in f:
            result.random = read_random(rd, rd.node(f, "random", h5py.Group))
        if "srs" in f:
            result.srs = read_srs(rd, rd.node(f, "srs", h5py.Group))
    except ValueError as exc:
        raise _Bad(str(exc)) from None
    _testlab(rd, f, result)
    if f.get("channels", getlink=True) is not None:
        try:
            result.channels = read_channel_geometry(
                rd, _numbered(rd.members(f, "channels"), "/channels"))
        except ValueError as exc:
            raise _Bad(str(exc)) from None
    return result


def _testlab(rd: _Reader, f: h5py.File, result: Result) -> None:
    """``/virtual_points``, ``/tpa`` and ``/semm``, frequency functions on ``/frf/omega``."""
    groups = [name for name in ("virtual_points", "tpa", "semm")
              if f.get(name, getlink=True) is not None]
    if not groups:
        return
    if result.frf is None:
        raise _Bad(f"/{groups[0]} without /frf (its frequencies)")
    k = len(result.frf.omega)
    try:
        if "virtual_points" in groups:
            members = rd.members(f, "virtual_points")
            result.virtual_points = read_virtual_points(
                rd, _numbered([m for m in members if m[0] != "monte_carlo"],
                              "/virtual_points"), k)
            mc = [g for name, g in members if name == "monte_carlo"]
            if mc:
                result.monte_carlo = read_monte_carlo(rd, mc[0], result.frf.omega)
        if "tpa" in groups:
            result.tpa = read_tpa(rd, rd.node(f, "tpa", h5py.Group), k)
        if "semm" in groups:
            result.semm = read_semm(rd, rd.node(f, "semm", h5py.Group), k)
    except ValueError as exc:
        raise _Bad(str(exc)) from None


def load(path: str | os.PathLike) -> Result:
    """Read a result written by :func:`substruct.io.hdf5.save`.

    Raises:
        FileNotFoundError: ``path`` does not exist.
        ValueError: ``"<path>: not a substruct result: <why>"`` for a file that is not a
            regular HDF5 file, is truncated, lacks the substruct layout or breaks it (a
            dataset of the wrong rank, kind or length, a link, more than
            :data:`MAX_RESULT_BYTES` declared, cells pointing past the points).
    """
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such file")
    if not path.is_file():
        raise ValueError(f"{path}: not a substruct result: not a regular file")
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        raise ValueError(f"{path}: not a substruct result: not a readable HDF5 file "
                         f"({exc})") from None
    try:
        with f:
            return _read(f)
    except _Bad as exc:
        raise ValueError(f"{path}: not a substruct result: {exc}") from None
    except Exception as exc:  # noqa: BLE001 - anything h5py or numpy say about a bad file
        raise ValueError(f"{path}: not a substruct result: damaged or incomplete "
                         f"({type(exc).__name__}: {exc})") from None
