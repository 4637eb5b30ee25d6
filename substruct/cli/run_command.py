"""``substruct run CASE.yaml``: check the outputs can be written, run the case, write the
result file and its pictures, print the table (or ``--json``)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from substruct.cli.arguments import InputError
from substruct.cli.files import optional_module, writable_dir
from substruct.cli.progress import ProgressBar
from substruct.cli.summary import print_summary, summary_json

if TYPE_CHECKING:
    from substruct.run.result import Result

__all__ = ["run_command", "picture_paths", "write_pictures"]


def run_command(args: argparse.Namespace) -> int:
    """Run ``args.case`` into ``args.out``; return the exit code (0).

    The output directory and every file the run may write are checked before anything is
    computed; the result file is written only once every analysis (and its cross-checks)
    has passed.
    """
    from substruct.case.loader import load_case
    from substruct.run.runner import build_model, run_case

    case = load_case(args.case, args.set)
    out = Path(args.out)
    target = out / f"{case.name}.h5"
    writable_dir(out, "--out")
    for path in [target, *(picture_paths(case, out) if case.output.pictures else [])]:
        if path.exists() and not args.force:
            raise InputError(f"{path} exists; use --force to overwrite it")
        if path.is_dir():
            raise InputError(f"{path} is a directory")
    model = build_model(case)
    results = optional_module("io.hdf5")
    bar = ProgressBar(sys.stderr) if not args.quiet else None
    result = run_case(case, progress=bar, model=model)
    files = [Path(results.save(result, target))]
    if case.output.pictures:
        files += write_pictures(result, out, case.name)
    if args.json:
        print(json.dumps(summary_json(result, files), indent=1))
    elif not args.quiet:
        modes = case.analysis.modes
        drops = {v.name: list(v.drop) for v in modes.variants} if modes else {}
        print_summary(result, sys.stdout, modes.count if modes else None, drops)
        if any(b != 0 for b in result.model.b):
            print("note: constant right-hand sides (rhs) do not enter modes or receptances")
        print("written: " + ", ".join(str(f) for f in files))
    return 0


def picture_paths(case: Any, out: Path) -> list[Path]:
    """Every picture :func:`write_pictures` may write for ``case`` (checked before running)."""
    name, modes = case.name, case.analysis.modes
    paths = []
    if modes is not None:
        paths += [out / f"{name}_modes.png"]
        paths += [out / f"{name}_modes_{v.name}.png" for v in modes.variants]
    if case.analysis.frf is not None:
        paths.append(out / f"{name}_frf.png")
    return paths


def write_pictures(result: Result, out: Path, name: str) -> list[Path]:
    """The mode pictures (main modes and each variant) and the receptance picture."""
    plotting = optional_module("viz.plotting")
    files = []
    if result.modes is not None and len(result.modes.omega) and result.model.drawings:
        files.append(Path(plotting.plot_modes(result, out / f"{name}_modes.png")))
        for variant, modes in result.variants.items():
            if len(modes.omega):
                files.append(Path(plotting.plot_modes(
                    result, out / f"{name}_modes_{variant}.png", variant=variant)))
    if result.frf is not None:
        files.append(Path(plotting.plot_frf(result, out / f"{name}_frf.png")))
    return files
