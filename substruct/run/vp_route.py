r"""The analysis route of a case whose FRF substructures have ``virtual_points:``
(:mod:`substruct.case.virtual_points`): each such part is transformed to its virtual points,

.. math::  Y_{qm}(\omega) = T_u\, Y(\omega)\, T_f^T ,

(:mod:`substruct.analysis.frf.virtual_point`), then every part (the finite-element model's
receptance at its joined points, plain FRF parts, transformed parts) is coupled by
:func:`substruct.analysis.frf.vp_coupling.couple_virtual_points`,

.. math::  Y_c = Y - Y B_f^T \, (B_u Y B_f^T)^{\dagger} \, B_u Y ,

with the parts' ``weaken`` components dropped from both :math:`B_u` and :math:`B_f` at their
connections, the ``regularization`` given (the same in every part that gives one) and the
interface reduced to singular vectors by an ``interface:`` block (likewise one per coupling).
Without any of them the result is checked against the generalized-inverse form.  The consistency
indicators of every transformed part are returned with it.
"""

from __future__ import annotations

import re
from typing import Callable

import numpy as np

from substruct.analysis.api import Progress
from substruct.analysis.checks import require_agreement
from substruct.analysis.errors import AnalysisInputError, CheckError
from substruct.analysis.frf.coupling import common_grid
from substruct.analysis.frf.quantity import as_quantity
from substruct.analysis.frf.virtual_point import (VirtualPoint, VptResult, check_measured,
                                                  consistency, virtual_point_transform)
from substruct.analysis.frf.vp_coupling import (Regularisation, VpPart,
                                                couple_virtual_points)
from substruct.analysis.frf.vp_reduction import InterfaceReduction
from substruct.analysis.frf.vp_noise import (MeasuredPart, MonteCarloResult, NoiseStudy,
                                             monte_carlo_coupling)
from substruct.analysis.results import Receptance
from substruct.linalg.task_runner import TaskRunner
from substruct.builder.frf_parts import MODEL_PART, FrfPart, split_frf_case
from substruct.builder.model import Model
from substruct.case.fields import parse_point
from substruct.case.frf_substructure import FrfSpec
from substruct.case.loader import Case
from substruct.case.virtual_points import VP_LABEL_COMPONENTS, VirtualPointsSpec, vp_label
from substruct.run.analyses import frf_result
from substruct.run.frf_route import ANALYSIS_GRID
from substruct.vocabulary import GENERALIZED_INVERSE

__all__ = ["has_virtual_points", "vp_frf_result", "transformed_part", "measured_part"]

_LIBRARY = dict(zip(("x", "y", "z", "rx", "ry", "rz"), VP_LABEL_COMPONENTS))


def has_virtual_points(case: Case) -> bool:
    """Whether an FRF substructure of the case has ``virtual_points:``."""
    return any(isinstance(s, FrfSpec) and s.virtual_points is not None
               for s in case.substructures)


def _relabel(label: str, points: set[str]) -> str:
    """A library label (``J:x``, ``J:e1``, a channel name) as a case-file label."""
    name, sep, comp = label.rpartition(":")
    if sep and name in points:
        return vp_label(name, _LIBRARY.get(comp, comp))
    return f"ch:{label}"


def transformed_part(case: Case, k: int, vps: VirtualPointsSpec, part: FrfPart
                     ) -> tuple[VpPart, VptResult]:
    """The measured part ``part`` (substructure ``k``, on the analysis grid) transformed to its
    virtual points, and its consistency indicators.

    Raises:
        CaseError: as :func:`measured_part`.
    """
    m = measured_part(case, k, vps, part)
    vp = m.part(m.Y)
    assert m.vpt is not None
    return vp, consistency(m.vpt, m.Y)


