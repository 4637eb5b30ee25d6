"""``substruct converge CASE.yaml``: the convergence study of a rod case
(:mod:`substruct.studies.convergence`), written as ``DIR/<name>_convergence.h5`` and ``.png``."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from substruct.cli.errors import InputError
from substruct.cli.files import optional_module, writable_dir
from substruct.cli.progress import ProgressBar

__all__ = ["converge_command"]


def converge_command(args: argparse.Namespace) -> int:
    """Run the study of ``args.case``; return the exit code (0).

    The arguments, the case and the output files are checked before any level is computed.
    """
    from substruct.case.loader import load_case
    from substruct.studies.convergence import VARIANTS, study_variants
    from substruct.studies.convergence_case import spec_from_case
    from substruct.studies.levels import parse_levels
    report = optional_module("io.convergence_report")

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
    progress = None
    if not args.quiet:
        bar = ProgressBar(sys.stderr, title="converge", unit="levels", minimum=0)
        width = 48 if getattr(sys.stderr, "isatty", lambda: False)() else 0

        def progress(done: int, total: int, what: str) -> None:
            label = spec.name if done >= total else what
            label = label if len(label) <= 48 else label[:45] + "..."
            bar(done, total, f"{label:<{width}s}")  # one width: \r overwrites it all
    result, h5, png = report.run_convergence(spec, out, levels, variants=variants,
                                             progress=progress, tol=args.tol,
                                             reference=args.reference, echo=False)
    if args.json:
        print(json.dumps(report.summary_json(result, args.tol, [h5, png]), indent=1))
    elif not args.quiet:
        report.print_table(result, tol=args.tol)
        print(f"written: {h5}, {png}")
    return 0
