r"""``analysis.transient`` of a case on its model: a thin adapter to
:func:`substruct.analysis.transient.transient` (eqs 5, 10).

A force at point ``p`` is the generalized force :math:`r(p)^T f(t)`; an output is
:math:`r(p)\, q(t)`.  A ground motion at point ``p`` moves the constraint rows that hold ``p``
alone, :math:`A_i = c\, r(p)` (:mod:`substruct.analysis.transient_base`).  Input the analysis cannot take becomes a
:class:`~substruct.case.loader.CaseError` at ``analysis.transient`` (exit 2); a check beyond
the tolerance stays a :class:`~substruct.analysis.errors.CheckError` (exit 1).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from substruct.analysis.api import modes
from substruct.analysis.errors import CheckError
from substruct.analysis.transient import TransientOptions, transient
from substruct.analysis.transient_base import BaseMotion
from substruct.analysis.transient_results import Transient
from substruct.builder.model import Model
from substruct.case.fields import MEMORY_LIMIT, gigabytes
from substruct.case.loader import Case
from substruct.case.transient import load_values

__all__ = ["transient_result"]


def _mode(case: Case, model: Model, k: int, field: str) -> np.ndarray:
    """Coupled mode ``k`` (1-based, M-normalized, real)."""
    asm = model.assembly
    if k > asm.n_dof:
        raise case.error(("analysis", "transient", "initial", field),
                         f"more than the {asm.n_dof} coordinates", k)
    md = modes(asm.M, None, asm.K, asm.A, k, what="transient (initial mode)")
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
    try:
        values = load_values(sig, t, case.base_dir, params)
        rate0 = accel0 = 0.0
        if kind == "displacement":  # g'(0), g''(0): one-sided differences of the signal
            d = max(1e-3 * float(t[1] - t[0]), 1e-12)
            g0, g1, g2 = load_values(sig, np.array([0.0, d, 2 * d]), case.base_dir, params)
            rate0, accel0 = (-3 * g0 + 4 * g1 - g2) / (2 * d), (g0 - 2 * g1 + g2) / d ** 2
    except ValueError as err:
        field = "table" if sig.shape == "table" else "expression"
        raise case.error(("analysis", "transient", "base", kind, field),
                         " ".join(str(err).split()), sig.table or sig.expression) from None
    return BaseMotion(rows=_grounding_rows(case, model), kind=kind, values=values,
                      rate0=float(rate0), accel0=float(accel0))


def transient_result(case: Case, model: Model) -> Transient:
    """The time histories ``case.analysis.transient`` asks for.

    Raises:
        CaseError: at ``analysis.transient``, for input the analysis cannot take.
        CheckError: a check disagrees by more than ``analysis.transient.tolerance``.
    """
    spec = case.analysis.transient
    if spec is None:
        raise TypeError(f"case {case.name!r} asks for no transient response")
    asm = model.assembly
    n, steps = asm.n_dof, spec.steps
    if spec.field_every:
        need = 8.0 * n * (steps // spec.field_every + 1)
        if need > MEMORY_LIMIT:
            raise case.error(("analysis", "transient", "field_every"),
                             f"{n} coordinates every {spec.field_every} steps need about "
                             f"{gigabytes(need)}, more than {gigabytes(MEMORY_LIMIT)}",
                             spec.field_every)
    t = spec.dt * np.arange(steps + 1)
    base = case.base_dir
    f = np.zeros((steps + 1, len(spec.loads)))
    for j, load in enumerate(spec.loads):
        try:
            f[:, j] = load_values(load, t, base, dict(case.parameters))
        except ValueError as err:
            field = "table" if load.shape == "table" else "expression"
            raise case.error(("analysis", "transient", "loads", j, field),
                             " ".join(str(err).split()), load.table or load.expression) from None
    B = (sp.csc_array(asm.rows([model.points[ld.point] for ld in spec.loads]).T)
         if spec.loads else sp.csc_array((n, 0)))
    O = (asm.rows([model.points[p] for p in spec.outputs]) if spec.outputs
         else sp.csr_array((0, n)))
    init = spec.initial
    d0 = init.scale * _mode(case, model, init.mode, "mode") if init.mode else None
    v0 = (init.velocity_scale * _mode(case, model, init.velocity_mode, "velocity_mode")
          if init.velocity_mode else None)
    opts = TransientOptions(integrator=spec.integrator, rho_inf=spec.rho_inf, every=spec.every,
                            field_every=spec.field_every, forces=spec.constraint_forces,
                            modal_count=spec.modal_count)
    ground = _base(case, model, t)
    try:
        return transient(asm.M, asm.C, asm.K, asm.A, asm.b, B, f, spec.dt, steps, O,
                         output_names=spec.outputs, constraint_labels=asm.constraint_labels,
                         d0=d0, v0=v0, method=spec.method, checks=spec.check,
                         tolerance=spec.tolerance, options=opts, base=ground)
    except ValueError as err:
        raise case.error(("analysis", "transient"), " ".join(str(err).split())) from None
    except CheckError as err:
        raise CheckError(f"{err}; to accept it, raise analysis.transient.tolerance") from None
