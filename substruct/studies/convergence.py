r"""Convergence study of a constrained rod: assumed modes vs finite elements, side by side.

A rod (any length, :math:`EA(x)`, :math:`m(x)`, supports) carries spring-mass attachments and
extra linear constraints on its points (a :class:`RodSystemSpec`).  The same system is discretized
by

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

**Solving.**  Each level is assembled (:func:`substruct.assembly.stack.assemble`) and its roots come
from the null-space form :math:`u = Z p`, :math:`A Z = 0` (:func:`lowest_modes`): ``Z`` sparse
(identity on all but ``rank(A)`` eliminated coordinates), then a dense symmetric solve for small
or dense models and shift-invert Lanczos with a SuperLU factorization for large sparse ones
(DESIGN.md section 6).  Damped systems go through the first companion form.

**Elsewhere.**  The table, the HDF5 file and the plot: :mod:`substruct.studies.convergence_report`;
a :class:`RodSystemSpec` from a case file: :mod:`substruct.studies.convergence_case`; the command
``substruct converge``: :mod:`substruct.cli`.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from substruct.assembly.stack import (
    Assembly,
    Connection,
    LinearConstraint,
    PointRef,
    assemble,
)
from substruct.models.discrete import fixed_free, free_free
from substruct.models.enrichment import rod_assumed_modes_enriched
from substruct.models.reduction import modal_truncation
from substruct.models.rod import Profile, paper_taper, rod_assumed_modes, rod_fe
from substruct.substructure import Substructure

__all__ = [
    "Attachment",
    "PointConstraint",
    "RodSystemSpec",
    "paper_rod_spec",
    "StudyLevels",
    "parse_levels",
    "SeriesResult",
    "VariantResult",
    "ConvergenceResult",
    "lowest_modes",
    "VARIANTS",
    "study_variants",
    "convergence_study",
    "dofs_to_reach",
]

ROD = "rod"
#: ``progress(done, total, description)``, called after each level.
Progress = Callable[[int, int, str], None]
#: The versions of the system a study can run (see :func:`study_variants`).
VARIANTS = ("constrained", "unconstrained", "bare")
#: Largest number of sine functions a level may ask for (the mass and stiffness quadrature is
#: dense: about ``1250 n^2`` bytes, 1.3 GB at this size).
MAX_RITZ = 1024
#: Largest number of elements a level may ask for.
MAX_ELEMENTS = 1_000_000

# ------------------------------------------------------------------------------ the system


@dataclass(frozen=True)
class Attachment:
    """A spring-mass(-damper) secondary system attached to the rod at ``x`` (eqs 17-20).

    Attributes:
        name: its name (kept verbatim in outputs).
        x: attachment position on the rod.
        kind: ``"fixed-free"`` (mass on a spring to ground, attached at the mass) or
            ``"free-free"`` (absorber: massless boundary DOF at the rod, spring, mass).
        mass, stiffness, damping: ``m``, ``k``, ``c``.
    """

    name: str
    x: float
    kind: str = "fixed-free"
    mass: float = 1.0
    stiffness: float = 1.0
    damping: float = 0.0

    def substructure(self) -> Substructure:
        """The secondary system as a :class:`Substructure`."""
        if self.kind == "fixed-free":
            return fixed_free(self.name, self.mass, self.stiffness, self.damping)
        if self.kind == "free-free":
            return free_free(self.name, self.mass, self.stiffness, self.damping)
        raise ValueError(f"attachment {self.name}: kind must be 'fixed-free' or 'free-free', "
                         f"got {self.kind!r}")


@dataclass(frozen=True)
class PointConstraint:
    r"""A homogeneous constraint on rod points, :math:`\sum_k c_k u(x_k) = 0` (eq 52).

    Attributes:
        terms: ``(x, c)`` pairs.
        name: label in outputs.
    """

    terms: tuple[tuple[float, float], ...]
    name: str = ""


@dataclass(frozen=True)
class RodSystemSpec:
    """A rod with attachments and extra point constraints: what a convergence study refines.

    Attributes:
        name: system name (outputs are ``<name>_convergence.h5`` ...).
        length: rod length ``L``.
        EA, m: stiffness and mass per unit length: constants or vectorized callables of ``x``.
        support: rod end conditions, one of :data:`substruct.models.rod.SUPPORTS`.
        attachments: secondary systems.
        constraints: extra linear constraints on rod points.
        n_modes: number of lowest roots studied.
    """

    name: str
    length: float
    EA: Profile | float
    m: Profile | float
    support: str = "fixed-free"
    attachments: tuple[Attachment, ...] = ()
    constraints: tuple[PointConstraint, ...] = ()
    n_modes: int = 6

    @property
    def points(self) -> tuple[float, ...]:
        """Attachment and constraint positions, sorted, without repeats: where the mode shapes
        have slope jumps (FE nodes, enrichment load points)."""
        xs = [float(a.x) for a in self.attachments]
        xs += [float(x) for c in self.constraints for x, _ in c.terms]
        out: list[float] = []
        for x in sorted(xs):
            if not out or abs(x - out[-1]) > 1e-9 * float(self.length):
                out.append(x)
        return tuple(out)

    @property
    def damped(self) -> bool:
        """Whether any attachment has damping (the roots are then complex)."""
        return any(a.damping > 0 for a in self.attachments)

    def constraint_names(self) -> str:
        """The constraints' names, joined (``"eq52"``)."""
        return ", ".join(c.name or f"constraint {i + 1}" for i, c in enumerate(self.constraints))

    def assemble(self, rod: Substructure) -> Assembly:
        """Stack ``rod`` (named ``"rod"``) with the attachments and build ``A`` (eqs 23-27, 52)."""
        subs = [rod] + [a.substructure() for a in self.attachments]
        links = [Connection(PointRef(rod.name, a.x), PointRef(a.name, "boundary"),
                            name=f"{a.name} at x={a.x:g}") for a in self.attachments]
        extra = [LinearConstraint(tuple((PointRef(rod.name, x), float(c)) for x, c in pc.terms),
                                  name=pc.name or f"constraint {i + 1}")
                 for i, pc in enumerate(self.constraints)]
        return assemble(subs, links, extra)


