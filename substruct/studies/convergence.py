r"""Convergence study of a constrained rod: assumed modes vs finite elements, side by side.

A rod (any length, :math:`EA(x)`, :math:`m(x)`, supports) carries spring-mass attachments and
extra linear constraints on its points (a :class:`~substruct.builder.rod_system.RodSystemSpec`).
The same system is discretized by

* ``assumed``: the uniform-rod eigenfunctions (eq 51) with ``g = n`` (no modal reduction);
* ``assumed-g<g>``: the same basis reduced to a fixed number ``g`` of rod modes (eqs 21-22), the
  paper's way (``g = 4``): it converges to the *truncated* model, not to the rod;
* ``enriched``: the sines plus static shapes of unit loads at the attachment and constraint
  points (:func:`substruct.models.enrichment.rod_assumed_modes_enriched`);
* ``fe-p1``, ``fe-p2``: Lagrange finite elements with nodes at those points
  (:func:`substruct.models.rod.rod_fe`),

at increasing size, and the lowest ``n_modes`` roots of each are compared with a limit.

**Limit.**  The finest ``fe-p2`` level (``fe-p1`` if there is none), and its Richardson estimate
from the two finest levels with the theoretical eigenvalue order :math:`2p` of elements of
degree :math:`p`:

.. math::  \lambda_R = \lambda_f + \frac{\lambda_f - \lambda_c}{r^{2p} - 1}, \qquad
           r = \frac{n^{el}_f}{n^{el}_c}.

Both are reported with their difference :math:`\delta_j = |\lambda_{R,j} - \lambda_{f,j}| /
|\lambda_{R,j}|`, the uncertainty of the limit.  Errors are measured against :math:`\lambda_R`
(or the finest level, ``reference="finest"``).

**Errors and rates.**  For each level and mode, the relative error of the root
:math:`e_j = |\lambda_j - \lambda_{ref,j}| / |\lambda_{ref,j}|` (for undamped systems
:math:`\lambda = i\omega`, so this is the relative error of the natural frequency; the relative
error of :math:`\omega^2` is twice it, at the same rate).  The observed order :math:`p_j` is the
fitted slope :math:`e_j \approx C\, N^{-p_j}` over the ``fit_points`` finest levels whose error
lies above the floor :math:`\max(\text{error\_floor}, 10\,\delta_j)` (below it the error is not
resolved), with ``N`` the number of Ritz functions or FE degrees of freedom of the rod
(before any modal reduction):

.. math::  \log e_j = \log C - p_j \log N \quad \text{(least squares)}.

Expected: P1 :math:`p = 2`, P2 :math:`p = 4` (eigenvalue error :math:`O(h^{2p})`; ``N ~ 1/h``);
the plain sines first order once point forces put slope jumps into the modes (the sine series of
a kink has coefficients :math:`\sim i^{-2}`, energy error :math:`\sim n^{-1/2}`, eigenvalue
error :math:`\sim n^{-1}`); the enriched basis represents the kinks exactly and converges at a
high algebraic rate.

**Solving.**  Each level is built by the builder
(:func:`substruct.builder.rod_system.rod_model`, assembled by
:meth:`~substruct.builder.rod_system.RodSystemSpec.assemble`) and its roots come from the one
analysis entry point, :func:`substruct.analysis.api.modes`, in the null-space form
:math:`u = T p`, :math:`A T = 0` (:func:`lowest_modes`): dense up to ``dense_limit``
coordinates, above it shift-invert Lanczos (undamped) or Arnoldi (damped) with the inverse
applied by a sparse factorization of the factorization registry, never one that ARPACK makes
for itself (docs/performance.md, "The factorization: measured, and the default").

**Elsewhere.**  The system and its rod at each level: :mod:`substruct.builder.rod_system`; a
system from a case file: :mod:`substruct.builder.rod_system_case`; the levels:
:mod:`substruct.studies.levels`; rates and Richardson limits: :mod:`substruct.studies.rates`;
the results: :mod:`substruct.studies.convergence_results`; the table, the HDF5 file and the plot:
:mod:`substruct.io.convergence_report`; the command ``substruct converge``: :mod:`substruct.cli`.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import numpy as np

from substruct.analysis.api import Progress, modes
from substruct.builder import Assembly, Substructure
from substruct.builder.rod_system import RodSystemSpec, reduced_rod, rod_model
from substruct.studies.convergence_results import (
    ConvergenceResult,
    SeriesResult,
    VariantResult,
)
from substruct.studies.levels import StudyLevels
from substruct.studies.rates import fit_order, observed_order, richardson

__all__ = [
    "VARIANTS",
    "lowest_modes",
    "study_variants",
    "convergence_study",
    "dofs_to_reach",
]

#: The versions of the system a study can run (see :func:`study_variants`).
VARIANTS = ("constrained", "unconstrained", "bare")

# -------------------------------------------------------------------------------- solving


def lowest_modes(asm: Assembly, n_modes: int, *, dense_limit: int = 400) -> np.ndarray:
    r"""The ``n_modes`` lowest roots of an assembled constrained system.

    .. math::  (\lambda^2 T^T M T + \lambda T^T C T + T^T K T)\, p = 0, \qquad A T = 0

    by :func:`substruct.analysis.api.modes` with the null-space formulation and no checks: the
    dense strategy up to ``dense_limit`` coordinates, the sparse one (shift-invert Lanczos,
    undamped; Arnoldi on the first companion form, damped) above it.

    Args:
        asm: the assembled system (homogeneous constraints).
        n_modes: number of roots wanted.
        dense_limit: largest number of coordinates solved densely.

    Returns:
        Complex roots ``(n_modes,)`` with ``Im >= 0`` (one of each conjugate pair; ``i omega`` if
        undamped), ascending in modulus, NaN-padded if the system has fewer.
    """
    out = np.full(n_modes, np.nan + 0j)
    solver = "dense" if asm.n_dof <= dense_limit else "sparse"
    found = modes(asm.M, asm.C, asm.K, asm.A, n_modes, method="null-space", solver=solver)
    out[:len(found)] = found.eigenvalues
    return out

# --------------------------------------------------------------------------------- study


@dataclass(frozen=True)
class _Method:
    key: str
    label: str
    levels: tuple[int, ...]
    theory: float
    build: Callable[[int], tuple[Substructure, float]]  # the rod and the seconds to charge


class _Rods:
    """Rod models built once per study: the plain sines serve both assumed-modes series, and
    the variants with the same points share every model.  A reused model is charged the time it
    took to build, so each level's cost reads as if it had been built for it."""

    def __init__(self) -> None:
        self._built: dict[tuple[Any, ...], tuple[Substructure, float]] = {}

    def get(self, key: tuple[Any, ...], make: Callable[[], Substructure]
            ) -> tuple[Substructure, float]:
        """``(model, seconds to charge)``: 0 if built now (the caller times it), else the time
        the first build took."""
        if key in self._built:
            return self._built[key]
        t = time.perf_counter()
        rod = make()
        self._built[key] = (rod, time.perf_counter() - t)
        return rod, 0.0


