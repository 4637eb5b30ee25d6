"""``substruct export RESULT.h5 --format op4|npz [--part NAME]``: the coupled model of a result
(its constraints eliminated) or one part of it, as matrices with their DOF map
(:mod:`substruct.io.model_export`), into ``<case>_model.<fmt>`` or ``<case>_<part>.<fmt>``
beside the result (or in ``--out``).  The file is written under the folder's lock into a
staging folder and moved into place; it is never the result read, even with ``--force``."""

from __future__ import annotations

import argparse
from pathlib import Path

from substruct.cli.errors import InputError
from substruct.cli.files import check_out_dir, check_out_file, check_targets, load_result, \
    optional_module

__all__ = ["export_model_command"]


def export_model_command(args: argparse.Namespace) -> int:
    """Write the model of ``args.result`` as ``args.format``; print its path; return 0."""
    from substruct.io.file_set import OutputDir
    from substruct.io.paths import write_errors

    if args.modes is not None or args.variant is not None or args.transient:
        raise InputError(f"--format {args.format} writes the model's matrices: no --modes, "
                         "--variant or --transient")
    result = load_result(args.result)
    export = optional_module("io.model_export")
    suffix = f".{args.format}"
    try:
        model = export.exported_model(result, args.part)
        if args.out is not None and Path(args.out).suffix.lower() == suffix:
            folder, name = check_out_file(args.out, "--out", (suffix,))
        else:
            folder_text = args.out if args.out is not None else str(Path(args.result).parent)
            name = export.model_path(result, ".", args.format, args.part).name
            folder = check_out_dir(folder_text, "--out", [name])
    except ValueError as err:
        raise InputError(" ".join(str(err).split())) from None
    with OutputDir(folder) as target:
        check_targets(folder, [name], [args.result], args.force)
        staging = target.stage(Path(name).stem)
        try:
            with write_errors(folder / name):
                export.write_model(model, staging / name, args.format)
        except (ValueError, FileExistsError) as err:
            raise InputError(" ".join(str(err).split())) from None
        target.commit(staging)
    print(folder / name)
    return 0
