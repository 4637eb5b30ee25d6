"""The full fields of a transient run to ParaView: ``substruct export RESULT.h5 --format xdmf
--transient``.

A run that kept the field every ``field_every`` steps (``/transient/snapshots``, the
displacement over the stacked coordinates at ``snapshot_t``) becomes an XDMF time series
``<case>_transient.xdmf`` + ``<case>_transient.h5``: the drawings of the model as one mesh
(:func:`substruct.io.export.combined_mesh`: solids, rods, discrete systems) and one step per
stored instant, time = the instant, point data ``displacement`` = ``(interp @ q_k)``
reshaped to ``(N, 3)``.  In ParaView, *Warp By Vector* with ``displacement`` and the time
slider play the response.  Written as one set (:mod:`substruct.io.file_set`), read back with
meshio's time-series reader and checked before it is kept; an existing file is replaced only
with ``force``.
"""

from __future__ import annotations

import os
from pathlib import Path

from substruct.io.export import combined_mesh
from substruct.io.file_set import OutputDir
from substruct.io.paths import safe_stem
from substruct.io.xdmf_export import check_xdmf_series, write_xdmf_series
from substruct.run.result import Result

__all__ = ["transient_export_paths", "export_transient"]


def transient_export_paths(result: Result, out: str | os.PathLike) -> list[Path]:
    """The ``.xdmf`` and ``.h5`` :func:`export_transient` would write (nothing written).

    Raises:
        ValueError: no transient response, or one without stored fields; ``out`` a file path
            not ending in ``.xdmf``.
    """
    tr = result.transient
    if tr is None:
        raise ValueError(f"result {result.case_name!r} holds no transient response")
    if not len(tr.snapshot_t):
        raise ValueError(f"the transient response of {result.case_name!r} stored no fields "
                         "(run it with analysis.transient.field_every > 0)")
    out = Path(out)
    if out.suffix:
        if out.suffix.lower() != ".xdmf":
            raise ValueError(f"export path {str(out)!r} does not end in .xdmf (format 'xdmf')")
        path = out
    else:
        stem = safe_stem(result.case_name)
        path = out / f"{stem}_transient.xdmf"
    return [path, path.with_suffix(".h5")]


def export_transient(result: Result, out: str | os.PathLike, *,
                     force: bool = False) -> list[Path]:
    r"""Write the stored fields of ``result.transient`` as an XDMF time series (module
    docstring): step ``k`` at :math:`t_k` holds the nodal displacements
    :math:`(\mathrm{interp}\, q_k)` of the drawings' points.  Returns the paths.

    Raises:
        ValueError: as :func:`transient_export_paths`; no drawings; drawings of another size
            than the fields.
        FileExistsError: a file to write exists (and ``force`` is false).
        substruct.io.file_set.BusyError: another process writes into the directory.
    """
    paths = transient_export_paths(result, out)
    tr = result.transient
    assert tr is not None
    mesh = combined_mesh(result.model)
    if mesh.interp.shape[1] != tr.snapshots.shape[1]:
        raise ValueError(f"drawings expect {mesh.interp.shape[1]} coordinates, the stored "
                         f"fields have {tr.snapshots.shape[1]}")
    for p in paths:
        if p.is_dir() or (p.exists() and not force):
            raise FileExistsError(f"{p} exists; use --force to overwrite it" if not p.is_dir()
                                  else f"{p} is a directory")
    disp = [mesh.displacement(q) for q in tr.snapshots]
    with OutputDir(paths[0].parent) as target:
        staging = target.stage(paths[0].stem)
        here = staging / paths[0].name
        write_xdmf_series(here, mesh.points, mesh.cells, tr.snapshot_t, disp)
        check_xdmf_series(here, len(mesh.points), sum(len(c) for _, c in mesh.cells),
                          tr.snapshot_t)
        target.commit(staging)
    return paths
