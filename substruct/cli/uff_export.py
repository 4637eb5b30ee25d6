"""``substruct export RESULT.h5 --format uff``: the result's receptances (UFF 58, binary), modes
(55, six digits, and 2414, double precision) and nodes (15) in one ``<case>.uff`` file
(:func:`substruct.io.uff.export_uff`); the other formats go to
:func:`substruct.cli.result_commands.export_command`.  The file name made from the case name
stored in the result goes through :func:`substruct.io.paths.safe_stem`."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from substruct.cli.errors import InputError
from substruct.cli.files import check_out_dir, check_out_file, check_targets, load_result, \
    optional_module
from substruct.cli.result_commands import export_command

__all__ = ["export_dispatch", "export_uff_command", "uff_target"]


def uff_target(result: Any, out: str | None, result_path: str) -> tuple[Path, str]:
    """The folder and file name of the UFF export: ``--out`` itself if it ends in ``.uff``
    or ``.unv``,
    else ``<case>.uff`` in ``--out`` (default: the result's folder).  The case name is read
    from the result file, so it becomes a file name only through
    :func:`~substruct.io.paths.safe_stem` (a name ``../x`` or ``/var/x`` stays in the
    folder)."""
    from substruct.io.paths import safe_stem

    if out is not None and Path(out).suffix.lower() in (".uff", ".unv"):
        return check_out_file(out, "--out", (".uff", ".unv"))
    folder = out if out is not None else str(Path(result_path).parent)
    name = f"{safe_stem(result.case_name)}.uff"
    return check_out_dir(folder, "--out", [name]), name


def export_uff_command(args: argparse.Namespace) -> int:
    """Write ``<case>.uff`` beside the result (or into ``--out``); print its path; return 0.

    ``--modes``, ``--variant`` and ``--transient`` do not apply: every mode and the receptances
    are written.
    The file is written under the folder's lock into a staging folder and moved into place
    (:class:`~substruct.io.file_set.OutputDir`); it is never the result read, even with
    ``--force``.
    """
    from substruct.io.file_set import OutputDir
    from substruct.io.paths import write_errors

    if args.modes is not None or args.variant is not None or getattr(args, "transient", False):
        raise InputError("--format uff writes every mode and the receptances: no --modes, "
                         "--variant or --transient")
    result = load_result(args.result)
    uff = optional_module("io.uff")
    folder, name = uff_target(result, args.out, args.result)
    with OutputDir(folder) as target:
        check_targets(folder, [name], [args.result], args.force)
        staging = target.stage(Path(name).stem)
        try:
            with write_errors(folder / name):
                uff.export_uff(result, staging / name)
        except (ValueError, FileExistsError) as err:
            raise InputError(" ".join(str(err).split())) from None
        target.commit(staging)
    print(folder / name)
    return 0


def export_dispatch(args: argparse.Namespace) -> int:
    """``substruct export``: UFF here, OP4 and NPZ by
    :func:`substruct.cli.model_export.export_model_command`, VTU and XDMF by
    :func:`substruct.cli.result_commands.export_command`."""
    if args.format in ("op4", "npz"):
        from substruct.cli.model_export import export_model_command

        return export_model_command(args)
    if getattr(args, "part", None) is not None:
        raise InputError("--part applies to --format op4 and npz")
    return export_uff_command(args) if args.format == "uff" else export_command(args)