def measured_part(case: Case, k: int, vps: VirtualPointsSpec, part: FrfPart) -> MeasuredPart:
    """The measured part ``part`` (substructure ``k``, on the analysis grid): its receptances
    at the sensors x impacts and its virtual point transformation, labelled as in the case.

    Raises:
        CaseError: a virtual point whose motions are unobservable or that has fewer channels
            than coordinates; measured receptances that are not finite.
    """
    table = vps.table()
    sensors = [c.name for c in table.of_kind("sensor")]
    impacts = [c.name for c in table.of_kind("impact")]
    rows = {lab: i for i, lab in enumerate(part.labels)}
    cols = {lab: i for i, lab in enumerate(part.columns())}
    Y = part.Y[:, [rows[s] for s in sensors]][:, :, [cols[h] for h in impacts]]
    points = []
    for p in vps.points:
        ex, wt = p.extra_modes, p.weights
        points.append(VirtualPoint(
            p.name, p.position, tuple(p.sensors), tuple(p.impacts),
            None if ex is None else np.asarray(ex.sensors, dtype=float),
            None if ex is None else np.asarray(ex.impacts, dtype=float),
            None if wt is None else np.asarray(wt.sensors, dtype=float),
            None if wt is None else np.asarray(wt.impacts, dtype=float)))
    loc: tuple[str | int, ...] = ("substructures", k, "virtual_points")
    try:
        vpt = virtual_point_transform(table, points, sensors, impacts)
    except ValueError as err:
        m = re.match(r"virtual point (\S+) \((sensor|impact)s\)", str(err))
        names = [p.name for p in vps.points]
        if m and m.group(1) in names:
            i = names.index(m.group(1))
            raise case.error((*loc, "points", i, f"{m.group(2)}s"), str(err),
                             getattr(vps.points[i], f"{m.group(2)}s")) from None
        raise case.error(loc, str(err)) from None
    try:
        check_measured(Y, sensors, impacts)
    except ValueError as err:
        raise case.error(("substructures", k, "file"), str(err)) from None
    names_set = {p.name for p in vps.points}
    return MeasuredPart(part.name, part.omega, Y, vpt,
                        tuple(_relabel(x, names_set) for x in vpt.out_labels),
                        tuple(_relabel(x, names_set) for x in vpt.in_labels))


def _regularisation(case: Case) -> tuple[Regularisation, float]:
    """The one regularisation the parts ask for (none if none does)."""
    chosen: tuple[Regularisation, float] | None = None
    first = ""
    for k, s in enumerate(case.substructures):
        if not isinstance(s, FrfSpec) or s.virtual_points is None:
            continue
        r = s.virtual_points.regularization
        if r is None:
            continue
        reg = Regularisation(r.method, rtol=1e-12 if r.rtol is None else r.rtol, rank=r.rank,
                             alpha=0.0 if r.alpha is None else r.alpha)
        if chosen is not None and chosen != (reg, r.length):
            raise case.error(("substructures", k, "virtual_points", "regularization"),
                             f"differs from that of {first}: the coupling has one "
                             f"regularization", r.method)
        chosen, first = (reg, r.length), s.name
    return chosen if chosen is not None else (Regularisation(), 1.0)


def _reduction(case: Case, reg_length: float | None
               ) -> tuple[InterfaceReduction | None, float | None]:
    """The one interface reduction the parts ask for and its length (``None`` if none does);
    refused when parts differ or its length is not that of the regularization."""
    chosen: tuple[InterfaceReduction, float] | None = None
    first = ""
    for k, s in enumerate(case.substructures):
        if not isinstance(s, FrfSpec) or s.virtual_points is None:
            continue
        r = s.virtual_points.interface
        if r is None:
            continue
        loc = ("substructures", k, "virtual_points", "interface")
        red = InterfaceReduction(keep=r.keep, tolerance=r.tolerance)
        if chosen is not None and chosen != (red, r.length):
            raise case.error(loc, f"differs from that of {first}: the coupling has one "
                             f"interface reduction", r.reduction)
        if reg_length is not None and r.length != reg_length:
            raise case.error((*loc, "length"), f"differs from the regularization's length "
                             f"{reg_length!r}: the coupling scales its rotations once",
                             r.length)
        chosen, first = (red, r.length), s.name
    return (None, None) if chosen is None else chosen


def _keep_at_most(case: Case, reduction: InterfaceReduction | None, rows: int) -> None:
    """Refuse a ``keep`` above the number of interface rows."""
    if reduction is None or reduction.keep is None or reduction.keep <= rows:
        return
    for k, s in enumerate(case.substructures):
        if isinstance(s, FrfSpec) and s.virtual_points is not None and \
                s.virtual_points.interface is not None:
            raise case.error(("substructures", k, "virtual_points", "interface", "keep"),
                             f"more singular vectors than the {rows} interface rows of the "
                             f"coupling", reduction.keep)


