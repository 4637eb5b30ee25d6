"""``substruct run CASE.yaml``: check the outputs can be written, run the case, write the
result file and its pictures as one set, print the table (or ``--json``).

The order of a run:

1. the case and the output paths are checked (:func:`~substruct.cli.files.check_out_dir`);
2. the output directory is locked (:class:`~substruct.io.file_set.OutputDir`: a second run
   into it fails with "another run is writing DIR"; leftovers of killed runs are removed);
3. a staging folder is made in it, and a child process (:func:`~substruct.cli.isolated.
   call_isolated`: SIGTERM and Ctrl-C act at once even inside a long dense solve) builds and
   analyses the model, draws the pictures (optional: ``--no-pictures``,
   ``output: {pictures: false}``) into the staging folder, writes the result file beside them
   (large arrays a block at a time), then the transient animation, and renders the report
   (table or ``--json``) (:func:`stage_set`).  The result never leaves the child: only the
   names of the files and the report come back, so a 2.6 GB receptance is neither copied nor
   sent between the processes;
4. the set is committed: the new files move into place together and the previous set's
   pictures that the new set does not have are removed.  Interrupted or failed at any point
   before, the directory holds the previous set; after, the new one; never a mix.
"""

from __future__ import annotations

import argparse
import io
import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from substruct.cli.files import (check_out_dir, check_targets, collector_paused, input_files,
                                 optional_module)
from substruct.cli.errors import InputError
from substruct.cli.isolated import call_isolated
from substruct.cli.progress import PhaseLog, ProgressBar, phases_wanted

if TYPE_CHECKING:
    from substruct.run.result import Result

__all__ = ["run_command", "run_backend", "amls_solvers", "monte_carlo_case", "picture_paths",
           "write_pictures", "write_case_pictures", "compute",
           "stage_set"]


def compute(case: Any, quiet: bool, frf_sink: Any = None, backend: Any = None,
            field_sink: Any = None) -> Result:
    """Build and analyse ``case`` (in the child process of :func:`run_command`); the
    receptances go to ``frf_sink`` as they are computed, and a transient run's stored fields
    to ``field_sink`` as they are recorded, if given
    (:func:`substruct.run.runner.run_case`); with a ``backend``
    (:class:`~substruct.studies.study_backend.Backend`, ``--workers`` or ``--scheduler``), the
    blocks of each level of an AMLS reduction are its tasks."""
    with collector_paused():  # loading the builder and the analyses
        import substruct.run.runner as runner

    show = phases_wanted(sys.stderr, quiet)  # the sweeps' lines as the phases
    bar = ProgressBar(sys.stderr) if show else None
    events = PhaseLog(sys.stderr, show, warn=not quiet)
    model = runner.build_model(case, events)
    if backend is None:
        return runner.run_case(case, progress=bar, model=model, events=events,
                              frf_sink=frf_sink, field_sink=field_sink)
    from substruct.studies.study_backend import BackendError, Session

    try:
        with Session(backend) as session:
            if not quiet:
                what = "Monte Carlo samples" if monte_carlo_case(case) else "AMLS tasks"
                events("amls", f"{what} on {backend.describe()}", 0)
            return runner.run_case(case, progress=bar, model=model, events=events,
                                   frf_sink=frf_sink, tasks=session,
                                   field_sink=field_sink)
    except BackendError as err:
        raise InputError(str(err)) from None


def run_backend(args: argparse.Namespace, case: Any) -> Any:
    """The backend of ``--workers``/``--scheduler`` (``None`` without them), refused unless
    the case reduces by AMLS (``solver: amls`` in any of :func:`amls_solvers`) or has a Monte
    Carlo study (``virtual_points.monte_carlo``), the analyses of ``run`` whose tasks it runs."""
    if getattr(args, "workers", None) is None and getattr(args, "scheduler", None) is None:
        if getattr(args, "connect_timeout", None) is not None:
            raise InputError(f"--connect-timeout: only with --scheduler, got "
                             f"{args.connect_timeout!r}")
        return None
    from substruct.cli.study_command import backend_options

    backend = backend_options(args)
    solvers = amls_solvers(case)
    if "amls" not in solvers.values() and not monte_carlo_case(case):
        flag = "--workers" if args.workers is not None else "--scheduler"
        got = ", ".join(f"{k} {v}" for k, v in solvers.items()) or "no modal analysis"
        raise InputError(f"{flag}: runs the blocks of an AMLS reduction or the samples of a "
                         f"virtual-point Monte Carlo study as tasks; the case has no "
                         f"virtual_points.monte_carlo and no solver: amls in analysis.modes "
                         f"or the modal block of analysis.frf, random or transient, got {got}")
    return backend


