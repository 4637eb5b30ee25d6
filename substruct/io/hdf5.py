"""Results files: a :class:`~substruct.run.result.Result` to HDF5 and back.

The layout is documented in ``docs/results.md``; in short::

    /                      attrs: format, format_version, substruct_version, case_name,
                                  case_yaml, created, units (+ scalar entries of Result.attrs)
    /modes/                omega, eigenvalues, damping_ratio, shapes, constraint_residual,
                           spurious_eigenvalues, spurious_reason; attrs method, agreement_<m>,
                           solver, tolerance
    /variants/<name>/      same as /modes (attr ``name`` holds the name verbatim)
    /frf/                  omega, H (chunked by frequency), inputs, outputs; attrs method,
                           agreement_<m>, constraint_residual, tolerance, quantity
                           (receptance, mobility or accelerance; receptance if absent)
    /model/                dof_labels, substructure_names, substructure_kinds, offsets,
                           A (CSR group), b, R (CSR group), constraint_labels
    /model/drawings/<i>/   points, interp (CSR group), rotations (CSR group, frames and
                           Nastran models only), cells/<k> (attr cell_type),
                           glyph_names, glyph_indices; attrs name, kind
    /recovery/<i>/         labels, modes, history, peak_max(_t), peak_min(_t); attrs part,
                           name, of (:mod:`substruct.io.recovery_hdf5`)

:func:`save` writes to a temporary file in the target directory and renames it over the
target, so an interrupted run never leaves a broken (or half-overwritten) result.
:func:`result_file` opens that temporary file before the result is computed, so that a
receptance sweep (and a transient run's stored fields) write their blocks into it as they come
(``/frf/H`` and ``/transient/snapshots`` are then never whole in memory); it is renamed only
once the result is saved.
:func:`load` (:mod:`substruct.io.result_reader`, which checks every part of the file before
trusting it) returns the same objects that were saved.
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
from substruct.analysis.results import Modes, Receptance
from substruct.io.blocks import BLOCK_BYTES, CHUNK_BYTES, DatasetSink, write_blocks
from substruct.io.file_set import TEMP_PREFIX
from substruct.io.paths import write_errors
from substruct.io.result_format import FORMAT, FORMAT_VERSION, RESERVED_ATTRS
from substruct.lazy import lazy_getattr
from substruct.run.result import ModelInfo, Result

__all__ = ["save", "load", "atomic_path", "listed_pictures", "result_file", "ResultFile",
           "FORMAT", "FORMAT_VERSION"]

#: :func:`load` is the reader's (imported on first use: a run that only writes does not load
#: the readers of every part of the layout).
__getattr__ = lazy_getattr(__name__, {"load": "substruct.io.result_reader"})

_RESERVED = RESERVED_ATTRS
#: Root attributes :func:`save` always writes itself (never taken from ``Result.attrs``).
_OWN = _RESERVED + ("substruct_version", "created")
_DEFAULT_UNITS = "consistent units of the case file; omega in rad/s"

_STR = h5py.string_dtype("utf-8")
#: Where a streamed sweep writes its receptances until the result moves them to ``/frf/H``.
_STREAMED_FRF = "_frf_H_streaming"
#: Where a transient run writes its stored fields until they move to ``/transient/snapshots``.
_STREAMED_FIELDS = "_transient_snapshots_streaming"


# ----------------------------------------------------------------------------- writing


def save(result: Result, path: str | os.PathLike, *, block_bytes: int = BLOCK_BYTES,
         chunk_bytes: int = CHUNK_BYTES, compression: str | None = None) -> Path:
    """Write ``result`` to the HDF5 file ``path`` atomically; return the path.

    The file is written under a temporary name (``*.h5.part``) in the target directory and
    renamed over ``path`` only once complete.  On any error the temporary file is removed and
    an existing file at ``path`` is left untouched.  Missing parent directories are created.

    The receptances ``/frf/H`` and the transient snapshots are chunked datasets written
    ``block_bytes`` at a time from views of the arrays, in chunks of about ``chunk_bytes``
    (whole frequencies or instants), optionally compressed (``"gzip"``, ``"lzf"``; off by
    default: :mod:`substruct.io.blocks` gives the measured cost).
    """
    with result_file(path, block_bytes=block_bytes, chunk_bytes=chunk_bytes,
                     compression=compression) as out:
        out.save(result)
    return Path(path)


class ResultFile:
    """A result file open for writing, before its result is complete: :attr:`frf_sink`
    takes the receptances of a sweep as they are computed and :attr:`field_sink` the fields
    a transient run stores as it records them (:class:`~substruct.io.blocks.DatasetSink`,
    datasets aside in the file), and :meth:`save` then writes the rest of the result, the
    streamed receptances becoming ``/frf/H`` and the fields ``/transient/snapshots`` without
    a copy (HDF5 links moved).  The file is the one :func:`save` writes.
    """

    def __init__(self, f: h5py.File, block_bytes: int, chunk_bytes: int,
                 compression: str | None, where: str | os.PathLike | None = None) -> None:
        self.file = f
        self.options: dict[str, Any] = {"block_bytes": block_bytes,
                                        "chunk_bytes": chunk_bytes, "compression": compression}
        self.frf_sink = DatasetSink(f, _STREAMED_FRF, where=where, **self.options)
        self.field_sink = DatasetSink(f, _STREAMED_FIELDS, where=where, **self.options)
        self.saved = False

    def save(self, result: Result) -> None:
        """Write ``result`` into the file (once); the writers of the optional parts are
        imported when the result has them."""
        if self.saved:
            raise RuntimeError("the result file is already written")
        f = self.file
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
            streamed = self.frf_sink if getattr(result.frf.H, "sink", None) is self.frf_sink \
                else None
            _write_frf(f.create_group("frf", track_order=True), result.frf, streamed,
                       **self.options)
        if _STREAMED_FRF in f:  # a sweep streamed here whose result was not kept
            del f[_STREAMED_FRF]
        if result.transient is not None:
            from substruct.io.transient_hdf5 import write_transient

            write_transient(f.create_group("transient", track_order=True),
                            result.transient, streamed=self.field_sink, **self.options)
        if _STREAMED_FIELDS in f:  # a run streamed here whose result was not kept
            del f[_STREAMED_FIELDS]
        if result.recovery:
            from substruct.io.recovery_hdf5 import write_recovery

            write_recovery(f.create_group("recovery", track_order=True), result.recovery)
        if result.random is not None:
            from substruct.io.spec_hdf5 import write_random

            write_random(f.create_group("random", track_order=True), result.random)
        if result.base_frf is not None:
            from substruct.io.spec_hdf5 import write_base_frf

            write_base_frf(f.create_group("base_frf", track_order=True), result.base_frf)
        if result.srs is not None:
            from substruct.io.spec_hdf5 import write_srs

            write_srs(f.create_group("srs", track_order=True), result.srs)
        if result.virtual_points:
            from substruct.io.vp_hdf5 import write_monte_carlo, write_virtual_points

            vg = f.create_group("virtual_points", track_order=True)
            write_virtual_points(vg, result.virtual_points)
            if result.monte_carlo is not None:
                write_monte_carlo(vg.create_group("monte_carlo", track_order=True),
                                  result.monte_carlo)
        if result.channels:
            from substruct.io.channels_hdf5 import write_channel_geometry

            write_channel_geometry(f.create_group("channels", track_order=True),
                                   result.channels)
        if result.tpa is not None:
            from substruct.io.tpa_hdf5 import write_tpa

            write_tpa(f.create_group("tpa", track_order=True), result.tpa)
        if result.semm is not None:
            from substruct.io.tpa_hdf5 import write_semm

            write_semm(f.create_group("semm", track_order=True), result.semm)
        self.saved = True


@contextlib.contextmanager
def result_file(path: str | os.PathLike, *, block_bytes: int = BLOCK_BYTES,
                chunk_bytes: int = CHUNK_BYTES, compression: str | None = None,
                where: str | os.PathLike | None = None) -> Iterator[ResultFile]:
    """The result file ``path`` open for writing (:class:`ResultFile`) under a temporary name
    (:func:`atomic_path`), renamed over ``path`` when the block ends with the result saved.
    On any error, or with nothing saved, the temporary file is removed and ``path`` is
    untouched: a sweep that fails half-way through its blocks leaves no file.

    With ``where``, an error of the file system while the file is opened, written by the
    sweep (:attr:`ResultFile.frf_sink`) or closed is a :class:`~substruct.io.paths.WriteError`
    naming ``where`` (:func:`~substruct.io.paths.write_errors`); other errors of the block
    pass unchanged.

    Raises:
        RuntimeError: the block ended without :meth:`ResultFile.save`.
    """
    def guard() -> contextlib.AbstractContextManager:
        return write_errors(where) if where is not None else contextlib.nullcontext()

    with guard(), contextlib.ExitStack() as opening:
        tmp = opening.enter_context(atomic_path(path, suffix=".h5.part"))
        f = opening.enter_context(h5py.File(tmp, "w", track_order=True))
        stack = opening.pop_all()
    with stack:  # an error of the block: the file closed and removed
        out = ResultFile(f, block_bytes, chunk_bytes, compression, where)
        yield out
        if not out.saved:
            raise RuntimeError(f"the result file {Path(path).name} was left unwritten")
        with guard():
            stack.close()  # closed, then renamed into place


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, suffix: str = ".part") -> Iterator[Path]:
    """Yield a temporary path beside ``path``; rename it to ``path`` if the block succeeds.

    The temporary file (``.substruct-<name>.<random><suffix>``) is created in the target
    directory (so the final ``os.replace`` is an
    atomic rename on the same file system) with the permissions a new file would get.  If the
    block raises, the temporary file is removed and ``path`` is untouched.  Missing parent
    directories are created.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, name = tempfile.mkstemp(dir=path.parent, prefix=f"{TEMP_PREFIX}{path.name}.",
                               suffix=suffix)
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


