"""The command line's arguments: one parser for ``run``, ``converge``, ``info``, ``export``,
``compare`` and ``study``, whose errors are :class:`~substruct.cli.errors.InputError` (one
line, exit code 2) instead of argparse's exit."""

from __future__ import annotations

import argparse
from typing import Any, NoReturn

from substruct.cli.errors import InputError

__all__ = ["COMMANDS", "build_parser", "add_compare_parser", "add_study_parser",
           "add_backend_options"]

#: The commands, in the order ``--help`` lists them.
COMMANDS = ("run", "converge", "info", "export", "compare", "study")


class ArgumentParser(argparse.ArgumentParser):
    """An argument parser whose errors are one line and exit code 2 (through
    :func:`substruct.cli.main.main`)."""

    def error(self, message: str) -> NoReturn:
        """Raise :class:`InputError` instead of printing the usage and exiting."""
        raise InputError(message)


def build_parser() -> argparse.ArgumentParser:
    """The parser of the ``substruct`` command; ``args.command`` names the command chosen."""
    from substruct import __version__

    parser = ArgumentParser(prog="substruct", description="Finite-element substructuring for "
                            "structural dynamics: coupled modes and receptances of constrained "
                            "substructures, from a case file.")
    parser.add_argument("--version", action="version", version=f"substruct {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="{" + ",".join(COMMANDS) + "}",
                                parser_class=ArgumentParser)

    run = sub.add_parser("run", help="run the analyses of a case file",
                         description="Run a case: write DIR/<name>.h5 and pictures beside it, "
                         "print the modes and an FRF summary.")
    run.add_argument("case", metavar="CASE.yaml", help="the case file")
    run.add_argument("--out", default="results", metavar="DIR",
                     help="output directory (default: results)")
    run.add_argument("--set", action="append", default=[], metavar="KEY.PATH=VALUE",
                     help="override a case value, e.g. substructures.c.stiffness=8000 "
                     "(repeatable; list items by name or 0-based index)")
    run.add_argument("--force", action="store_true", help="overwrite an existing result")
    run.add_argument("--no-pictures", action="store_true",
                     help="write the result file only (as output: {pictures: false})")
    run.add_argument("--quiet", action="store_true",
                     help="no progress bar and no table (errors are still reported)")
    run.add_argument("--json", action="store_true",
                     help="print a machine-readable summary instead of the table")
    add_backend_options(run, "the blocks of each level of an AMLS reduction (analysis.modes."
                        "solver: amls) and the samples of a virtual-point Monte Carlo study "
                        "(virtual_points.monte_carlo) as tasks")

    conv = sub.add_parser("converge", help="convergence study of a rod case",
                          description="Refine the case's rod by assumed modes, an enriched Ritz "
                          "basis and P1/P2 finite elements, with its attachments and "
                          "constraints; write DIR/<name>_convergence.h5 and .png, print "
                          "errors, fitted orders and costs.")
    conv.add_argument("case", metavar="CASE.yaml", help="the case file (one rod)")
    conv.add_argument("--levels", default=None, metavar="SPEC",
                      help="quick, default or fine, or items such as "
                      "'assumed=4:256; enriched=1,2,4; p1=8:1024; p2=4:512; g=4' "
                      "(default: default, g from the rod's reduce.modes)")
    conv.add_argument("--variants", default="constrained,unconstrained,bare", metavar="LIST",
                      help="comma list of constrained, unconstrained, bare "
                      "(default: all three)")
    conv.add_argument("--out", default="results", metavar="DIR",
                      help="output directory (default: results)")
    conv.add_argument("--set", action="append", default=[], metavar="KEY.PATH=VALUE",
                      help="override a case value (repeatable), as for run")
    conv.add_argument("--tol", type=float, default=1e-6,
                      help="tolerance of the 'DOFs to reach' summary (default: 1e-6)")
    conv.add_argument("--reference", choices=("richardson", "finest"), default="richardson",
                      help="limit the errors are measured against (default: richardson)")
    conv.add_argument("--force", action="store_true", help="overwrite existing outputs")
    conv.add_argument("--quiet", action="store_true", help="no progress bar and no table")
    conv.add_argument("--json", action="store_true",
                      help="print a machine-readable summary instead of the table")

    info = sub.add_parser("info", help="print what a result file holds")
    info.add_argument("result", metavar="RESULT.h5")
    info.add_argument("--json", action="store_true", help="machine-readable summary")

    export = sub.add_parser("export", help="write mode shapes for ParaView (VTU or XDMF), "
                            "receptances and modes as UFF 58/55/15 (uff), or the model's "
                            "matrices with their DOF map (op4, npz)")
    export.add_argument("result", metavar="RESULT.h5")
    export.add_argument("--format", required=True, choices=("vtu", "xdmf", "uff", "op4", "npz"))
    export.add_argument("--part", default=None, metavar="NAME",
                        help="with --format op4 or npz: this part's matrices instead of the "
                        "coupled model")
    export.add_argument("--modes", default=None, metavar="SPEC",
                        help="mode numbers, e.g. 1-6 or 1,3,5 (default: all)")
    export.add_argument("--variant", default=None, help="export the modes of this variant")
    export.add_argument("--transient", action="store_true",
                        help="with --format xdmf: the stored fields of the transient response "
                        "as a time series, instead of the modes")
    export.add_argument("--out", default=None, metavar="DIR",
                        help="output directory (default: beside the result)")
    export.add_argument("--force", action="store_true",
                        help="replace files of the same names (never the result itself)")
    add_compare_parser(sub)
    add_study_parser(sub)
    return parser


