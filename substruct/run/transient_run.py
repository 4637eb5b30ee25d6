r"""``analysis.transient`` of a case on its model: a thin adapter to
:func:`substruct.analysis.transient.response.transient` (eqs 5, 10).

A force at point ``p`` is the generalized force :math:`r(p)^T f(t)`; an output is
:math:`r(p)\, q(t)`.  A ground motion at point ``p`` moves the constraint rows that hold ``p``
alone, :math:`A_i = c\, r(p)` (:mod:`substruct.analysis.transient.base`).

Input the analysis cannot take (:data:`~substruct.analysis.errors.INPUT_ERRORS`,
:class:`~substruct.analysis.transient.initial.InitialStateError`) becomes a
:class:`~substruct.case.loader.CaseError` at ``analysis.transient`` (exit 2), and so does a
signal, table or state file the case layer's readers refuse (their ``ValueError``, caught
around those calls only); a check beyond the tolerance stays a
:class:`~substruct.analysis.errors.CheckError` (exit 1).  Any other exception, a plain
``ValueError`` of the analysis included, is an internal error: a bug never passes as bad input.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sp

from substruct.analysis.api import modes
from substruct.analysis.errors import INPUT_ERRORS, CheckError
from substruct.analysis.transient import (
    InitialConditions,
    LoadHistory,
    TransientOptions,
    TransientOutputs,
    transient,
)
from substruct.analysis.transient.base import BaseMotion
from substruct.analysis.transient.fields import FieldSink
from substruct.analysis.transient.initial import InitialStateError
from substruct.analysis.transient.results import Transient
from substruct.builder.model import Model
from substruct.case.fields import MEMORY_LIMIT, gigabytes
from substruct.case.expressions import ExpressionError
from substruct.case.loader import Case
from substruct.analysis.transient.loads import merge_pairs, step_pairs
from substruct.case.modal_spec import TransientModal
from substruct.case.transient import load_values
from substruct.case.transient_files import npz_only, npz_vector
from substruct.case.transient_signals import waveform
from substruct.linalg.task_runner import TaskRunner
from substruct.run.modal_options import amls_options

__all__ = ["transient_result"]


def _mode(case: Case, model: Model, k: int, field: str) -> np.ndarray:
    """Coupled mode ``k`` (1-based, M-normalized, real)."""
    asm = model.assembly
    if k > asm.n_dof:
        raise case.error(("analysis", "transient", "initial", field),
                         f"more than the {asm.n_dof} coordinates", k)
    try:
        md = modes(asm.M, None, asm.K, asm.A, k, what="transient (initial mode)")
    except INPUT_ERRORS as err:
        raise case.error(("analysis", "transient", "initial", field),
                         " ".join(str(err).split()), k) from None
    if len(md) < k:
        raise case.error(("analysis", "transient", "initial", field),
                         f"the model has {len(md)} modes", k)
    return np.asarray(md.shapes[:, k - 1]).real


def _grounding_rows(case: Case, model: Model) -> np.ndarray:
    """``m``: the coefficient ``c`` of each constraint row ``A_i = c r(p)`` that grounds a
    point ``p`` of ``analysis.transient.base.at`` (0 for the other rows)."""
    spec = case.analysis.transient
    assert spec is not None and spec.base is not None
    asm = model.assembly
    A = sp.csr_array(asm.A)
    coef = np.zeros(A.shape[0])
    for i, p in enumerate(spec.base.at):
        r = asm.row(model.points[p]).toarray().ravel()
        rr = float(r @ r)
        found = False
        for k in np.flatnonzero(np.abs(A @ r) > 0.0):
            row = A[[k]].toarray().ravel()
            c = float(row @ r) / rr if rr else 0.0
            if c and np.abs(row - c * r).max() <= 1e-12 * np.abs(row).max():
                coef[k], found = c, True
        if not found:
            raise case.error(("analysis", "transient", "base", "at", i),
                             "not a grounded support: no active constraint holds this point "
                             "alone (add one with terms: {point: 1})", p)
    return coef


def _base(case: Case, model: Model, t: np.ndarray) -> BaseMotion | None:
    """The ground motion of ``analysis.transient.base``, or ``None``."""
    spec = case.analysis.transient
    assert spec is not None
    if spec.base is None:
        return None
    sig, kind = spec.base.signal, spec.base.kind
    params = dict(case.parameters)
    d = max(1e-3 * float(t[1] - t[0]), 1e-12)
    try:  # the case layer's reading and evaluation of the signal, nothing else
        values = load_values(sig, t, case.base_dir, params)
        g = (load_values(sig, np.array([0.0, d, 2 * d]), case.base_dir, params)
             if kind == "displacement" else None)
    except ValueError as err:
        field = sig.shape if sig.shape in ("table", "expression") else "amplitude"
        raise case.error(("analysis", "transient", "base", kind, field),
                         " ".join(str(err).split()), getattr(sig, field)) from None
    rate0 = accel0 = 0.0
    if g is not None:  # g'(0), g''(0): one-sided differences of the signal
        g0, g1, g2 = g
        rate0, accel0 = (-3 * g0 + 4 * g1 - g2) / (2 * d), (g0 - 2 * g1 + g2) / d ** 2
    return BaseMotion(rows=_grounding_rows(case, model), kind=kind, values=values,
                      rate0=float(rate0), accel0=float(accel0))


def _loads(case: Case, t: np.ndarray, steps: int
           ) -> tuple[np.ndarray, dict[int, tuple[np.ndarray, np.ndarray]]]:
    """``(f, pairs)``: the load factors at the instants ``t`` and the pairs of the steps over
    which a load jumps or kinks (:mod:`substruct.analysis.transient.loads`)."""
    spec = case.analysis.transient
    assert spec is not None
    f = np.zeros((steps + 1, len(spec.loads)))
    columns = []
    for j, load in enumerate(spec.loads):
        field = load.shape if load.shape in ("table", "expression") else "amplitude"
        loc, shown = ("analysis", "transient", "loads", j, field), getattr(load, field,
                                                                            load.amplitude)
        try:  # the case layer's reading and evaluation of the signal, nothing else
            wave = waveform(load, case.base_dir, dict(case.parameters))
            f[:, j] = wave.values(t)
        except ValueError as err:
            raise case.error(loc, " ".join(str(err).split()), shown) from None
        if not np.all(np.isfinite(f[:, j])):
            raise case.error(loc, "the load is not finite at some time", shown)
        try:  # evaluates the signal again, inside the steps where it jumps or kinks
            columns.append(step_pairs(wave.values, wave.breaks, spec.dt, steps))
        except ExpressionError as err:
            raise case.error(loc, " ".join(str(err).split()), shown) from None
        if load.amplitude != 0 and not np.any(f[:, j]) and \
                not any(np.any(pair) for pair in columns[-1].values()):
            where = ("analysis", "transient", "loads", j,
                     "start" if hasattr(load, "start") else field)
            raise case.error(where, f"the load is 0 over the whole run (t = 0 to {t[-1]:g}): "
                             f"it never acts", getattr(load, where[-1], shown))
    return f, merge_pairs(columns, f)


def _by_points(case: Case, model: Model, key: str) -> np.ndarray | None:
    r"""The state vector of ``initial.<key>`` given as ``{point: value}``: the minimum-norm
    :math:`q` with :math:`R q = u` (``R`` the points' rows; the coordinates of the points set,
    the others 0)."""
    spec = case.analysis.transient
    assert spec is not None
    values = getattr(spec.initial, key)
    if values is None:
        return None
    R = model.assembly.rows([model.points[p] for p in values])
    u = np.array(list(values.values()), dtype=float)
    G = (R @ R.T).toarray()
    if np.linalg.matrix_rank(G) < len(values):
        raise case.error(("analysis", "transient", "initial", key), "its points are not "
                         "independent coordinates (a point named twice, or points that "
                         "move together)", list(values))
    return np.asarray(R.T @ np.linalg.solve(G, u))


def _from_file(case: Case, n: int) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The arrays ``displacement`` and ``velocity`` of ``initial.file`` (``n`` each)."""
    spec = case.analysis.transient
    assert spec is not None
    name = spec.initial.file
    if name is None:
        return None, None
    path = Path(name) if Path(name).is_absolute() else case.base_dir / name
    loc = ("analysis", "transient", "initial", "file")
    if path.suffix.lower() != ".npz":
        raise case.error(loc, "an initial state file is an .npz file with arrays "
                         "displacement and/or velocity", name)
    try:
        npz_only(path, ("displacement", "velocity"))
    except ValueError as err:
        raise case.error(loc, " ".join(str(err).split()), name) from None
    try:
        d = npz_vector(path, "displacement", n, exact=n)
        v = npz_vector(path, "velocity", n, exact=n)
    except ValueError as err:
        raise case.error(loc, f"{' '.join(str(err).split())} (the model has {n} "
                         f"coordinates)", name) from None
    if d is None and v is None:
        raise case.error(loc, "holds neither an array displacement nor velocity", name)
    for what, x in (("displacement", d), ("velocity", v)):
        if x is not None and not np.all(np.isfinite(x)):
            raise case.error(loc, f"{what} holds values that are not finite", name)
    return d, v