def paper_rod_spec() -> RodSystemSpec:
    r"""The tapered rod of section 6 (Table 1, DESIGN.md section 2).

    :math:`L = 200`, :math:`EA(x) = \frac65\, 6\cdot 10^6 [1 - (x/L)^2/2]`,
    :math:`m(x) = \frac65 [1 - (x/L)^2/2]` (eq 50), fixed-free; ``a``, ``b`` fixed-free at
    ``L/4``, ``L/2`` (``k = 3000, 9000``), ``c``, ``d`` free-free at ``3L/4``, ``L``
    (``k = 7000, 3000``), all masses 1; constraint (52)
    :math:`2u(L/4) - 5u(L/2) - 4u(3L/4) + 3u(L) = 0`; 6 modes.
    """
    L = 200.0
    EA, m = paper_taper(2.0e5 * 30.0, 1.0, L)
    att = (Attachment("a", L / 4, "fixed-free", 1.0, 3000.0),
           Attachment("b", L / 2, "fixed-free", 1.0, 9000.0),
           Attachment("c", 3 * L / 4, "free-free", 1.0, 7000.0),
           Attachment("d", L, "free-free", 1.0, 3000.0))
    eq52 = PointConstraint(((L / 4, 2.0), (L / 2, -5.0), (3 * L / 4, -4.0), (L, 3.0)), "eq52")
    return RodSystemSpec("tapered_rod", L, EA, m, "fixed-free", att, (eq52,), 6)


# ------------------------------------------------------------------------------ the levels


