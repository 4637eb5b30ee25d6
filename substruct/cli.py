"""The ``substruct`` command: ``run``, ``info`` and ``export``.

::

    substruct run CASE.yaml [--out DIR] [--set key.path=value ...] [--force] [--quiet] [--json]
    substruct converge CASE.yaml [--levels quick|default|fine|"assumed=4:256; ..."]
                       [--variants constrained,unconstrained,bare] [--out DIR]
                       [--set key.path=value ...] [--tol 1e-6] [--reference richardson|finest]
                       [--force] [--quiet] [--json]
    substruct info RESULT.h5 [--json]
    substruct export RESULT.h5 --format vtu|xdmf [--modes 1-6] [--variant NAME] [--out DIR]

Exit codes: 0 success; 2 bad input (one line ``substruct: error: <message>`` on stderr, no
traceback, nothing written); 1 internal error (with its traceback); 130 interrupted (Ctrl-C);
143 terminated (SIGTERM; partly written files are removed either way).
``run`` checks that the output directory can be written and that the result does not exist
(unless ``--force``) before computing anything; so does ``converge`` (a convergence study of the
case's rod, :mod:`substruct.studies.convergence`), which writes ``DIR/<name>_convergence.h5`` and
``.png``.
"""

from __future__ import annotations

import os

# BLAS on one thread unless the user says otherwise, before numpy loads: the dense blocks here
# are small or mid-sized and threaded OpenBLAS on two busy cores made a 400-frequency sweep of
# cases/two_rods_spring.yaml 8x slower (50 s vs 6.5 s) and a 1600 x 1600 eig 1.25x slower.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import traceback  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any, Sequence, TextIO  # noqa: E402

import numpy as np  # noqa: E402

__all__ = ["main"]

#: Sweeps with more frequencies than this show a progress bar (unless ``--quiet``).
PROGRESS_MIN = 50


class InputError(Exception):
    """Bad input found by the command line itself (exit code 2)."""