def amls_solvers(case: Any) -> dict[str, str]:
    """The eigensolver of each analysis of ``case`` that may reduce by AMLS, by its field:
    ``analysis.modes``, and the modal sums of ``analysis.frf`` (``method`` modal or auto),
    ``analysis.random`` (``method: modal``) and ``analysis.transient`` (the modal form, its
    method or a check)."""
    a = case.analysis
    found = {}
    if a.modes is not None:
        found["analysis.modes.solver"] = a.modes.solver
    if a.frf is not None and a.frf.method in ("modal", "auto"):
        found["analysis.frf.modal.solver"] = a.frf.modal.solver
    for name, block, used in (
            ("random", a.random, a.random is not None and a.random.method == "modal"),
            ("transient", a.transient, a.transient is not None
             and "modal" in (a.transient.method, *a.transient.check))):
        if used:
            modal = block.modal
            found[f"analysis.{name}.modal.solver"] = "auto" if modal is None else modal.solver
    return found


def monte_carlo_case(case: Any) -> bool:
    """Whether a substructure of ``case`` asks for a Monte Carlo study of its virtual points
    (its samples are tasks)."""
    return any(getattr(getattr(s, "virtual_points", None), "monte_carlo", None) is not None
               for s in case.substructures)


def run_command(args: argparse.Namespace) -> int:
    """Run ``args.case`` into ``args.out``; return the exit code (0).

    The output directory and every file the run may write are checked before anything is
    computed; the result file is written only once every analysis (and its cross-checks)
    has passed, together with its pictures and animation, and the set is committed only once
    its report is ready: an error before the commit leaves no file of the set.
    """
    with collector_paused():
        from substruct.case.loader import load_case
        from substruct.io.file_set import OutputDir

        case = load_case(args.case, args.set)
        backend = run_backend(args, case)
        pictures = case.output.pictures and not getattr(args, "no_pictures", False)
        h5_name = f"{case.name}.h5"
        candidates = [p.name for p in picture_paths(case, Path("."))]
        out = check_out_dir(args.out, "--out", [h5_name, *candidates])
    with OutputDir(out) as target:  # BusyError on entering: nothing was computed
        report = _run_locked(case, args, target, out, h5_name, candidates, pictures, backend)
    sys.stdout.write(report)
    return 0


def _run_locked(case: Any, args: argparse.Namespace, target: Any, out: Path, h5_name: str,
                candidates: list[str], pictures: bool, backend: Any = None) -> str:
    """Check the targets, stage the set in a child (:func:`stage_set`), commit; the report."""
    check_targets(out, [h5_name, *(candidates if pictures else [])], input_files(case),
                  args.force)
    with collector_paused():
        results = optional_module("io.hdf5")
    old = results.listed_pictures(out / h5_name) if (out / h5_name).exists() else []
    staging = target.stage(case.name)
    new, report = call_isolated(lambda: stage_set(case, args, staging, out, pictures,
                                                        backend))
    staged = sorted(p.name for p in staging.iterdir())
    if staged != sorted(new):
        raise RuntimeError(f"the run staged {staged}, expected {sorted(new)}")
    gone = [n for n in {*candidates, *old} if n not in new and n.startswith(f"{case.name}_")
            and (out / n).is_file()]
    target.commit(staging, remove=gone)
    return report


def stage_set(case: Any, args: argparse.Namespace, staging: Path, out: Path,
              pictures: bool, backend: Any = None) -> tuple[list[str], str]:
    """Compute the case, then write its set into ``staging``: the pictures, the result file
    (with the names of the pictures), the transient animation; render the report.  Return
    the names written and the report (in the child process of :func:`run_command`).

    The result stays in this process.  The result file is opened (under a temporary name)
    before the computation, and the receptance sweep writes its blocks of frequencies into it
    as they are computed (:func:`substruct.io.hdf5.result_file`): the whole receptance is
    never in memory; so do the fields a transient run stores.  The summary and the pictures
    are drawn from what the sweep kept as the blocks passed (its largest value, the first
    curves) or from a selection read back (the animation's frames); the rest of the result is
    written once the pictures are drawn, and the file is renamed into place only then.  Only
    the names and the report go back to the parent.
    """
    from substruct.io.paths import write_errors

    results = optional_module("io.hdf5")
    h5_name = f"{case.name}.h5"
    drawn: list[Path] = []
    with results.result_file(staging / h5_name, where=out) as h5:
        result = compute(case, args.quiet, h5.frf_sink, backend, h5.field_sink)
        with write_errors(out):
            if pictures:
                drawn = write_pictures(result, staging, case.name)
                drawn += write_case_pictures(case, staging, result)
            result.attrs["pictures"] = "\n".join(p.name for p in drawn)
            h5.save(result)
            # the animation reads its frames back from the file, still open
            tr = result.transient
            if pictures and tr is not None and len(tr.snapshot_t) and result.model.drawings:
                movie = optional_module("viz.transient_animation")
                gif = staging / f"{case.name}_transient.gif"
                movie.write_transient_gif(result, gif)
                drawn.append(gif)
    new = [h5_name, *(p.name for p in drawn)]
    return new, _report(args, case, result, [out / name for name in new])