def _write_frf(g: h5py.Group, frf: Receptance, streamed: DatasetSink | None = None,
               block_bytes: int = BLOCK_BYTES, chunk_bytes: int = CHUNK_BYTES,
               compression: str | None = None) -> None:
    g.attrs["method"] = str(frf.method)
    g.attrs["constraint_residual"] = float(frf.constraint_residual)
    g.attrs["tolerance"] = float(frf.tolerance)
    g.attrs["quantity"] = str(frf.quantity)
    _write_agreement(g, frf.agreement)
    _array(g, "omega", np.asarray(frf.omega, dtype=float), "rad/s")
    if streamed is not None:  # written block by block as the sweep computed it
        g.file.move(streamed.dataset.name, f"{g.name}/H")
    else:
        write_blocks(g, "H", np.asarray(frf.H), block_bytes=block_bytes,
                     chunk_bytes=chunk_bytes, compression=compression)
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
    for key, matrix in model.matrices.items():  # output: {matrices: true}
        _csr(g, key, matrix)
    drawings = g.create_group("drawings", track_order=True)
    for i, d in enumerate(model.drawings):
        dg = drawings.create_group(str(i), track_order=True)
        dg.attrs["name"] = str(d.name)
        dg.attrs["kind"] = str(d.kind)
        _array(dg, "points", np.asarray(d.points, dtype=float).reshape(-1, 3))
        _csr(dg, "interp", d.interp)
        if d.rotations is not None:
            _csr(dg, "rotations", d.rotations)
        cells = dg.create_group("cells", track_order=True)
        for k, (cell_type, conn) in enumerate(d.cells):
            ds = cells.create_dataset(str(k), data=np.asarray(conn, dtype=np.int64))
            ds.attrs["cell_type"] = str(cell_type)
        _strings(dg, "glyph_names", list(d.glyphs))
        _array(dg, "glyph_indices", np.asarray(list(d.glyphs.values()), dtype=np.int64))


# ----------------------------------------------------------------------------- reading


def listed_pictures(path: str | os.PathLike) -> list[str]:
    """The picture names a result file lists as its set (root attribute ``pictures``); ``[]``
    when the file is missing, unreadable or lists none.  Only plain names of files beside the
    result are returned (no directory parts)."""
    try:
        with h5py.File(path, "r") as f:
            aid = f.attrs.get_id("pictures") if "pictures" in f.attrs else None
            if aid is None or aid.shape != () or h5py.check_string_dtype(aid.dtype) is None:
                return []
            text = f.attrs["pictures"]
    except Exception:  # noqa: BLE001 - a damaged old file lists nothing
        return []
    text = text.decode("utf-8", "replace") if isinstance(text, bytes) else str(text)
    return [n for n in text.splitlines()
            if n and "/" not in n and "\\" not in n and n not in (".", "..")]