@dataclass(frozen=True)
class StudyLevels:
    """Sizes of each series.

    Attributes:
        assumed: numbers ``n`` of sine functions (``g = n``).
        fixed_g: also run the sines reduced to this many rod modes (levels ``n >= g``);
            ``None`` for no such series.
        enriched: numbers ``n`` of sines of the enriched basis (plus one static shape per point).
        fe_p1, fe_p2: target numbers of elements.
    """

    assumed: tuple[int, ...] = (4, 8, 16, 32, 64, 128, 256)
    fixed_g: int | None = 4
    enriched: tuple[int, ...] = (1, 2, 4, 6, 8, 12, 16, 24, 32, 48, 64)
    fe_p1: tuple[int, ...] = (8, 16, 32, 64, 128, 256, 512, 1024)
    fe_p2: tuple[int, ...] = (4, 8, 16, 32, 64, 128, 256, 512)

    PRESETS = ("quick", "default", "fine")

    @classmethod
    def preset(cls, name: str) -> "StudyLevels":
        """``"quick"`` (a few seconds, coarse), ``"default"``, ``"fine"`` (longer series)."""
        if name == "default":
            return cls()
        if name == "quick":
            return cls(assumed=(4, 8, 16, 32, 64), enriched=(1, 2, 4, 8, 16, 32),
                       fe_p1=(8, 16, 32, 64, 128, 256), fe_p2=(4, 8, 16, 32, 64, 128))
        if name == "fine":
            return cls(assumed=(4, 8, 16, 32, 64, 128, 256, 512),
                       enriched=(1, 2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64, 96),
                       fe_p1=(8, 16, 32, 64, 128, 256, 512, 1024, 2048),
                       fe_p2=(4, 8, 16, 32, 64, 128, 256, 512, 1024))
        raise ValueError(f"unknown levels preset {name!r}; expected one of {cls.PRESETS}")


_LEVEL_KEYS = {"assumed": "assumed", "am": "assumed", "enriched": "enriched",
               "p1": "fe_p1", "fe_p1": "fe_p1", "fe-p1": "fe_p1",
               "p2": "fe_p2", "fe_p2": "fe_p2", "fe-p2": "fe_p2", "g": "fixed_g",
               "fixed_g": "fixed_g"}


def parse_levels(text: str | None, *, fixed_g: int | None = 4) -> StudyLevels:
    """Levels from a command-line string.

    A preset name (``quick``, ``default``, ``fine``), or ``;``-separated items ``key=values``
    over the default levels (or over a preset named as the first item), ``values`` a comma
    list or ``a:b`` (powers of two from ``a`` up to ``b``), ``key`` one of ``assumed``,
    ``enriched``, ``p1``, ``p2``, ``g`` (``g=none`` drops the fixed-g series, an empty list
    drops a series)::

        "assumed=4:256; p1=8:1024; p2=4,8,16,32,64; g=4"
        "quick; g=none"

    Args:
        text: the string (``None`` or blank: the default levels).
        fixed_g: ``g`` of the fixed-g series unless ``text`` sets one (``None``: no such
            series); a case file's ``reduce: {modes: g}``.

    Raises:
        ValueError: an unknown key, a value that is not a positive integer, a range ``a:b``
            with ``a > b``, more than :data:`MAX_RITZ` functions or :data:`MAX_ELEMENTS`
            elements.
    """
    if fixed_g is not None:
        fixed_g = _positive_int(str(fixed_g), f"g={fixed_g}")
    items = [s.strip() for s in (text or "").split(";") if s.strip()]
    base = StudyLevels()
    if items and items[0] in StudyLevels.PRESETS:
        base = StudyLevels.preset(items.pop(0))
    changes: dict[str, Any] = {"fixed_g": fixed_g}
    for item in items:
        key, sep, value = item.partition("=")
        key = key.strip().lower()
        if not sep or key not in _LEVEL_KEYS:
            raise ValueError(f"levels: bad item {item!r}; expected key=values with key one of "
                             "assumed, enriched, p1, p2, g, or a preset " f"{StudyLevels.PRESETS}"
                             " first")
        field_name = _LEVEL_KEYS[key]
        value = value.strip()
        if field_name == "fixed_g":
            changes[field_name] = None if value.lower() in ("", "none", "off") else \
                _positive_int(value, item)
            continue
        if ":" in value:
            lo, hi = (_positive_int(v, item) for v in value.split(":", 1))
            if lo > hi:
                raise ValueError(f"levels: empty range {value!r} in {item!r} (a:b needs a <= b)")
            vals = [lo]
            while vals[-1] * 2 <= hi:
                vals.append(vals[-1] * 2)
        else:
            vals = [_positive_int(v, item) for v in value.split(",") if v.strip()]
        most = MAX_RITZ if field_name in ("assumed", "enriched") else MAX_ELEMENTS
        if vals and max(vals) > most:
            what = "functions" if most == MAX_RITZ else "elements"
            raise ValueError(f"levels: {max(vals)} in {item!r} is more than the {most} {what} "
                             "a level may have")
        changes[field_name] = tuple(sorted(set(vals)))
    return dataclasses.replace(base, **changes)