def _initial(case: Case, model: Model) -> tuple[np.ndarray | None, np.ndarray | None]:
    """``(d0, v0)`` of ``analysis.transient.initial`` (``None``: zero, or the static state)."""
    spec = case.analysis.transient
    assert spec is not None
    init = spec.initial
    d_file, v_file = _from_file(case, model.assembly.n_dof)
    loc = ("analysis", "transient", "initial")
    if d_file is not None and (init.mode or init.displacement is not None or init.static):
        raise case.error((*loc, "file"), "the initial displacement is given one way; the file "
                         "holds one too", init.file)
    if v_file is not None and (init.velocity_mode or init.velocity is not None):
        raise case.error((*loc, "file"), "the initial velocity is given one way; the file "
                         "holds one too", init.file)
    d0 = (init.scale * _mode(case, model, init.mode, "mode") if init.mode else
          _by_points(case, model, "displacement") if init.displacement is not None else d_file)
    v0 = (init.velocity_scale * _mode(case, model, init.velocity_mode, "velocity_mode")
          if init.velocity_mode else
          _by_points(case, model, "velocity") if init.velocity is not None else v_file)
    return d0, v0


def _modal(block: TransientModal | None, tasks: TaskRunner | None) -> dict[str, Any]:
    """The modal form's options of ``analysis.transient.modal`` (none if not given); an
    AMLS basis's tree levels run through ``tasks`` (``None``: in this process)."""
    if block is None:
        return {}
    return dict(modal_solver=block.solver, modal_cutoff=block.cutoff,
                modal_residual=block.residual,
                modal_amls=amls_options(block.solver, block.amls, tasks))