def vp_frf_result(case: Case, model: Model, progress: Progress | None = None,
                  tasks: TaskRunner | None = None
                  ) -> tuple[Receptance, dict[str, VptResult], MonteCarloResult | None]:
    """The receptances ``case.analysis.frf`` asks for, of the parts coupled at their virtual
    points (module docstring), the consistency indicators per transformed part, and the
    Monte Carlo study of a ``monte_carlo:`` block (``None`` without one; its samples run
    through ``tasks``, in process by default, as do the tree levels of the model's AMLS
    basis, ``modal.solver: amls``).

    Raises:
        CaseError: as :func:`transformed_part`; an output that is not measured as an output
            (an impact passing through) or an input that is not one; a connection at a
            channel passing through; every interface row weakened; a singular interface.
        CheckError: the generalized-inverse form disagrees beyond ``analysis.frf.tolerance``.
    """
    spec = case.analysis.frf
    if spec is None:
        raise TypeError(f"case {case.name!r} asks for no receptances")
    split = split_frf_case(case)
    checks: dict[str, float] = {}
    if split.model_case is None:
        w0 = spec.omegas()
        first = FrfPart(ANALYSIS_GRID, w0, [], np.zeros((len(w0), 0, 0), dtype=complex))
    else:
        fe = frf_result(split.model_case, model, progress, tasks=tasks)
        first = FrfPart(MODEL_PART, fe.omega, list(split.model_points), fe.H)
        checks.update({f"{MODEL_PART} {k}": v for k, v in fe.agreement.items()})
    w, same = common_grid([first, *split.parts])
    index = {s.name: k for k, s in enumerate(case.substructures)}
    parts: list[VpPart] = []
    if split.model_case is not None:
        parts.append(VpPart(MODEL_PART, w, first.labels, first.labels, same[0].Y))
    indicators: dict[str, VptResult] = {}
    measured: list[MeasuredPart] = []
    if split.model_case is not None:
        measured.append(MeasuredPart(MODEL_PART, w, same[0].Y, None, tuple(first.labels),
                                     tuple(first.labels), noisy=False))
    weaken: dict[str, list[str]] = {}
    for part in same[1:]:
        k = index[part.name]
        s = case.substructures[k]
        assert isinstance(s, FrfSpec)
        if s.virtual_points is None:
            parts.append(VpPart(part.name, w, part.labels, part.labels, part.Y))
            measured.append(MeasuredPart(part.name, w, part.Y, None, tuple(part.labels),
                                         tuple(part.labels)))
            continue
        m = measured_part(case, k, s.virtual_points, part)
        assert m.vpt is not None
        measured.append(m)
        parts.append(m.part(m.Y))
        indicators[part.name] = consistency(m.vpt, m.Y)
        weaken[part.name] = list(s.virtual_points.weaken)
    frf_names = {p.name for p in split.parts}

    def stacked(point: str) -> str:
        return point if parse_point(point)[0] in frf_names else f"{MODEL_PART}@{point}"

    for i, chain in enumerate(case.connections):
        for j, point in enumerate(chain):
            sub, where = parse_point(point)
            if sub in indicators and (where or "").startswith("ch:"):
                raise case.error(("connections", i, j), "a channel that passes through is "
                                 "measured one way only: join the part at a virtual-point "
                                 "coordinate (vp:<point>:<ux|uy|uz|rx|ry|rz>)", point)
    pairs = [(stacked(a), stacked(b)) for a, b in split.pairs]
    drop = [a for a, b in pairs for side in (a, b)
            if side.rsplit(":", 1)[-1] in weaken.get(parse_point(side)[0], [])]
    reg, length = _regularisation(case)
    has_reg = any(isinstance(s, FrfSpec) and s.virtual_points is not None
                  and s.virtual_points.regularization is not None for s in case.substructures)
    reduction, red_length = _reduction(case, length if has_reg else None)
    length = red_length if red_length is not None else length
    _keep_at_most(case, reduction, sum(1 for a, _ in pairs if a not in drop))
    try:
        res = couple_virtual_points(parts, pairs, reg, drop, drop, "coupled", length,
                                    reduction=reduction)
    except AnalysisInputError as err:
        raise case.error(("connections",), f"the interface receptance is singular ({err}): "
                         "connections that repeat each other, or a joint the channels do not "
                         "observe", [list(p) for p in split.pairs]) from None
    except ValueError as err:
        raise case.error(("connections",), str(err), [list(p) for p in split.pairs]) from None
    Yc = res.part
    outs: list[int] = []
    ins: list[int] = []
    for key, points, labels, acc, what in (
            ("outputs", spec.outputs, Yc.out_labels, outs, "an output (a sensor or a joint)"),
            ("inputs", spec.inputs, Yc.in_labels, ins, "an input (an impact or a joint)")):
        for i, p in enumerate(points):
            if stacked(p) not in labels:
                raise case.error(("analysis", "frf", key, i), f"not measured as {what}", p)
            acc.append(labels.index(stacked(p)))
    H = Yc.Y[:, outs][:, :, ins]
    kept = [(a, b) for a, b in pairs if a not in drop]
    scale = max(float(np.abs(Yc.Y).max(initial=0.0)), 1e-300)
    residual = max((float(np.abs(Yc.Y[:, Yc.out_labels.index(a)]
                                 - Yc.Y[:, Yc.out_labels.index(b)]).max()) / scale
                    for a, b in kept), default=0.0)
    if np.isfinite(res.agreement):
        checks = {GENERALIZED_INVERSE: res.agreement, **checks}
        try:
            require_agreement("frf (lm-fbs at virtual points)", "lm-fbs",
                              {GENERALIZED_INVERSE: res.agreement}, spec.tolerance)
        except CheckError as err:
            raise CheckError(f"{err}; to accept it, raise analysis.frf.tolerance") from None
    how = "lm-fbs at virtual points" + (f" ({reg.kind})" if reg.kind != "none" else "") + \
        (" (weakened)" if drop else "") + (" (svd-reduced interface)" if reduction else "")
    coupled = Receptance(method=how, omega=w, H=H, inputs=list(spec.inputs),
                         outputs=list(spec.outputs), agreement=checks,
                         constraint_residual=residual, tolerance=spec.tolerance)
    mc = _monte_carlo(case, measured, pairs, drop, reg, length, stacked, tasks, reduction)
    return as_quantity(coupled, spec.quantity), indicators, mc