def _positive_int(text: str, item: str) -> int:
    try:
        v = int(text.strip())
    except ValueError:
        raise ValueError(f"levels: {text!r} in {item!r} is not an integer") from None
    if v < 1:
        raise ValueError(f"levels: {v} in {item!r} must be positive")
    return v


# ------------------------------------------------------------------------------- results


@dataclass
class SeriesResult:
    """One discretization refined: plain arrays over levels (rows) and modes (columns).

    Attributes:
        key: ``"assumed"``, ``"assumed-g4"``, ``"enriched"``, ``"fe-p1"``, ``"fe-p2"``.
        label: for tables and legends.
        level: the size parameter (``n`` or target number of elements).
        dofs: Ritz functions or free FE DOFs of the rod (before modal reduction).
        coupled_dofs: coordinates of the assembled system.
        seconds: wall time of each level (build, assemble, solve; a rod model reused from
            another series or variant is charged the time its build took).
        eigenvalues: complex roots ``(levels, modes)`` (``i omega`` if undamped; NaN if the
            level has fewer roots).
        rel_error: ``|lambda - lambda_ref| / |lambda_ref|`` (``inf`` where the level has fewer
            roots than asked, NaN for a rigid-body reference root).
        rate: fitted order ``p`` per mode (``e ~ N^-p``; NaN if fewer than 2 levels fit).
        fit_mask: levels used in each fit ``(levels, modes)``.
        theory_rate: the expected order (NaN when there is none to state).
        extrapolated_difference: per mode, relative difference between this series'
            own Richardson extrapolation (with its fitted order) and the reference limit: the
            evidence that it converges to the same limit (NaN if the order is below 0.5).
    """

    key: str
    label: str
    level: np.ndarray
    dofs: np.ndarray
    coupled_dofs: np.ndarray
    seconds: np.ndarray
    eigenvalues: np.ndarray
    rel_error: np.ndarray
    rate: np.ndarray
    fit_mask: np.ndarray
    theory_rate: float
    extrapolated_difference: np.ndarray

    @property
    def omega(self) -> np.ndarray:
        """``|lambda|`` (rad/s), the natural frequencies of an undamped system."""
        return np.abs(self.eigenvalues)

    @property
    def worst_error(self) -> np.ndarray:
        """Largest error over the modes at each level (rigid-body NaN entries ignored; ``inf``
        if a root is missing)."""
        e = np.where(np.isnan(self.rel_error), -np.inf, self.rel_error)
        out = e.max(axis=1)
        return np.where(np.isneginf(out), np.nan, out)


