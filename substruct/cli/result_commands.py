"""``substruct info RESULT.h5`` and ``substruct export RESULT.h5``: read a result file back,
print what it holds, or write its mode shapes for ParaView (VTU, XDMF).

A result file is untrusted input: it is read through :func:`substruct.io.hdf5.load`, which
checks every part before using it.  ``info`` prints through :class:`EscapedText`, so that a
string of the file cannot move the cursor, retitle or clear the terminal.  ``export`` never
replaces the file it reads, nor, without ``--force``, any file that exists; its files are
written as one set under the directory's lock (:mod:`substruct.io.file_set`).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any, Callable, TextIO

from substruct.cli.errors import InputError
from substruct.cli.files import check_out_dir, check_out_file, check_targets, load_result, \
    optional_module
from substruct.cli.summary import print_summary, summary_json

__all__ = ["info_command", "export_command", "EscapedText"]


class EscapedText:
    """A text stream that writes control and format characters escaped (``\\x1b``), line
    breaks and tabs excepted.

    Args:
        stream: where the text goes (``sys.stdout``).
    """

    def __init__(self, stream: TextIO):
        self.stream = stream

    def write(self, text: str) -> int:
        """Write ``text`` with every non-printable character but ``\\n`` and ``\\t`` escaped."""
        from substruct.case.text import printable

        lines = text.split("\n")
        self.stream.write("\n".join("\t".join(printable(part) for part in line.split("\t"))
                                    for line in lines))
        return len(text)

    def flush(self) -> None:
        """Flush the stream underneath."""
        self.stream.flush()

    def isatty(self) -> bool:
        """Whether the stream underneath is a terminal."""
        return bool(getattr(self.stream, "isatty", lambda: False)())


def info_command(args: argparse.Namespace) -> int:
    """Print the case, the model and the results of ``args.result``; return 0."""
    result = load_result(args.result)
    if args.json:  # JSON escapes control characters itself
        print(json.dumps(summary_json(result, [Path(args.result)]), indent=1))
        return 0
    out = EscapedText(sys.stdout)
    attrs = result.attrs
    out.write(f"{args.result}: result of case {result.case_name!r}\n")
    for key in ("description", "created", "substruct_version", "units", "case_file",
                "overrides"):
        if attrs.get(key):
            value = " ".join(str(attrs[key]).split())
            out.write(f"  {key}: {value}\n")
    model = result.model
    for name, kind, a, b in zip(model.substructure_names, model.substructure_kinds,
                                model.offsets[:-1], model.offsets[1:]):
        out.write(f"  substructure {name}: {kind}, {int(b - a)} coordinate(s)\n")
    for label in model.constraint_labels:
        out.write(f"  constraint: {label}\n")
    print_summary(result, out)  # type: ignore[arg-type]
    return 0


def _export_transient(args: argparse.Namespace, result: Any) -> int:
    """``export --format xdmf --transient``: the stored fields of the transient response as
    an XDMF time series (:mod:`substruct.io.transient_export`), with the checks of
    :func:`export_command`."""
    if args.format != "xdmf" or args.modes is not None or args.variant is not None:
        raise InputError("--transient exports the stored fields as --format xdmf; --modes and "
                         "--variant do not apply")
    export = optional_module("io.transient_export")
    out = _out(args, (".xdmf",))
    try:
        paths = export.transient_export_paths(result, out)
    except ValueError as err:
        raise InputError(" ".join(str(err).split())) from None
    _check_targets(args, paths)
    return _write(lambda: export.export_transient(result, out, force=args.force))


def _write(export: Callable[[], list[Path]]) -> int:
    """Run ``export``, print the paths it wrote; its refusals (a busy directory, a file in the
    way) as one-line input errors."""
    from substruct.io.file_set import BusyError

    try:
        paths = export()
    except BusyError as err:
        raise InputError(str(err)) from None
    except (ValueError, FileExistsError) as err:
        raise InputError(" ".join(str(err).split())) from None
    for p in paths:
        print(p)
    return 0


def _out(args: argparse.Namespace, file_suffixes: tuple[str, ...]) -> Path:
    """``--out`` checked (:func:`~substruct.cli.files.check_out_dir`, or
    :func:`~substruct.cli.files.check_out_file` when it names a file by its ending): the
    directory, or the file; the result's folder without ``--out``."""
    if args.out is None:
        return check_out_dir(str(Path(args.result).parent), "--out")
    if Path(args.out).suffix.lower() in file_suffixes:
        folder, name = check_out_file(args.out, "--out", file_suffixes)
        return folder / name
    return check_out_dir(args.out, "--out")


def _check_targets(args: argparse.Namespace, paths: list[Path]) -> None:
    """Every file an export will write: its folder can hold it, none is the result read (even
    with ``--force``), none exists unless ``--force`` (checked again under the lock)."""
    check_out_dir(str(paths[0].parent), "--out", [p.name for p in paths])
    for p in paths:
        check_targets(p.parent, [p.name], [args.result], args.force)


def export_command(args: argparse.Namespace) -> int:
    """Write the selected modes of ``args.result`` as VTU or XDMF; print the paths; return 0.

    Every file is checked before anything is written: none may be the result read (even with
    ``--force``), none may exist unless ``--force``.
    """
    result = load_result(args.result)
    if getattr(args, "transient", False):
        return _export_transient(args, result)
    export = optional_module("io.export")
    out = _out(args, (".vtu", ".xdmf"))
    try:
        paths = export.export_paths(result, out, args.format, args.modes,
                                    variant=args.variant)
    except ValueError as err:
        text = " ".join(str(err).split())
        raise InputError("--" + text if text.startswith("modes: ") else text) from None
    _check_targets(args, paths)
    return _write(lambda: export.export_modes(result, out, args.format, args.modes,
                                              variant=args.variant, force=args.force))