def _report(args: argparse.Namespace, case: Any, result: Result, files: list[Path]) -> str:
    """What the run prints (the table, ``--json`` or nothing), as text (the tables' module is
    imported only for a report that is printed)."""
    text = io.StringIO()
    if args.json or not args.quiet:
        from substruct.cli.summary import print_summary, summary_json
    if args.json:
        print(json.dumps(summary_json(result, files), indent=1), file=text)
    elif not args.quiet:
        modes = case.analysis.modes
        drops = {v.name: list(v.drop) for v in modes.variants} if modes else {}
        print_summary(result, text, modes.count if modes else None, drops)
        if any(b != 0 for b in result.model.b):
            print("note: constant right-hand sides (rhs) do not enter modes or receptances",
                  file=text)
        print("written: " + ", ".join(str(f) for f in files), file=text)
    return text.getvalue()


def picture_paths(case: Any, out: Path) -> list[Path]:
    """Every picture :func:`write_pictures` may write for ``case`` (checked before running)."""
    name, modes = case.name, case.analysis.modes
    paths = []
    if modes is not None:
        paths += [out / f"{name}_modes.png"]
        paths += [out / f"{name}_modes_{v.name}.png" for v in modes.variants]
    if case.analysis.frf is not None:
        paths.append(out / f"{name}_frf.png")
    if case.analysis.frf is not None and any(
            getattr(s, "virtual_points", None) is not None for s in case.substructures):
        paths.append(out / f"{name}_consistency.png")
    if any(getattr(s, "virtual_points", None) is not None for s in case.substructures):
        paths.append(out / f"{name}_vp_geometry.png")
    if any(getattr(getattr(s, "virtual_points", None), "monte_carlo", None) is not None
           for s in case.substructures):
        paths.append(out / f"{name}_monte_carlo.png")
    if case.analysis.tpa is not None:
        paths += [out / f"{name}_paths.png", out / f"{name}_validation.png"]
    if case.analysis.transient is not None:
        paths.append(out / f"{name}_transient.png")
        if case.analysis.transient.field_every:
            paths.append(out / f"{name}_transient.gif")
    if case.analysis.random is not None:
        paths.append(out / f"{name}_random.png")
    if case.analysis.srs is not None:
        paths.append(out / f"{name}_srs.png")
    return paths


def write_case_pictures(case: Any, out: Path, result: Result | None = None) -> list[Path]:
    """The virtual-point geometry picture (channels and virtual points of every part with
    ``virtual_points:``, :mod:`substruct.viz.vp_geometry_picture`), drawn from the geometry
    the result keeps (``/channels``) when it has one, else from the case."""
    if not any(getattr(s, "virtual_points", None) is not None for s in case.substructures):
        return []
    geo = optional_module("viz.vp_geometry_picture")
    parts = geo.geometry_of(result.channels) if result is not None and result.channels \
        else geo.vp_geometry(case)
    return [Path(geo.plot_vp_geometry(parts, out / f"{case.name}_vp_geometry.png",
                                      f"{case.name}: virtual-point geometry"))]


def write_pictures(result: Result, out: Path, name: str) -> list[Path]:
    """The mode pictures (main modes and each variant), the receptance picture, the
    transient histories and the random response's PSDs and shock response spectra
    (:mod:`substruct.viz.spec_picture`); the plotting modules are imported here, only when a picture is
    drawn."""
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
    if result.virtual_points or result.tpa is not None or result.monte_carlo is not None \
            or result.semm is not None:
        lab = optional_module("viz.testlab_picture")
        if result.virtual_points:
            files.append(Path(lab.plot_consistency(result, out / f"{name}_consistency.png")))
        if result.monte_carlo is not None:
            files.append(Path(lab.plot_monte_carlo(result, out / f"{name}_monte_carlo.png")))
        if result.tpa is not None:
            files.append(Path(lab.plot_paths(result, out / f"{name}_paths.png")))
            files.append(Path(lab.plot_validation(result, out / f"{name}_validation.png")))
        if result.semm is not None:
            files.append(Path(lab.plot_semm(result, out / f"{name}_semm.png")))
    tr = result.transient
    if tr is not None and tr.t.size and (tr.outputs or tr.constraint_forces.size):
        picture = optional_module("viz.transient_picture")
        files.append(Path(picture.plot_transient(result, out / f"{name}_transient.png")))
    if result.random is not None or result.srs is not None:
        spec = optional_module("viz.spec_picture")
        if result.random is not None:
            files.append(spec.plot_random(result.random, result.case_name,
                                          out / f"{name}_random.png"))
        if result.srs is not None:
            files.append(spec.plot_srs(result.srs, result.case_name, out / f"{name}_srs.png"))
    return files