@dataclass
class VariantResult:
    """The study of one version of the system (with constraints, without, bare rod).

    Attributes:
        key: ``"constrained"``, ``"unconstrained"`` or ``"bare"``.
        label: e.g. ``"with eq52"``.
        series: by series key, in run order.
        limit_finest: roots of the finest reference level.
        limit_richardson: Richardson estimate (NaN if the reference series has one level).
        limit: the reference used for the errors.
        limit_difference: :math:`\\delta_j`, relative difference between the two estimates.
        limit_source: e.g. ``"fe-p2 n_el=512 (Richardson with 256, order 4)"``.
        reference_order: observed order of the reference series from three levels, with no
            assumed limit (the finest triple whose last difference exceeds 10 error_floor).
        floor: error floor of the rate fits per mode.
        seconds: wall time of the variant.
    """

    key: str
    label: str
    series: dict[str, SeriesResult]
    limit_finest: np.ndarray
    limit_richardson: np.ndarray
    limit: np.ndarray
    limit_difference: np.ndarray
    limit_source: str
    reference_order: np.ndarray
    floor: np.ndarray
    seconds: float


@dataclass
class ConvergenceResult:
    """Everything a convergence study produced (plain data, HDF5 round trip).

    Attributes:
        name: system name.
        n_modes: modes studied.
        variants: by variant key.
        levels: the :class:`StudyLevels` as a dict.
        seconds: total wall time.
        attrs: settings (reference, fit points, floor, ...).
    """

    name: str
    n_modes: int
    variants: dict[str, VariantResult]
    levels: dict[str, Any]
    seconds: float
    attrs: dict[str, Any] = field(default_factory=dict)


# -------------------------------------------------------------------------------- solving


def _null_space(A: sp.csr_array, rtol: float = 1e-10) -> sp.csr_array:
    r"""Sparse ``Z`` with ``A Z = 0``: eliminate ``rank(A)`` pivot coordinates.

    .. math::  Q^T A = B, \quad B \Pi = [B_p\; B_f], \qquad
               u_p = -B_p^{-1} B_f\, u_f, \qquad u = Z u_{\bar p}

    with ``Q R Pi`` the pivoted QR of the (row-scaled) columns of ``A`` that hold entries.
    ``Z`` is the identity on the kept coordinates plus ``rank(A)`` rows.
    """
    m, n = A.shape
    A = sp.csr_array(A)
    A.eliminate_zeros()
    if m == 0 or A.nnz == 0:
        return sp.csr_array(sp.eye_array(n))
    cols = np.unique(A.indices)
    Ad = A[:, cols].toarray()
    rn = np.linalg.norm(Ad, axis=1)
    Ad = Ad[rn > 0] / rn[rn > 0, None]
    Q, R, piv = sla.qr(Ad, mode="economic", pivoting=True)
    d = np.abs(np.diag(R))
    r = int(np.sum(d > rtol * d[0]))
    B = Q[:, :r].T @ Ad
    X = -sla.solve(B[:, piv[:r]], B[:, piv[r:]])  # r x (s - r)
    elim = cols[piv[:r]]
    keep = np.setdiff1d(np.arange(n), elim)
    pos = -np.ones(n, dtype=int)
    pos[keep] = np.arange(keep.size)
    rows = [keep, np.repeat(elim, X.shape[1])]
    colidx = [np.arange(keep.size), np.tile(pos[cols[piv[r:]]], r)]
    vals = [np.ones(keep.size), X.ravel()]
    Z = sp.coo_array((np.concatenate(vals), (np.concatenate(rows), np.concatenate(colidx))),
                     shape=(n, keep.size))
    return sp.csr_array(Z)


