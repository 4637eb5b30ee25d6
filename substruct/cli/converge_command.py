"""``substruct converge CASE.yaml``: the convergence study of a rod case
(:mod:`substruct.studies.convergence`), written as ``DIR/<name>_convergence.h5`` and ``.png``.

It follows ``substruct run``: the arguments, the case and the output paths are checked first;
the output directory is locked (a second writer fails with "another run is writing DIR") and
the targets are checked under the lock (none may exist without ``--force``);
the study is computed in a child process (:func:`~substruct.cli.isolated.call_isolated`, so
that Ctrl-C and SIGTERM act at once); the result file and its picture are written into a
staging folder, the report is rendered, and only then are they moved into place together
(:class:`~substruct.io.file_set.OutputDir`): a failure before leaves no file of the study.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any

from substruct.cli.errors import InputError
from substruct.cli.files import check_out_dir, check_targets, input_files, optional_module
from substruct.cli.isolated import call_isolated
from substruct.cli.progress import ProgressBar

__all__ = ["converge_command"]


def converge_command(args: argparse.Namespace) -> int:
    """Run the study of ``args.case``; return the exit code (0).

    The arguments, the case and the output files are checked before any level is computed.
    """
    from substruct.case.loader import load_case
    from substruct.studies.convergence import VARIANTS, study_variants
    from substruct.builder.rod_system_case import spec_from_case
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
    out = check_out_dir(args.out, "--out",
                        [p.name for p in report.output_paths(Path("."), spec.name)])
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
    sys.stdout.write(_study_locked(out, spec, levels, variants, progress_bar, args, report,
                                   picture, input_files(case)))
    return 0


def _study_locked(out: Path, spec: Any, levels: Any, variants: list[str], progress_bar: Any,
                  args: argparse.Namespace, report: Any, picture: Any,
                  inputs: list[Path]) -> str:
    """The study computed in a child under the lock of ``out`` (its targets checked there);
    its file and picture staged, the report rendered, then the set committed; the report."""
    from substruct.io.file_set import OutputDir
    from substruct.cli.convergence_summary import print_table
    from substruct.io.paths import write_errors
    from substruct.studies.convergence import convergence_study

    h5, png = report.output_paths(out, spec.name)
    with OutputDir(out) as target:  # BusyError on entering: nothing was computed
        check_targets(out, [h5.name, png.name], inputs, args.force)
        result = call_isolated(lambda: convergence_study(
            spec, levels, variants=variants, reference=args.reference,
            progress=progress_bar()))
        staging = target.stage(spec.name)
        h5_part, png_part = report.output_paths(staging, spec.name)
        with write_errors(out):
            report.save_h5(result, h5_part)
            picture.plot_convergence(result, png_part, tol=args.tol)
        if args.json:
            text = json.dumps(report.convergence_summary_json(result, args.tol, [h5, png]),
                              indent=1) + "\n"
        elif not args.quiet:
            text = print_table(result, tol=args.tol, file=False) + "\n" + \
                f"written: {h5}, {png}\n"
        else:
            text = ""
        target.commit(staging)
    return text