def _methods(spec: RodSystemSpec, levels: StudyLevels, smooth: bool,
             rods: _Rods | None = None) -> list[_Method]:
    """The series of a study, each building its rod through
    :func:`substruct.builder.rod_system.rod_model` (a model shared by key: the
    discretization, the level and the points, which are all that the rod depends on within one
    study)."""
    pts = spec.points
    rods = rods or _Rods()

    def made(discretization: str) -> Callable[[int], tuple[Substructure, float]]:
        return lambda n: rods.get((discretization, n, pts),
                                  lambda: rod_model(spec, discretization, n))

    def truncated(n: int, g: int) -> tuple[Substructure, float]:
        rod, charge = made("sines")(n)
        return reduced_rod(rod, g), charge

    out = [_Method("assumed", "assumed modes (g = n)", tuple(levels.assumed),
                   np.nan if smooth else 1.0, made("sines"))]
    g = levels.fixed_g
    if g is not None:
        out.append(_Method(f"assumed-g{g}", f"assumed modes (g = {g})",
                           tuple(n for n in levels.assumed if n >= g), np.nan,
                           lambda n: truncated(n, g)))
    if pts:
        out.append(_Method("enriched", "enriched assumed modes", tuple(levels.enriched), np.nan,
                           made("enriched")))
    out.append(_Method("fe-p1", "FE P1", tuple(levels.fe_p1), 2.0, made("fe-p1")))
    out.append(_Method("fe-p2", "FE P2", tuple(levels.fe_p2), 4.0, made("fe-p2")))
    return [mt for mt in out if mt.levels]