def add_compare_parser(sub: Any) -> None:
    """Add ``compare`` to the sub-parsers ``sub`` of the ``substruct`` parser (here, so that
    building the parser imports no command's module)."""
    p = sub.add_parser("compare", help="compare the modes of two results: frequencies, MAC")
    p.add_argument("first", metavar="A.h5")
    p.add_argument("second", metavar="B.h5")
    p.add_argument("--variant-a", default=None, help="the modes of this variant of A")
    p.add_argument("--variant-b", default=None, help="the modes of this variant of B")
    p.add_argument("--image", default=None, metavar="PNG",
                   help="draw the MAC matrix into this file (.png, .svg or .pdf)")
    p.add_argument("--force", action="store_true", help="replace an existing --image file")
    p.add_argument("--json", action="store_true", help="machine-readable output")


def add_study_parser(sub: Any) -> None:
    """Register ``study`` on the subparsers ``sub`` of :func:`build_parser`."""
    study = sub.add_parser("study", help="run the parameter study of a case file",
                           description="Run every sample of the case's study: block (a grid "
                           "or random samples of its parameters); write DIR/<name>_study.h5 "
                           "and pictures; print a summary.")
    study.add_argument("case", metavar="CASE.yaml", help="the case file (with a study: block)")
    study.add_argument("--out", default="results", metavar="DIR",
                       help="output directory (default: results)")
    study.add_argument("--set", action="append", default=[], metavar="KEY.PATH=VALUE",
                       help="override a case value (repeatable), as for run")
    add_backend_options(study, "the samples")
    study.add_argument("--force", action="store_true", help="overwrite an existing study file")
    study.add_argument("--no-pictures", action="store_true", help="write the study file only")
    study.add_argument("--quiet", action="store_true", help="no progress bar and no summary")
    study.add_argument("--json", action="store_true",
                       help="print a machine-readable summary instead of the table")

def add_backend_options(parser: Any, what: str) -> None:
    """``--workers N`` | ``--scheduler tcp://HOST:PORT`` and ``--connect-timeout``: where
    ``what`` runs (a Dask LocalCluster started here, or an existing cluster)."""
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, default=None, metavar="N",
                       help=f"run {what} on a Dask LocalCluster of N worker processes "
                       "(1 thread each)")
    where.add_argument("--scheduler", default=None, metavar="tcp://HOST:PORT",
                       help=f"run {what} on an existing Dask cluster (tcp:// only)")
    parser.add_argument("--connect-timeout", type=float, default=None, metavar="SECONDS",
                        help="with --scheduler: seconds to reach the scheduler and receive its "
                        "handshake (default: 5)")