def lowest_modes(asm: Assembly, n_modes: int, *, dense_limit: int = 400) -> np.ndarray:
    r"""The ``n_modes`` lowest roots of an assembled constrained system.

    .. math::  (\lambda^2 Z^T M Z + \lambda Z^T C Z + Z^T K Z)\, p = 0, \qquad A Z = 0

    (the null-space formulation; ``Z`` from a pivoted elimination, sparse).  Undamped:
    :math:`Z^T K Z\, p = \omega^2 Z^T M Z\, p`, dense ``eigh`` up to ``dense_limit`` coordinates
    or for dense matrices, else shift-invert Lanczos about a small negative shift with a SuperLU
    ``OPinv``.  Damped: the first companion form, dense ``eig`` or shift-invert Arnoldi.

    Args:
        asm: the assembled system (homogeneous constraints).
        n_modes: number of roots wanted.
        dense_limit: largest reduced size solved densely.

    Returns:
        Complex roots ``(n_modes,)`` with ``Im >= 0`` (one of each conjugate pair; ``i omega`` if
        undamped), ascending in modulus, NaN-padded if the system has fewer.
    """
    Z = _null_space(asm.A)
    Mr = sp.csr_array(Z.T @ asm.M @ Z)
    Kr = sp.csr_array(Z.T @ asm.K @ Z)
    Cr = sp.csr_array(Z.T @ asm.C @ Z)
    Cr.eliminate_zeros()
    n = Mr.shape[0]
    out = np.full(n_modes, np.nan + 0j)
    if n == 0:
        return out
    # a small negative shift keeps K - shift M definite with rigid-body modes (as reduction.py)
    scale = max(abs(Kr.diagonal()).sum() / max(abs(Mr.diagonal()).sum(), 1e-300), 1e-300)
    shift = -1e-9 * scale
    dense = n <= dense_limit or Kr.nnz > 0.2 * n * n
    if Cr.nnz == 0 or abs(Cr).max() == 0:
        k = min(n_modes, n)
        if dense or k >= n - 1:
            Md, Kd = Mr.toarray(), Kr.toarray()
            lam = sla.eigh((Kd + Kd.T) / 2, (Md + Md.T) / 2, eigvals_only=True,
                           subset_by_index=[0, k - 1])
        else:
            lu = spla.splu(sp.csc_matrix(Kr - shift * Mr), permc_spec="MMD_AT_PLUS_A")
            op = spla.LinearOperator((n, n), matvec=lu.solve, dtype=float)
            lam = spla.eigsh(Kr, k=k, M=Mr, sigma=shift, which="LM", OPinv=op,
                             v0=_start(n), return_eigenvectors=False)
        lam = np.sort(np.maximum(np.real(lam), 0.0))
        out[:k] = 1j * np.sqrt(lam)
        return out
    # damped: X v = lambda Y v, v = [lambda p; p]
    I = sp.eye_array(n)
    X = sp.bmat([[-Cr, -Kr], [I, None]], format="csc")
    Y = sp.bmat([[Mr, None], [None, I]], format="csc")
    k2 = min(2 * n_modes + 2, 2 * n - 2)
    if dense or k2 < 1:
        lam = sla.eig(X.toarray(), Y.toarray(), right=False)
    else:
        lu = spla.splu(sp.csc_matrix(X - shift * Y), permc_spec="MMD_AT_PLUS_A")
        op = spla.LinearOperator((2 * n, 2 * n), matvec=lu.solve, dtype=float)
        lam = spla.eigs(X, k=k2, M=Y, sigma=shift, which="LM", OPinv=op,
                        v0=_start(2 * n), return_eigenvectors=False)
    lam = lam[np.isfinite(lam)]
    lam = lam[lam.imag >= -1e-9 * np.maximum(abs(lam), 1e-300)]
    lam = np.where(abs(lam.imag) <= 1e-9 * abs(lam), lam.real + 0j, lam)
    lam = lam[np.argsort(abs(lam), kind="stable")][:n_modes]
    out[:lam.size] = lam
    return out


