"""The study file: one HDF5 file per study, written atomically, and read back.

Layout::

    /                  attrs: format (substruct-study), format_version, substruct_version,
                              case_name, kind (grid | random), backend, created, case_yaml,
                              shared (the reduced parts made once for every sample),
                              shared_seconds (the time it took)
    /parameters/       names (strings), table (samples x parameters)
    /samples/<name>    collected arrays, samples x k: frequency, damping_ratio, mac (per mode),
                       frf_peak, frf_peak_omega (per peak; attr ``peaks`` names them);
                       frf (samples x frequencies x curves, complex; attr ``curves``) and
                       frf_omega (samples x frequencies) with ``collect: frf``;
                       seconds (time of each sample), error (one string per sample, "" if run)
    /failures/         index, message: the samples that failed and why
    /reference/<name>  the same arrays for the case as written (when the MAC is collected)
    /tracking          the modes followed through the samples (collect: track;
                       :mod:`substruct.io.tracking_file`)

The file is written to a temporary name beside the target and renamed over it
(:func:`substruct.io.hdf5.atomic_path`): an interrupted study never leaves half a file.
"""

from __future__ import annotations

import datetime as dt
import os
from pathlib import Path

import h5py
import numpy as np

from substruct import __version__
from substruct.io.hdf5 import atomic_path
from substruct.io.tracking_file import read_tracking, write_tracking
from substruct.studies.study_run import StudyResult

__all__ = ["STUDY_FORMAT", "STUDY_FORMAT_VERSION", "save_study", "load_study"]

#: The ``format`` attribute of a study file.
STUDY_FORMAT = "substruct-study"
#: Its layout version.
STUDY_FORMAT_VERSION = 1
_STR = h5py.string_dtype("utf-8")


def save_study(result: StudyResult, path: str | os.PathLike) -> Path:
    """Write ``result`` to ``path`` atomically; return the path."""
    path = Path(path)
    with atomic_path(path) as tmp:
        with h5py.File(tmp, "w") as f:
            attrs = {"format": STUDY_FORMAT, "format_version": STUDY_FORMAT_VERSION,
                     "substruct_version": __version__, "case_name": result.case_name,
                     "kind": result.kind, "backend": result.backend,
                     "created": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
                     "case_yaml": result.case_yaml, "shared_seconds": result.shared_seconds}
            f.attrs.update(attrs)
            f.attrs["shared"] = np.array(result.shared, dtype=object).astype(_STR) \
                if result.shared else np.array([], dtype=_STR)
            g = f.create_group("parameters")
            g.create_dataset("names", data=np.array(result.parameters, dtype=object), dtype=_STR)
            g.create_dataset("table", data=result.table)
            s = f.create_group("samples")
            for name, values in result.values.items():
                s.create_dataset(name, data=values)
            s.attrs["peaks"] = np.array(result.peaks, dtype=object).astype(_STR) \
                if result.peaks else np.array([], dtype=_STR)
            s.attrs["curves"] = np.array(result.curves, dtype=object).astype(_STR) \
                if result.curves else np.array([], dtype=_STR)
            s.create_dataset("seconds", data=result.seconds)
            s.create_dataset("error", data=np.array(result.errors, dtype=object), dtype=_STR)
            fail = f.create_group("failures")
            fail.create_dataset("index", data=np.array(result.failed, dtype=np.int64))
            fail.create_dataset("message", data=np.array(
                [result.errors[k] for k in result.failed], dtype=object), dtype=_STR)
            ref = f.create_group("reference")
            for name, values in result.reference.items():
                ref.create_dataset(name, data=values)
            if isinstance(result.tracking, str):
                f.attrs["tracking"] = result.tracking
            elif result.tracking is not None:
                write_tracking(f.create_group("tracking"), result.tracking)
    return path


def _strings(ds: h5py.Dataset) -> list[str]:
    return [v.decode() if isinstance(v, bytes) else str(v) for v in ds[()]]


def load_study(path: str | os.PathLike) -> StudyResult:
    """Read a study file written by :func:`save_study`.

    Raises:
        ValueError: not a study file.
    """
    with h5py.File(path, "r") as f:
        if f.attrs.get("format") != STUDY_FORMAT:
            raise ValueError(f"{path}: not a substruct study file")
        s = f["samples"]
        values = {k: np.asarray(s[k][()]) for k in s if k not in ("seconds", "error")}
        peaks = [p.decode() if isinstance(p, bytes) else str(p) for p in s.attrs["peaks"]]
        tracking = read_tracking(f["tracking"]) if "tracking" in f else (
            str(f.attrs["tracking"]) if "tracking" in f.attrs else None)
        return StudyResult(case_name=str(f.attrs["case_name"]), kind=str(f.attrs["kind"]),
                           parameters=_strings(f["parameters/names"]),
                           table=np.asarray(f["parameters/table"][()]), values=values,
                           errors=_strings(s["error"]), seconds=np.asarray(s["seconds"][()]),
                           reference={k: np.asarray(v[()]) for k, v in f["reference"].items()},
                           backend=str(f.attrs["backend"]),
                           case_yaml=str(f.attrs["case_yaml"]), peaks=peaks,
                           curves=[p.decode() if isinstance(p, bytes) else str(p)
                                   for p in s.attrs.get("curves", [])],
                           shared=[p.decode() if isinstance(p, bytes) else str(p)
                                   for p in f.attrs.get("shared", [])],
                           shared_seconds=float(f.attrs.get("shared_seconds", 0.0)),
                           tracking=tracking)