def _run_variant(key: str, label: str, spec: RodSystemSpec, levels: StudyLevels,
                 reference: str, fit_points: int, error_floor: float,
                 tick: Callable[[str], None], rods: _Rods) -> VariantResult:
    t0 = time.perf_counter()
    smooth = not spec.points
    k = spec.n_modes
    raw: dict[str, dict[str, Any]] = {}
    for mt in _methods(spec, levels, smooth, rods):
        rec: dict[str, list[Any]] = {"level": [], "dofs": [], "coupled": [], "sec": [],
                                     "lam": [], "n_el": []}
        for n in mt.levels:
            t = time.perf_counter()
            rod, charge = mt.build(n)
            asm = spec.assemble(rod)
            lam = lowest_modes(asm, k)
            rec["sec"].append(time.perf_counter() - t + charge)
            rec["level"].append(n)
            rec["dofs"].append(int(rod.meta.get("reduced_from", rod.n_dof)))
            rec["coupled"].append(asm.n_dof)
            rec["lam"].append(lam)
            rec["n_el"].append(int(rod.meta.get("n_elements", n)))
            tick(f"{label}: {mt.label} {n}")
        raw[mt.key] = {"method": mt, **{f: np.array(v) for f, v in rec.items()}}

    ref_key = "fe-p2" if "fe-p2" in raw else "fe-p1" if "fe-p1" in raw else None
    nan = np.full(k, np.nan + 0j)
    if ref_key is None:
        finest, rich, source, ref_order = nan, nan, "none", np.full(k, np.nan)
    else:
        r = raw[ref_key]
        order = 2.0 * (2 if ref_key == "fe-p2" else 1)
        finest = r["lam"][-1]
        source = f"{ref_key} n_el={r['n_el'][-1]}"
        if len(r["lam"]) >= 2:
            ratio = r["n_el"][-1] / r["n_el"][-2]
            rich = richardson(r["lam"][-1], r["lam"][-2], ratio, order)
            source += f" (Richardson with n_el={r['n_el'][-2]}, order {order:g})"
        else:
            rich = nan
        ref_order = observed_order(r["lam"], r["n_el"], 10 * error_floor)
    use_rich = reference == "richardson" and np.all(np.isfinite(rich))
    limit = rich if use_rich else finest
    with np.errstate(divide="ignore", invalid="ignore"):
        diff = abs(rich - finest) / abs(limit)
    amax = np.nanmax(abs(limit)) if np.any(np.isfinite(limit)) else np.nan
    rigid = abs(limit) <= 1e-6 * amax
    diff[rigid] = np.nan
    floor = np.maximum(error_floor, 10 * np.nan_to_num(diff, nan=0.0))

    series: dict[str, SeriesResult] = {}
    for skey, r in raw.items():
        mt = r["method"]
        lam = r["lam"].reshape(len(r["level"]), k)
        with np.errstate(divide="ignore", invalid="ignore"):
            err = abs(lam - limit[None, :]) / abs(limit)[None, :]
        err[np.isnan(lam)] = np.inf  # a root this level does not have
        err[:, rigid] = np.nan
        rates, masks, extra = np.full(k, np.nan), np.zeros(err.shape, bool), np.full(k, np.nan)
        for j in range(k):
            rates[j], masks[:, j] = fit_order(r["dofs"].astype(float), err[:, j], floor[j],
                                         fit_points)
            if np.isfinite(rates[j]) and rates[j] >= 0.5 and lam.shape[0] >= 2 \
                    and np.all(np.isfinite(lam[-2:, j])):
                ext = richardson(lam[-1, j], lam[-2, j], r["dofs"][-1] / r["dofs"][-2],
                                  rates[j])
                extra[j] = abs(ext - limit[j]) / abs(limit[j])
        series[skey] = SeriesResult(
            key=skey, label=mt.label, level=r["level"], dofs=r["dofs"],
            coupled_dofs=r["coupled"], seconds=r["sec"], eigenvalues=lam, rel_error=err,
            rate=rates, fit_mask=masks, theory_rate=mt.theory, extrapolated_difference=extra)
    return VariantResult(key=key, label=label, series=series, limit_finest=finest,
                         limit_richardson=rich, limit=limit, limit_difference=diff,
                         limit_source=source, reference_order=ref_order, floor=floor,
                         seconds=time.perf_counter() - t0)