def _start(n: int) -> np.ndarray:
    """A fixed start vector for ARPACK: the same run gives the same numbers (its own random
    start once made test_lowest_modes_damped_attachments fail)."""
    return np.random.default_rng(0).standard_normal(n)


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
    pts = spec.points
    L, EA, m, sup = spec.length, spec.EA, spec.m, spec.support
    rods = rods or _Rods()

    def sines(n: int) -> tuple[Substructure, float]:
        return rods.get(("sines", n, pts),
                        lambda: rod_assumed_modes(ROD, L, EA, m, n, sup, nodes_at=pts))

    def truncated(n: int, g: int) -> tuple[Substructure, float]:
        rod, charge = sines(n)
        return modal_truncation(rod, g), charge

    def made(key: tuple[Any, ...], make: Callable[[], Substructure]
             ) -> tuple[Substructure, float]:
        return rods.get(key + (pts,), make)

    out = [_Method("assumed", "assumed modes (g = n)", tuple(levels.assumed),
                   np.nan if smooth else 1.0, sines)]
    g = levels.fixed_g
    if g is not None:
        out.append(_Method(f"assumed-g{g}", f"assumed modes (g = {g})",
                           tuple(n for n in levels.assumed if n >= g), np.nan,
                           lambda n: truncated(n, g)))
    if pts:
        out.append(_Method("enriched", "enriched assumed modes", tuple(levels.enriched), np.nan,
                           lambda n: made(("enriched", n), lambda: rod_assumed_modes_enriched(
                               ROD, L, EA, m, n, pts, sup))))
    out.append(_Method("fe-p1", "FE P1", tuple(levels.fe_p1), 2.0,
                       lambda n: made(("p1", n), lambda: rod_fe(ROD, L, EA, m, n, 1, sup,
                                                                nodes_at=pts))))
    out.append(_Method("fe-p2", "FE P2", tuple(levels.fe_p2), 4.0,
                       lambda n: made(("p2", n), lambda: rod_fe(ROD, L, EA, m, n, 2, sup,
                                                                nodes_at=pts))))
    return [mt for mt in out if mt.levels]


def _fit(dofs: np.ndarray, err: np.ndarray, floor: float, fit_points: int
         ) -> tuple[float, np.ndarray]:
    """Order ``p`` of ``err ~ C dofs^-p`` over the finest ``fit_points`` levels above ``floor``
    (NaN if fewer levels are above it)."""
    ok = np.isfinite(err) & (err > floor)
    idx = np.nonzero(ok)[0][-fit_points:]
    mask = np.zeros(err.shape, dtype=bool)
    if idx.size < max(fit_points, 2) or np.unique(dofs[idx]).size < 2:
        return np.nan, mask
    mask[idx] = True
    slope = np.polyfit(np.log(dofs[idx]), np.log(err[idx]), 1)[0]
    return float(-slope), mask


def _observed_order(lam: np.ndarray, n_el: np.ndarray, floor: float) -> np.ndarray:
    r"""Order from three levels without any assumed limit, per mode:
    :math:`p = \log(|\lambda_2 - \lambda_1| / |\lambda_3 - \lambda_2|) / \log r`, over the
    finest triple whose last difference is above ``floor`` (relative); NaN if there is none."""
    k = lam.shape[1] if lam.ndim == 2 else 0
    out = np.full(k, np.nan)
    for j in range(k):
        for i in range(lam.shape[0] - 1, 1, -1):
            l1, l2, l3 = lam[i - 2, j], lam[i - 1, j], lam[i, j]
            if not np.all(np.isfinite([l1, l2, l3])) or abs(l3 - l2) <= floor * abs(l3):
                continue
            out[j] = np.log(abs(l2 - l1) / abs(l3 - l2)) / np.log(n_el[i] / n_el[i - 1])
            break
    return out


def _richardson(lf: np.ndarray, lc: np.ndarray, ratio: float, order: float) -> np.ndarray:
    return lf + (lf - lc) / (ratio**order - 1.0)


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
            rich = _richardson(r["lam"][-1], r["lam"][-2], ratio, order)
            source += f" (Richardson with n_el={r['n_el'][-2]}, order {order:g})"
        else:
            rich = nan
        ref_order = _observed_order(r["lam"], r["n_el"], 10 * error_floor)
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
            rates[j], masks[:, j] = _fit(r["dofs"].astype(float), err[:, j], floor[j],
                                         fit_points)
            if np.isfinite(rates[j]) and rates[j] >= 0.5 and lam.shape[0] >= 2 \
                    and np.all(np.isfinite(lam[-2:, j])):
                ext = _richardson(lam[-1, j], lam[-2, j], r["dofs"][-1] / r["dofs"][-2],
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
