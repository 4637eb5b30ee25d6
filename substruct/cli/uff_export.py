"""``substruct export RESULT.h5 --format uff``: the result's receptances (UFF 58, binary), modes
(55, six digits, and 2414, double precision) and nodes (15) in one ``<case>.uff`` file (:func:`substruct.io.uff.export_uff`); the other
formats go to :func:`substruct.cli.result_commands.export_command`."""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from substruct.cli.errors import InputError
from substruct.cli.files import check_out_dir, load_result, optional_module
from substruct.cli.result_commands import export_command

__all__ = ["export_dispatch", "export_uff_command"]


def export_uff_command(args: argparse.Namespace) -> int:
    """Write ``<case>.uff`` beside the result (or into ``--out``); print its path; return 0.

    ``--modes`` and ``--variant`` do not apply: every mode and the receptances are written.
    """
    if args.modes is not None or args.variant is not None:
        raise InputError("--format uff writes every mode and the receptances: no --modes or "
                         "--variant")
    result = load_result(args.result)
    uff = optional_module("io.uff")
    out = args.out if args.out is not None else str(Path(args.result).resolve().parent)
    path = uff.uff_path(result, out)
    check_out_dir(str(path.parent), "--out", [path.name])
    if path.exists() and os.path.samefile(path, args.result):
        raise InputError(f"{path} is the result being exported")
    try:
        print(uff.export_uff(result, out, force=args.force))
    except (ValueError, FileExistsError) as err:
        raise InputError(" ".join(str(err).split())) from None
    return 0


def export_dispatch(args: argparse.Namespace) -> int:
    """``substruct export``: UFF here, VTU and XDMF by
    :func:`substruct.cli.result_commands.export_command`."""
    return export_uff_command(args) if args.format == "uff" else export_command(args)
