"""``substruct info RESULT.h5`` and ``substruct export RESULT.h5``: read a result file back,
print what it holds, or write its mode shapes for ParaView (VTU, XDMF)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from substruct.cli.arguments import InputError
from substruct.cli.files import load_result, optional_module, writable_dir
from substruct.cli.summary import print_summary, summary_json

__all__ = ["info_command", "export_command"]


def info_command(args: argparse.Namespace) -> int:
    """Print the case, the model and the results of ``args.result``; return 0."""
    result = load_result(args.result)
    if args.json:
        print(json.dumps(summary_json(result, [Path(args.result)]), indent=1))
        return 0
    attrs = result.attrs
    print(f"{args.result}: result of case {result.case_name!r}")
    for key in ("description", "created", "substruct_version", "units", "case_file",
                "overrides"):
        if attrs.get(key):
            value = " ".join(str(attrs[key]).split())
            print(f"  {key}: {value}")
    model = result.model
    for name, kind, a, b in zip(model.substructure_names, model.substructure_kinds,
                                model.offsets[:-1], model.offsets[1:]):
        print(f"  substructure {name}: {kind}, {int(b - a)} coordinate(s)")
    for label in model.constraint_labels:
        print(f"  constraint: {label}")
    print_summary(result, sys.stdout)
    return 0


def export_command(args: argparse.Namespace) -> int:
    """Write the selected modes of ``args.result`` as VTU or XDMF; print the paths; return 0."""
    result = load_result(args.result)
    out = Path(args.out) if args.out else Path(args.result).resolve().parent
    writable_dir(out, "--out")
    export = optional_module("io.export")
    if args.modes is not None:
        try:
            export.parse_modes(args.modes)
        except ValueError as err:
            raise InputError(f"--modes: {err}") from None
    try:
        paths = export.export_modes(result, out, args.format, args.modes, variant=args.variant)
    except ValueError as err:
        raise InputError(" ".join(str(err).split())) from None
    for p in paths:
        print(p)
    return 0
