"""``substruct study CASE.yaml``: the samples of the case's ``study:`` block
(:mod:`substruct.studies.study_run`), in this process (default), on a LocalCluster
(``--workers N``) or on an existing Dask cluster (``--scheduler tcp://host:port``); written as
``DIR/<name>_study.h5`` (:mod:`substruct.io.study_file`) and pictures beside it, as one set
under the lock of ``DIR`` like ``run`` (:mod:`substruct.io.file_set`): a second study into the
same ``DIR`` is refused while the first runs ("another run is writing DIR"), and after it
unless ``--force``; a study killed at any point leaves the previous set, and the next writer
removes its temporary files.

Progress bars (tqdm: done, elapsed, ETA) for the shared reductions and the samples are drawn
on stderr when it is a terminal and ``--quiet`` is not given.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from substruct.cli.errors import InputError
from substruct.cli.progress import CountBar, phases_wanted
from substruct.cli.files import check_out_dir, check_targets, input_files

__all__ = ["study_command", "backend_options"]


def _summary(result: Any, seconds: float) -> dict[str, Any]:
    out: dict[str, Any] = {"case": result.case_name, "backend": result.backend,
                           "samples": len(result.errors), "failed": len(result.failed),
                           "seconds": round(seconds, 3), "parameters": result.parameters}
    if "frf_peak" in result.values and np.isfinite(result.values["frf_peak"][:, 0]).any():
        k = int(np.nanargmin(result.values["frf_peak"][:, 0]))
        out["smallest_peak"] = {"sample": k, "peak": float(result.values["frf_peak"][k, 0]),
                                "at": dict(zip(result.parameters, map(float, result.table[k])))}
    out["failures"] = [{"sample": k, "error": result.errors[k]} for k in result.failed[:20]]
    return out


def _den_hartog(case: Any) -> Any:
    """Den Hartog's tuning of the absorber the grid tunes, if it tunes one
    (:func:`substruct.studies.study_tuning.absorber_tuning`); a problem computing it is a
    warning, the study is written anyway."""
    from substruct.studies.study_tuning import absorber_tuning

    try:
        return absorber_tuning(case)
    except Exception as err:  # the marker is an extra: never lose a study for it
        print(f"substruct: warning: no Den Hartog tuning: {' '.join(str(err).split())}",
              file=sys.stderr)
        return None


def backend_options(args: argparse.Namespace) -> Any:
    """The :class:`~substruct.studies.study_backend.Backend` of the options ``--workers``,
    ``--scheduler``, ``--connect-timeout``: the number of workers, the scheduler's address,
    its protocol and the timeout checked (nothing is connected yet)."""
    from substruct.studies.study_backend import CONNECT_TIMEOUT, Backend, BackendError
    from substruct.studies.scheduler_probe import connect_timeout, scheduler_address

    if args.workers is not None and not 1 <= args.workers <= 1024:
        raise InputError(f"--workers: between 1 and 1024, got {args.workers}")
    if args.connect_timeout is not None and args.scheduler is None:
        raise InputError(f"--connect-timeout: only with --scheduler, got "
                         f"{args.connect_timeout!r}")
    if args.scheduler is None:
        return Backend(workers=args.workers)
    try:
        address = scheduler_address(args.scheduler)
        timeout = connect_timeout(CONNECT_TIMEOUT if args.connect_timeout is None
                                  else args.connect_timeout)
    except BackendError as err:
        raise InputError(str(err)) from None
    return Backend(scheduler=str(address), connect_timeout=timeout)


def study_command(args: argparse.Namespace) -> int:
    """Run the study of ``args.case``; return the exit code (0, also when samples failed:
    they are recorded in the file and listed in the summary; when every sample failed the
    study has no result: :class:`~substruct.analysis.errors.CheckError`, exit 1, nothing
    written)."""
    from substruct.case.loader import load_case
    from substruct.io.file_set import OutputDir
    from substruct.studies.study_run import study_of

    backend = backend_options(args)
    case = load_case(args.case, args.set)
    study_of(case)
    names = [f"{case.name}_study.h5", *(f"{case.name}_study_{kind}.png" for kind in _PICTURES)]
    out = check_out_dir(args.out, "--out", names)
    with OutputDir(out) as held:  # BusyError on entering (exit 2): nothing was computed
        check_targets(out, names if not args.no_pictures and case.output.pictures
                      else names[:1], input_files(case), args.force)
        return _study_locked(args, case, backend, out, held, names)


#: The pictures a study may draw (:func:`substruct.viz.study_picture.study_pictures`).
_PICTURES = ("frequencies", "histogram", "tuning", "tracked")


def _study_locked(args: argparse.Namespace, case: Any, backend: Any, out: Path, held: Any,
                  names: list[str]) -> int:
    """The study computed, its file and pictures staged, its report rendered, then the set
    committed under the lock ``held`` of ``out`` (a failure before the commit leaves nothing;
    pictures of the previous study of the case that the new one does not draw are removed
    with the commit)."""
    from substruct.io.paths import write_errors
    from substruct.io.study_file import save_study
    from substruct.studies.study_backend import BackendError
    from substruct.studies.study_run import run_study

    target = out / names[0]
    # the bars redraw a line: on a terminal only, and not with SUBSTRUCT_PROGRESS=0
    show = phases_wanted(sys.stderr, args.quiet) and \
        bool(getattr(sys.stderr, "isatty", lambda: False)())
    samples = CountBar(sys.stderr, "study", "sample", show)
    parts = CountBar(sys.stderr, "reductions", "part", show)
    start = time.perf_counter()
    try:
        result = run_study(case, backend, samples, parts_tick=parts)
    except BackendError as err:
        raise InputError(str(err)) from None
    finally:
        parts.close()
        samples.close()
    seconds = time.perf_counter() - start
    if result.failed and len(result.failed) == len(result.errors):
        from substruct.analysis.errors import CheckError

        first = result.failed[0]
        raise CheckError(f"every sample of the study failed ({len(result.failed)} of "
                         f"{len(result.errors)}), nothing written; sample {first}: "
                         f"{result.errors[first]}")
    staging = held.stage(f"{case.name}_study")
    pictures = []
    tuning = _den_hartog(case)
    with write_errors(out):
        save_study(result, staging / target.name)
        if not args.no_pictures and case.output.pictures:
            from substruct.viz.study_picture import study_pictures

            marked = None if tuning is None else (
                tuning[1].k_opt, tuning[1].c_opt,
                f"Den Hartog ({tuning[1].k_opt:.5g}, {tuning[1].c_opt:.4g})")
            pictures = [out / p.name for p in study_pictures(result, staging, marked=marked)]
    text = io.StringIO()
    with contextlib.redirect_stdout(text):  # the report, ready before the commit
        _report(args, result, seconds, tuning, target, pictures)
    staged = sorted(p.name for p in staging.iterdir())
    if staged != sorted([target.name, *(p.name for p in pictures)]):
        raise RuntimeError(f"the study staged {staged}")
    held.commit(staging, remove=[n for n in names[1:] if n not in staged
                                 and (out / n).is_file()])
    sys.stdout.write(text.getvalue())
    return 0


def _report(args: argparse.Namespace, result: Any, seconds: float, tuning: Any, target: Path,
            pictures: list[Path]) -> None:
    """Print the summary of the study (``--json``, the table, or nothing)."""
    summary = _summary(result, seconds)
    if tuning is not None:
        summary["den_hartog"] = {"absorber": tuning[0], "mu": tuning[1].mu,
                                 result.parameters[0]: tuning[1].k_opt,
                                 result.parameters[1]: tuning[1].c_opt}
    tracking = result.tracking
    if isinstance(tracking, str):
        summary["tracking"] = tracking
    elif tracking is not None:
        marks = (lambda rows, key: [{key: float(tracking.values[s]),
                                     "tracks": [a + 1, b + 1]} for s, a, b in rows])
        summary["tracking"] = {"crossings": marks(tracking.crossings, "after"),
                               "veerings": marks(tracking.veerings, "at")}
    summary["files"] = [str(p) for p in (target, *pictures)]
    if args.json:
        print(json.dumps(summary, indent=1))
    elif not args.quiet:
        print(f"{summary['case']}: {summary['samples']} samples of "
              f"{', '.join(result.parameters)} on {summary['backend']} in {seconds:.1f} s, "
              f"{summary['failed']} failed")
        if "smallest_peak" in summary:
            best = summary["smallest_peak"]
            at = ", ".join(f"{k} = {v:.6g}" for k, v in best["at"].items())
            print(f"smallest FRF peak {result.peaks[0]}: {best['peak']:.6g} at {at}")
        if "den_hartog" in summary:
            dh = summary["den_hartog"]
            print(f"Den Hartog's tuning of absorber {dh['absorber']} (mu = {dh['mu']:.4g}): "
                  + ", ".join(f"{p} = {dh[p]:.6g}" for p in result.parameters))
        if isinstance(tracking, str):
            print(f"modes {tracking}")
        elif tracking is not None:
            for kind, rows in (("crossing", tracking.crossings),
                               ("veering", tracking.veerings)):
                for s, a, b in rows:
                    print(f"{kind} of tracks {a + 1} and {b + 1} "
                          f"{'after' if kind == 'crossing' else 'at'} "
                          f"{tracking.parameter} = {float(tracking.values[s]):.6g}")
        for fail in summary["failures"]:
            print(f"sample {fail['sample']} failed: {fail['error']}")
        for f in summary["files"]:
            print(f"wrote {f}")