def transient_result(case: Case, model: Model, extra: sp.csr_array | None = None,
                     extra_names: list[str] | None = None,
                     field_sink: FieldSink | None = None,
                     tasks: TaskRunner | None = None) -> Transient:
    """The time histories ``case.analysis.transient`` asks for; ``extra`` output rows (named
    ``extra_names``) are recorded after the case's outputs (the recovery of superelements'
    interiors, :mod:`substruct.run.recovery`).  The fields stored every ``field_every`` steps
    go to ``field_sink`` a block at a time as they are recorded, if given (the result file of
    ``substruct run``); else they are kept whole, and refused beyond the memory limit.  The
    tree levels of an AMLS basis (``modal.solver: amls``) run through ``tasks``
    (:class:`~substruct.linalg.task_runner.TaskRunner`; ``None``: in this process).

    Raises:
        CaseError: at ``analysis.transient``, for input the analysis cannot take.
        CheckError: a check disagrees by more than ``analysis.transient.tolerance``.
    """
    spec = case.analysis.transient
    if spec is None:
        raise TypeError(f"case {case.name!r} asks for no transient response")
    asm = model.assembly
    n, steps = asm.n_dof, spec.steps
    if spec.field_every and field_sink is None:
        need = 8.0 * n * (steps // spec.field_every + 1)
        if need > MEMORY_LIMIT:
            raise case.error(("analysis", "transient", "field_every"),
                             f"{n} coordinates every {spec.field_every} steps need about "
                             f"{gigabytes(need)}, more than {gigabytes(MEMORY_LIMIT)}",
                             spec.field_every)
    t = spec.dt * np.arange(steps + 1)
    f, pairs = _loads(case, t, steps)
    B = (sp.csc_array(asm.rows([model.points[ld.point] for ld in spec.loads]).T)
         if spec.loads else sp.csc_array((n, 0)))
    O = (asm.rows([model.points[p] for p in spec.outputs]) if spec.outputs
         else sp.csr_array((0, n)))
    names = list(spec.outputs)
    if extra is not None and extra.shape[0]:
        O = sp.csr_array(sp.vstack([O, extra]))
        names += list(extra_names or [f"recovered {k + 1}" for k in range(extra.shape[0])])
    d0, v0 = _initial(case, model)
    ground = _base(case, model, t)
    try:
        opts = TransientOptions(method=spec.method, checks=spec.check, tolerance=spec.tolerance,
                                integrator=spec.integrator, rho_inf=spec.spectral_radius,
                                every=spec.every, field_every=spec.field_every,
                                forces=spec.constraint_forces, modal_count=spec.modal_count,
                                **_modal(spec.modal, tasks))
        initial = InitialConditions(d0=d0, v0=v0, static=spec.initial.static)
        return transient(asm.M, asm.C, asm.K, asm.A, asm.b,
                         LoadHistory(B, f, spec.dt, steps, pairs=pairs, base=ground),
                         TransientOutputs(O, names, fields=field_sink),
                         constraint_labels=asm.constraint_labels, initial=initial, options=opts)
    except InitialStateError as err:
        raise case.error(("analysis", "transient", "initial"), " ".join(str(err).split())
                         ) from None
    except INPUT_ERRORS as err:  # any other ValueError is a bug: an internal error
        raise case.error(("analysis", "transient"), " ".join(str(err).split())) from None
    except CheckError as err:
        raise CheckError(f"{err}; to accept it, raise analysis.transient.tolerance") from None
