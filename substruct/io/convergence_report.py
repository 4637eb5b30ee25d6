"""Keeping a convergence study: the HDF5 file (:func:`save_h5` / :func:`load_h5`, round trip),
its path (:func:`output_paths`), and the JSON summary of ``substruct converge --json``
(:func:`convergence_summary_json`).

The study itself (:func:`substruct.studies.convergence.convergence_study`) returns plain arrays
in a :class:`~substruct.studies.convergence_results.ConvergenceResult`; its table is
:func:`substruct.cli.convergence_summary.print_table`, its picture
:func:`substruct.viz.convergence_picture.plot_convergence`.

Files are written atomically (:func:`substruct.io.hdf5.atomic_path`).
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from substruct.io.hdf5 import atomic_path
from substruct.studies.convergence import dofs_to_reach
from substruct.studies.convergence_results import ConvergenceResult, SeriesResult, VariantResult

__all__ = [
    "output_paths",
    "convergence_summary_json",
    "save_h5",
    "load_h5",
]


def output_paths(out_dir: str | os.PathLike[str], name: str) -> tuple[Path, Path]:
    """``(DIR/<name>_convergence.h5, DIR/<name>_convergence.png)``: what a study writes."""
    out = Path(out_dir)
    return out / f"{name}_convergence.h5", out / f"{name}_convergence.png"


# ---------------------------------------------------------------------------------- JSON


def _num(x: Any) -> Any:
    """A JSON-safe number (``null`` for NaN, ``"inf"``/``"-inf"``)."""
    x = float(x)
    return x if math.isfinite(x) else (None if math.isnan(x) else ("inf" if x > 0 else "-inf"))


def _nums(values: Any) -> list[Any]:
    return [_num(x) for x in np.ravel(values)]


def convergence_summary_json(result: ConvergenceResult, tol: float = 1e-6,
                             files: Sequence[str | os.PathLike[str]] = ()) -> dict[str, Any]:
    """The study in JSON-ready form: per variant the limit (``|lambda|``, rad/s) and its
    uncertainty, per series the sizes, worst error per level, fitted and theoretical orders,
    and the rod DOFs to reach ``tol`` (``null`` if not reached).  NaN is ``null``, infinity
    ``"inf"`` (a root the level does not have)."""
    variants = {}
    for v in result.variants.values():
        series = {}
        for s in v.series.values():
            series[s.key] = {
                "label": s.label, "level": [int(n) for n in s.level],
                "dofs": [int(n) for n in s.dofs], "seconds": _nums(s.seconds),
                "worst_error": _nums(s.worst_error), "rate": _nums(s.rate),
                "theory_rate": _num(s.theory_rate), "dofs_to_reach": dofs_to_reach(s, tol)}
        variants[v.key] = {
            "label": v.label, "limit_source": v.limit_source, "seconds": _num(v.seconds),
            "limit_omega": _nums(abs(v.limit)), "limit_difference": _nums(v.limit_difference),
            "reference_order": _nums(v.reference_order), "series": series}
    return {"name": result.name, "n_modes": int(result.n_modes), "tol": float(tol),
            "seconds": _num(result.seconds), "files": [str(f) for f in files],
            "attrs": result.attrs, "variants": variants}


# ------------------------------------------------------------------------------- HDF5


def save_h5(result: ConvergenceResult, path: str | os.PathLike[str]) -> Path:
    """Write ``result`` to HDF5 atomically (:func:`substruct.io.hdf5.atomic_path`: a temporary
    file in the same folder, then ``os.replace``): a reader never sees a half-written file, and
    an existing file is replaced only by a complete one.

    Layout: root attributes ``name``, ``n_modes``, ``seconds``, ``levels`` and ``attrs`` (JSON);
    a group per variant (attributes ``label``, ``limit_source``, ``seconds``; datasets
    ``limit_finest``, ``limit_richardson``, ``limit``, ``limit_difference``,
    ``reference_order``, ``floor``) holding a group per series (attributes ``label``,
    ``theory_rate``; datasets ``level``, ``dofs``, ``coupled_dofs``, ``seconds``,
    ``eigenvalues`` (complex), ``rel_error``, ``rate``, ``fit_mask``,
    ``extrapolated_difference``).
    """
    import h5py

    path = Path(path)
    with atomic_path(path, suffix=".h5.part") as tmp:
        with h5py.File(tmp, "w") as f:
            f.attrs["name"] = result.name
            f.attrs["n_modes"] = result.n_modes
            f.attrs["seconds"] = result.seconds
            f.attrs["levels"] = json.dumps(result.levels)
            f.attrs["attrs"] = json.dumps(result.attrs)
            f.attrs["variant_order"] = json.dumps(list(result.variants))
            for v in result.variants.values():
                g = f.create_group(v.key)
                g.attrs["label"] = v.label
                g.attrs["limit_source"] = v.limit_source
                g.attrs["seconds"] = v.seconds
                g.attrs["series_order"] = json.dumps(list(v.series))
                for name in ("limit_finest", "limit_richardson", "limit", "limit_difference",
                             "reference_order", "floor"):
                    g.create_dataset(name, data=getattr(v, name))
                for s in v.series.values():
                    h = g.create_group(s.key)
                    h.attrs["label"] = s.label
                    h.attrs["theory_rate"] = s.theory_rate
                    for name in ("level", "dofs", "coupled_dofs", "seconds", "eigenvalues",
                                 "rel_error", "rate", "fit_mask", "extrapolated_difference"):
                        h.create_dataset(name, data=getattr(s, name))
    return path


def load_h5(path: str | os.PathLike[str]) -> ConvergenceResult:
    """Read a file written by :func:`save_h5`."""
    import h5py

    with h5py.File(path, "r") as f:
        variants: dict[str, VariantResult] = {}
        for vkey in json.loads(f.attrs["variant_order"]):
            g = f[vkey]
            series: dict[str, SeriesResult] = {}
            for skey in json.loads(g.attrs["series_order"]):
                h = g[skey]
                series[skey] = SeriesResult(
                    key=skey, label=str(h.attrs["label"]),
                    theory_rate=float(h.attrs["theory_rate"]),
                    **{name: h[name][()] for name in (
                        "level", "dofs", "coupled_dofs", "seconds", "eigenvalues", "rel_error",
                        "rate", "fit_mask", "extrapolated_difference")})
            variants[vkey] = VariantResult(
                key=vkey, label=str(g.attrs["label"]), series=series,
                limit_source=str(g.attrs["limit_source"]), seconds=float(g.attrs["seconds"]),
                **{name: g[name][()] for name in ("limit_finest", "limit_richardson", "limit",
                                                  "limit_difference", "reference_order",
                                                  "floor")})
        return ConvergenceResult(name=str(f.attrs["name"]), n_modes=int(f.attrs["n_modes"]),
                                 variants=variants, levels=json.loads(f.attrs["levels"]),
                                 seconds=float(f.attrs["seconds"]),
                                 attrs=json.loads(f.attrs["attrs"]))
