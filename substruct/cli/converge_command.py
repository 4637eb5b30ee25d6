"""``substruct converge CASE.yaml``: the convergence study of a rod case
(:mod:`substruct.studies.convergence`), written as ``DIR/<name>_convergence.h5`` and ``.png``.

It follows ``substruct run``: the arguments, the case and the output paths are checked first;
the output directory is locked (a second writer fails with "another run is writing DIR");
the study is computed in a child process (:func:`~substruct.cli.isolated.call_isolated`, so
that Ctrl-C and SIGTERM act at once); the result file and its picture are written into a
staging folder and moved into place together (:class:`~substruct.io.file_set.OutputDir`).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any

from substruct.cli.errors import InputError
from substruct.cli.files import optional_module, writable_dir
from substruct.cli.isolated import call_isolated
from substruct.cli.progress import ProgressBar

__all__ = ["converge_command"]


def converge_command(args: argparse.Namespace) -> int:
    """Run the study of ``args.case``; return the exit code (0).

    The arguments, the case and the output files are checked before any level is computed.
    """
    from substruct.builder.rod_system_case import spec_from_case
    from substruct.case.loader import load_case
    from substruct.cli.convergence_summary import print_table
    from substruct.studies.convergence import VARIANTS, study_variants
    from substruct.studies.levels import parse_levels
    report = optional_module("io.convergence_report")
    picture = optional_module("viz.convergence_picture")

    variants = [v.strip() for v in args.variants.split(",") if v.strip()]
    if not variants or any(v not in VARIANTS for v in variants):
        raise InputError(f"--variants: expected a comma list of {', '.join(VARIANTS)}, "
                         f"got {args.variants!r}")
    if not (math.isfinite(args.tol) and args.tol > 0):
        raise InputError(f"--tol: must be a positive number, got {args.tol:g}")
    case = load_case(args.case, args.set)
    spec, fixed_g = spec_from_case(case)
    try:
        levels = parse_levels(args.levels, fixed_g=fixed_g)
    except ValueError as err:
        raise InputError(f"--levels: {str(err).removeprefix('levels: ')}") from None
    if not levels.fe_p1 and not levels.fe_p2:
        raise InputError("--levels: no finite-element series (p1 or p2); the study measures "
                         "its errors against the finest of them")
    if not study_variants(spec, variants):
        raise InputError(f"--variants {args.variants}: nothing to study (case {case.name} has "
                         "no active constraints, so no constrained variant)")
    out = Path(args.out)
    writable_dir(out, "--out")
    for target in report.output_paths(out, spec.name):
        if target.is_dir():
            raise InputError(f"{target} is a directory")
        if target.exists() and not args.force:
            raise InputError(f"{target} exists; use --force to overwrite it")
    quiet, name = args.quiet, spec.name

    def progress_bar() -> Any:  # made in the child, on its (relayed) stderr
        if quiet:
            return None
        bar = ProgressBar(sys.stderr, title="converge", unit="levels", minimum=0)
        width = 48 if getattr(sys.stderr, "isatty", lambda: False)() else 0

        def progress(done: int, total: int, what: str) -> None:
            label = name if done >= total else what
            label = label if len(label) <= 48 else label[:45] + "..."
            bar(done, total, f"{label:<{width}s}")  # one width: \r overwrites it all
        return progress
    result, h5, png = _study_locked(out, spec, levels, variants, progress_bar, args,
                                    report, picture)
    if args.json:
        print(json.dumps(report.convergence_summary_json(result, args.tol, [h5, png]),
                         indent=1))
    elif not args.quiet:
        print_table(result, tol=args.tol)
        print(f"written: {h5}, {png}")
    return 0


def _study_locked(out: Path, spec: Any, levels: Any, variants: list[str], progress_bar: Any,
                  args: argparse.Namespace, report: Any, picture: Any
                  ) -> tuple[Any, Path, Path]:
    """The study computed in a child under the lock of ``out``; its file and picture
    committed as one set."""
    from substruct.io.file_set import BusyError, OutputDir
    from substruct.studies.convergence import convergence_study

    try:
        with OutputDir(out) as target:
            result = call_isolated(lambda: convergence_study(
                spec, levels, variants=variants, reference=args.reference,
                progress=progress_bar()))
            staging = target.stage(spec.name)
            h5_part, png_part = report.output_paths(staging, spec.name)
            report.save_h5(result, h5_part)
            picture.plot_convergence(result, png_part, tol=args.tol)
            target.commit(staging)
    except BusyError as err:  # raised on entering: nothing was computed
        raise InputError(str(err)) from None
    h5, png = report.output_paths(out, spec.name)
    return result, h5, png