def _monte_carlo(case: Case, measured: list[MeasuredPart], pairs: list[tuple[str, str]],
                 drop: list[str], reg: Regularisation, length: float,
                 stacked: Callable[[str], str], tasks: TaskRunner | None,
                 reduction: InterfaceReduction | None = None) -> MonteCarloResult | None:
    """The study of the one ``monte_carlo:`` block of the case (refused in a second part)."""
    found = [(k, s) for k, s in enumerate(case.substructures) if isinstance(s, FrfSpec)
             and s.virtual_points is not None and s.virtual_points.monte_carlo is not None]
    if not found:
        return None
    if len(found) > 1:
        k = found[1][0]
        raise case.error(("substructures", k, "virtual_points", "monte_carlo"),
                         f"one Monte Carlo study per case (it perturbs every measured part); "
                         f"{found[0][1].name} gives one already", found[1][1].name)
    k, s = found[0]
    assert s.virtual_points is not None and s.virtual_points.monte_carlo is not None
    mc = s.virtual_points.monte_carlo
    spec = case.analysis.frf
    assert spec is not None
    loc = ("substructures", k, "virtual_points", "monte_carlo")
    nominal = couple_virtual_points([m.part(m.Y) for m in measured], pairs, reg, drop, drop,
                                    "coupled", length, check=False,
                                    reduction=reduction).part
    picked = []
    for key, given, labels in (("outputs", mc.outputs or spec.outputs, nominal.out_labels),
                               ("inputs", mc.inputs or spec.inputs, nominal.in_labels)):
        for i, p in enumerate(given):
            if stacked(p) not in labels:
                raise case.error((*loc, key, i), f"not one of the coupled {key}", p)
        picked.append(list(given))
    study = NoiseStudy(tuple(measured), tuple(pairs), tuple(stacked(p) for p in picked[0]),
                       tuple(stacked(p) for p in picked[1]), mc.level, reg, tuple(drop),
                       tuple(drop), length, reduction)
    res = monte_carlo_coupling(study, mc.samples, mc.seed, mc.percentiles,
                               map=None if tasks is None else tasks.map)
    return MonteCarloResult(res.omega, picked[0], picked[1], res.level, res.samples, res.seed,
                            res.nominal, res.mean, res.std, res.percentiles, res.bands)