class _Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line and exit code 2 (through :func:`main`)."""

    def error(self, message: str) -> None:  # type: ignore[override]
        raise InputError(message)


# ------------------------------------------------------------------------- arguments


def _parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="substruct", description="Finite-element substructuring for "
                     "structural dynamics: coupled modes and receptances of constrained "
                     "substructures, from a case file.")
    from substruct import __version__
    parser.add_argument("--version", action="version", version=f"substruct {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="{run,converge,info,export}",
                                parser_class=_Parser)

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
    run.add_argument("--quiet", action="store_true",
                     help="no progress bar and no table (errors are still reported)")
    run.add_argument("--json", action="store_true",
                     help="print a machine-readable summary instead of the table")
    run.set_defaults(func=_cmd_run)

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
    conv.set_defaults(func=_cmd_converge)

    info = sub.add_parser("info", help="print what a result file holds")
    info.add_argument("result", metavar="RESULT.h5")
    info.add_argument("--json", action="store_true", help="machine-readable summary")
    info.set_defaults(func=_cmd_info)

    export = sub.add_parser("export", help="write mode shapes for ParaView (VTU or XDMF)")
    export.add_argument("result", metavar="RESULT.h5")
    export.add_argument("--format", required=True, choices=("vtu", "xdmf"))
    export.add_argument("--modes", default=None, metavar="SPEC",
                        help="mode numbers, e.g. 1-6 or 1,3,5 (default: all)")
    export.add_argument("--variant", default=None, help="export the modes of this variant")
    export.add_argument("--out", default=None, metavar="DIR",
                        help="output directory (default: beside the result)")
    export.set_defaults(func=_cmd_export)
    return parser


# ---------------------------------------------------------------------------- helpers


def _writable_dir(out: Path, what: str) -> None:
    """Raise :class:`InputError` unless ``out`` is, or can be created as, a writable directory.

    Nothing is left behind: a probe file in the nearest existing directory is removed again.
    """
    if out.exists() and not out.is_dir():
        raise InputError(f"{what} {out} exists and is not a directory")
    probe = out
    while not probe.exists():
        if probe.parent == probe:
            break
        probe = probe.parent
    if not probe.is_dir():
        raise InputError(f"{what} {out}: {probe} is not a directory")
    try:
        with tempfile.TemporaryFile(dir=probe):
            pass
    except OSError as err:
        raise InputError(f"{what} {out} is not writable ({err.strerror or err})") from None


def _module(name: str) -> Any:
    """``substruct.<name>``, imported on demand."""
    import importlib
    try:
        return importlib.import_module(f"substruct.{name}")
    except ModuleNotFoundError as err:
        if err.name == f"substruct.{name}":
            raise RuntimeError(f"substruct.{name} is not available in this installation") \
                from None
        raise


class _Bar:
    """A plain progress bar on stderr for sweeps of more than ``minimum`` points
    (:data:`PROGRESS_MIN`); ``title`` and ``unit`` name the sweep (``FRF``, ``frequencies``)."""

    def __init__(self, stream: TextIO, width: int = 30, *, title: str = "FRF",
                 unit: str = "frequencies", minimum: int = PROGRESS_MIN):
        self.stream, self.width, self.last = stream, width, -1
        self.title, self.unit, self.minimum = title, unit, minimum

    def __call__(self, done: int, total: int, label: str) -> None:
        if total <= self.minimum:
            return
        tty = getattr(self.stream, "isatty", lambda: False)()
        if not tty:  # a log file: one line per sweep, no carriage returns
            if done >= total:
                self.stream.write(f"{self.title} {label}: {total} {self.unit} done\n")
                self.stream.flush()
            return
        filled = int(self.width * done / total)
        if filled == self.last and done < total:
            return
        self.last = filled
        bar = "#" * filled + "." * (self.width - filled)
        self.stream.write(f"\r{self.title} {label:<20s} [{bar}] {done}/{total}")
        if done >= total:
            self.stream.write("\n")
            self.last = -1
        self.stream.flush()


def _num(x: float) -> Any:
    """A JSON-safe float (``null`` for nan, a string for inf)."""
    x = float(x)
    return x if math.isfinite(x) else (None if math.isnan(x) else ("inf" if x > 0 else "-inf"))


def _complex(z: complex, digits: int = 4, scientific: bool = False) -> str:
    """``a+bi`` with ``digits`` decimals, or ``digits`` significant figures in scientific
    notation (``1.234e-09-5.678e-11i``)."""
    if scientific:
        return f"{z.real:.{digits - 1}e}{z.imag:+.{digits - 1}e}i"
    return f"{z.real:.{digits}f}{z.imag:+.{digits}f}i"


def _scientific(H: np.ndarray) -> bool:
    """Whether a receptance matrix needs scientific notation: fixed decimals would print
    the small receptances of stiff structures in SI units (``1e-9 m/N``) as ``0.0000``."""
    scale = float(np.abs(H).max()) if np.size(H) else 0.0
    return scale != 0.0 and not 0.1 <= scale < 1e5


# ------------------------------------------------------------------------ summaries


def _reasons(mr) -> dict[str, int]:
    counts: dict[str, int] = {}
    for r in mr.spurious_reason:
        counts[r] = counts.get(r, 0) + 1
    return counts


def _modes_json(mr) -> dict[str, Any]:
    return {"method": mr.method, "omega": [_num(w) for w in mr.omega],
            "freq_hz": [_num(f) for f in mr.freq_hz],
            "damping_ratio": [_num(z) for z in mr.damping_ratio],
            "residual": [_num(r) for r in mr.residual],
            "eigenvalues": [[_num(z.real), _num(z.imag)] for z in mr.eigenvalues],
            "spurious": {"count": int(len(mr.spurious)), "reasons": _reasons(mr)},
            "agreement": {k: _num(v) for k, v in mr.agreement.items()}}


def _summary_json(result, files: Sequence[Path] = ()) -> dict[str, Any]:
    out: dict[str, Any] = {"case": result.case_name, "files": [str(f) for f in files],
                           "attrs": {k: (v if isinstance(v, (str, int, float, bool)) else str(v))
                                     for k, v in result.attrs.items()},
                           "model": {"substructures": list(result.model.substructure_names),
                                     "kinds": list(result.model.substructure_kinds),
                                     "n_dof": int(result.model.offsets[-1]),
                                     "constraints": list(result.model.constraint_labels)}}
    if result.modes is not None:
        out["modes"] = _modes_json(result.modes)
    if result.variants:
        out["variants"] = {k: _modes_json(v) for k, v in result.variants.items()}
    if result.frf is not None:
        frf = result.frf
        H = np.asarray(frf.H)
        out["frf"] = {"method": frf.method, "n_omega": int(len(frf.omega)),
                      "omega_range": [_num(frf.omega.min()), _num(frf.omega.max())],
                      "inputs": list(frf.inputs), "outputs": list(frf.outputs),
                      "max_abs_H": _num(np.abs(H).max()),
                      "constraint_residual": _num(frf.constraint_residual),
                      "agreement": {k: _num(v) for k, v in frf.agreement.items()}}
        if H.size <= 1000:
            out["frf"]["H"] = {"real": H.real.tolist(), "imag": H.imag.tolist()}
    return out


def _print_modes(mr, out: TextIO, requested: int | None = None) -> None:
    n = len(mr.omega)
    more = f" of {requested} requested" if requested is not None and requested > n else ""
    out.write(f"  {n} physical mode(s){more}, {mr.method}:\n")
    out.write(f"  {'mode':>4s}  {'omega (rad/s)':>14s}  {'f (Hz)':>12s}  "
              f"{'damping ratio':>13s}  {'|A u| residual':>14s}\n")
    for j in range(n):
        zeta = float(mr.damping_ratio[j])
        zeta = 0.0 if abs(zeta) < 5e-13 else zeta  # no "-0.0000" from round-off
        out.write(f"  {j + 1:4d}  {mr.omega[j]:14.4f}  {mr.freq_hz[j]:12.4f}  "
                  f"{zeta:13.4f}  {mr.residual[j]:14.1e}\n")
    if len(mr.spurious):
        out.write(f"  spurious roots set aside: {len(mr.spurious)}\n")
        for reason, count in _reasons(mr).items():
            out.write(f"    {count} x {reason}\n")
    if mr.agreement:
        figures = ", ".join(f"{k} {v:.1e}" for k, v in mr.agreement.items())
        out.write(f"  agreement with check formulations (max relative eigenvalue "
                  f"difference): {figures}\n")


def _print_summary(result, out: TextIO, requested: int | None = None,
                   drops: dict[str, list[str]] | None = None) -> None:
    model = result.model
    names = model.substructure_names
    out.write(f"{result.case_name}: {int(model.offsets[-1])} coordinates in {len(names)} "
              f"substructure(s) ({', '.join(names)}), {len(model.constraint_labels)} "
              f"constraint row(s)\n")
    if result.modes is not None:
        out.write("modes\n")
        _print_modes(result.modes, out, requested)
    for name, mr in result.variants.items():
        dropped = f" (drops {', '.join(drops[name])})" if drops and name in drops else ""
        out.write(f"variant {name}{dropped}\n")
        _print_modes(mr, out, requested)
    if result.frf is not None:
        _print_frf(result.frf, out)


def _print_frf(frf, out: TextIO) -> None:
    H = np.asarray(frf.H)
    w = np.asarray(frf.omega)
    span = f"omega = {w[0]:g} rad/s" if len(w) == 1 else \
        f"{len(w)} frequencies, {w.min():g} to {w.max():g} rad/s"
    out.write(f"FRF ({frf.method}): {span}, {len(frf.outputs)} output(s) x "
              f"{len(frf.inputs)} input(s)\n")
    out.write(f"  constraint residual max|A q - R F| / max|H|: {frf.constraint_residual:.1e}\n")
    if frf.agreement:
        figures = ", ".join(f"{k} {v:.1e}" for k, v in frf.agreement.items())
        out.write(f"  agreement with check formulations (max |H - H_check| / max |H|): "
                  f"{figures}\n")
    if len(w) <= 3 and H.shape[1] * H.shape[2] <= 64:
        width = max(len(s) for s in frf.outputs)
        for k, wk in enumerate(w):
            out.write(f"  H at omega = {wk:g} rad/s (rows: outputs, columns: inputs "
                      f"{', '.join(frf.inputs)}):\n")
            sci = _scientific(H[k])
            for i, name in enumerate(frf.outputs):
                row = "  ".join(f"{_complex(z, scientific=sci):>{22 if sci else 16}s}"
                                for z in H[k, i])
                out.write(f"    {name:<{width}s}  {row}\n")
        return
    for i, o in enumerate(frf.outputs[:6]):
        for j, inp in enumerate(frf.inputs[:6]):
            mag = np.abs(H[:, i, j])
            k = int(np.argmax(mag))
            out.write(f"  {o} / {inp}: max |H| = {mag[k]:.4g} at omega = {w[k]:.4g} rad/s\n")


# ------------------------------------------------------------------------- commands


def _cmd_run(args: argparse.Namespace) -> int:
    from substruct.case.loader import load_case
    from substruct.run.runner import build_model, run_case

    case = load_case(args.case, args.set)
    out = Path(args.out)
    target = out / f"{case.name}.h5"
    _writable_dir(out, "--out")
    for path in [target, *(_picture_paths(case, out) if case.output.pictures else [])]:
        if path.exists() and not args.force:
            raise InputError(f"{path} exists; use --force to overwrite it")
        if path.is_dir():
            raise InputError(f"{path} is a directory")
    model = build_model(case)
    results = _module("io.hdf5")
    show = not args.quiet and not args.json
    bar = _Bar(sys.stderr) if not args.quiet else None
    result = run_case(case, progress=bar, model=model)
    files = [Path(results.save(result, target))]
    if case.output.pictures:
        files += _pictures(result, out, case.name)
    if args.json:
        print(json.dumps(_summary_json(result, files), indent=1))
    elif show:
        drops = {v.name: list(v.drop) for v in case.analysis.modes.variants} \
            if case.analysis.modes else {}
        requested = case.analysis.modes.count if case.analysis.modes else None
        _print_summary(result, sys.stdout, requested, drops)
        if any(b != 0 for b in result.model.b):
            print("note: constant right-hand sides (rhs) do not enter modes or receptances")
        print("written: " + ", ".join(str(f) for f in files))
    return 0


def _picture_paths(case, out: Path) -> list[Path]:
    """Every picture :func:`_pictures` may write for ``case`` (checked before running)."""
    name, modes = case.name, case.analysis.modes
    paths = []
    if modes is not None:
        paths += [out / f"{name}_modes.png"]
        paths += [out / f"{name}_modes_{v.name}.png" for v in modes.variants]
    if case.analysis.frf is not None:
        paths.append(out / f"{name}_frf.png")
    return paths


def _pictures(result, out: Path, name: str) -> list[Path]:
    plotting = _module("viz.plotting")
    files = []
    if result.modes is not None and len(result.modes.omega) and result.model.drawings:
        files.append(Path(plotting.plot_modes(result, out / f"{name}_modes.png")))
        for variant, mr in result.variants.items():
            if len(mr.omega):
                files.append(Path(plotting.plot_modes(
                    result, out / f"{name}_modes_{variant}.png", variant=variant)))
    if result.frf is not None:
        files.append(Path(plotting.plot_frf(result, out / f"{name}_frf.png")))
    return files


def _cmd_converge(args: argparse.Namespace) -> int:
    from substruct.case.loader import load_case
    from substruct.studies.convergence import VARIANTS, parse_levels, study_variants
    from substruct.studies.convergence_case import spec_from_case
    report = _module("studies.convergence_report")

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
    _writable_dir(out, "--out")
    targets = report.output_paths(out, spec.name)
    for target in targets:
        if target.is_dir():
            raise InputError(f"{target} is a directory")
        if target.exists() and not args.force:
            raise InputError(f"{target} exists; use --force to overwrite it")
    progress = None
    if not args.quiet:
        bar = _Bar(sys.stderr, title="converge", unit="levels", minimum=0)
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


def _load_result(path: str) -> Any:
    results = _module("io.hdf5")
    try:
        return results.load(path)
    except FileNotFoundError:
        raise InputError(f"{path}: no such file") from None
    except (ValueError, OSError) as err:
        raise InputError(" ".join(str(err).split())) from None


def _cmd_info(args: argparse.Namespace) -> int:
    result = _load_result(args.result)
    if args.json:
        print(json.dumps(_summary_json(result, [Path(args.result)]), indent=1))
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
    _print_summary(result, sys.stdout)
    return 0


def _cmd_export(args: argparse.Namespace) -> int:
    result = _load_result(args.result)
    out = Path(args.out) if args.out else Path(args.result).resolve().parent
    _writable_dir(out, "--out")
    export = _module("io.export")
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


# ----------------------------------------------------------------------------- main


def _fail(message: str) -> int:
    sys.stderr.write(f"substruct: error: {' '.join(str(message).split())}\n")
    return 2


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``substruct`` command line; return the exit code."""
    parser = _parser()
    try:
        args = parser.parse_args(argv)
    except InputError as err:
        return _fail(str(err))
    except SystemExit as exc:  # --help, --version
        return int(exc.code or 0)
    if getattr(args, "func", None) is None:
        return _fail("choose a command: run, converge, info or export (see substruct --help)")
    from substruct.case.loader import CaseError
    restore = _terminate_on_sigterm()
    try:
        return int(args.func(args))
    except (InputError, CaseError) as err:
        return _fail(str(err))
    except KeyboardInterrupt:
        sys.stderr.write("substruct: interrupted\n")
        return 130
    except Terminated:  # temporary files were removed on the way out
        sys.stderr.write("substruct: terminated\n")
        return 143
    except BrokenPipeError:  # the reader went away (substruct info ... | head)
        _silence_stdout()
        return 0
    except Exception:  # an internal error: show everything
        traceback.print_exc()
        return 1
    finally:
        restore()


class Terminated(BaseException):
    """SIGTERM arrived while a command ran; it unwinds like Ctrl-C, so that partly written
    files (``*.part``) are removed on the way out (exit code 143)."""


def _terminate_on_sigterm() -> Any:
    """Turn SIGTERM into :class:`Terminated` until the returned undo function is called."""
    import signal
    import threading
    if threading.current_thread() is not threading.main_thread():
        return lambda: None

    def handler(signum: int, frame: Any) -> None:
        raise Terminated()
    previous = signal.signal(signal.SIGTERM, handler)
    return lambda: signal.signal(signal.SIGTERM, previous)


def _silence_stdout() -> None:
    """Point stdout at /dev/null so that the interpreter's final flush does not fail."""
    import os
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):
        pass


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