def study_variants(spec: RodSystemSpec, which: Sequence[str] = VARIANTS
                   ) -> list[tuple[str, str, RodSystemSpec]]:
    """The versions of ``spec`` a study runs, as ``(key, label, spec)``, in the order asked.

    ``"constrained"``: ``spec`` as given (skipped if it has no extra constraints: it would
    repeat ``"unconstrained"``); ``"unconstrained"``: without its extra constraints (skipped
    when it is the bare rod and ``"bare"`` is asked too); ``"bare"``: the rod alone.  Repeated
    keys count once.

    Raises:
        ValueError: a key that is not one of :data:`VARIANTS`.
    """
    names = spec.constraint_names()
    out: list[tuple[str, str, RodSystemSpec]] = []
    for v in dict.fromkeys(which):
        if v == "constrained":
            if spec.constraints:
                out.append((v, f"with {names}", spec))
        elif v == "unconstrained":
            label = f"without {names}" if spec.constraints else "as given"
            if spec.attachments or spec.constraints or "bare" not in which:
                out.append((v, label, dataclasses.replace(spec, constraints=())))
        elif v == "bare":
            out.append((v, "bare rod (no attachments, no constraints)",
                        dataclasses.replace(spec, attachments=(), constraints=())))
        else:
            raise ValueError(f"unknown variant {v!r}; expected one of {', '.join(VARIANTS)}")
    return out


def convergence_study(spec: RodSystemSpec, levels: StudyLevels | None = None, *,
                      variants: Sequence[str] = VARIANTS,
                      reference: str = "richardson", fit_points: int = 3,
                      error_floor: float = 1e-10,
                      progress: Progress | None = None) -> ConvergenceResult:
    r"""Refine every discretization of ``spec`` and measure errors and rates (module docstring).

    For each variant (``"constrained"``: ``spec`` as given; ``"unconstrained"``: without its
    extra constraints; ``"bare"``: the rod alone, smooth modes) and each series of ``levels``,
    build the rod, assemble it with the attachments and constraints, take the ``spec.n_modes``
    lowest roots (:func:`lowest_modes`), then

    .. math::  e_{lj} = \frac{|\lambda_{lj} - \lambda_{ref,j}|}{|\lambda_{ref,j}|}, \qquad
               \log e_{lj} \approx \log C_j - p_j \log N_l .

    Args:
        spec: the system.
        levels: sizes of the series (default :class:`StudyLevels`).
        variants: which versions to run (a variant identical to another is skipped).
        reference: ``"richardson"`` or ``"finest"`` (the limit errors are measured against).
        fit_points: levels in each rate fit (the finest ones above the floor; a mode with fewer
            such levels gets no rate).
        error_floor: errors below this are not used in fits: the roots themselves carry
            round-off of about ``1e-12`` relative (varying between runs), so errors near it have
            no rate in them.
        progress: called as ``progress(done, total, description)`` after each level.

    Returns:
        A :class:`ConvergenceResult`.
    """
    if reference not in ("richardson", "finest"):
        raise ValueError(f"reference must be 'richardson' or 'finest', got {reference!r}")
    levels = levels or StudyLevels()
    todo = study_variants(spec, variants)
    total = sum(len(mt.levels) for _, _, s in todo
                for mt in _methods(s, levels, not s.points))
    done = 0

    def tick(what: str) -> None:
        nonlocal done
        done += 1
        if progress is not None:
            progress(done, total, what)

    t0 = time.perf_counter()
    rods = _Rods()
    out = {key: _run_variant(key, label, s, levels, reference, fit_points, error_floor, tick,
                             rods)
           for key, label, s in todo}
    return ConvergenceResult(
        name=spec.name, n_modes=spec.n_modes, variants=out,
        levels=dataclasses.asdict(levels), seconds=time.perf_counter() - t0,
        attrs={"reference": reference, "fit_points": fit_points, "error_floor": error_floor,
               "support": spec.support, "length": float(spec.length),
               "points": list(spec.points), "damped": spec.damped})


def dofs_to_reach(series: SeriesResult, tol: float) -> int | None:
    """Fewest rod DOFs from which the worst error over the modes stays ``<= tol``.

    ``None`` if the finest level does not reach it.
    """
    worst = series.worst_error
    ok = np.isfinite(worst) & (worst <= tol)
    if not ok.size or not ok[-1]:
        return None
    first = ok.size - int(np.argmin(ok[::-1])) if not ok.all() else 0
    return int(series.dofs[first])
