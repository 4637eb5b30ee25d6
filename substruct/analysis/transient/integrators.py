r"""One-step implicit integrators of :math:`M \ddot q + C \dot q + K q = F(t) + A^T \lambda`,
:math:`A q = b`: Newmark's average acceleration and the generalized-alpha method.

The generalized-alpha method (Chung and Hulbert, 1993) satisfies the equation of motion at
shifted instants,

.. math::  M a_{n+1-\alpha_m} + C v_{n+1-\alpha_f} + K d_{n+1-\alpha_f}
           = F(t_{n+1-\alpha_f}) + A^T \lambda, \qquad x_{n+1-\alpha} = (1-\alpha) x_{n+1}
           + \alpha x_n,

with Newmark's updates

.. math::  d_{n+1} = d_n + h v_n + h^2 \big[(\tfrac12 - \beta) a_n + \beta a_{n+1}\big],
           \qquad v_{n+1} = v_n + h \big[(1-\gamma) a_n + \gamma a_{n+1}\big],

and, for a spectral radius :math:`\rho_\infty \in [0, 1]` at infinite frequency,
:math:`\alpha_m = (2\rho_\infty - 1)/(\rho_\infty + 1)`,
:math:`\alpha_f = \rho_\infty/(\rho_\infty + 1)`, :math:`\gamma = \tfrac12 - \alpha_m + \alpha_f`,
:math:`\beta = \tfrac14 (1 - \alpha_m + \alpha_f)^2`: second order, unconditionally stable.
Newmark's average acceleration is :math:`\alpha_m = \alpha_f = 0`, :math:`\beta = \tfrac14`,
:math:`\gamma = \tfrac12` (energy conserving, no numerical damping).

Each step solves with the effective matrix

.. math::  S = (1 - \alpha_m) M + (1 - \alpha_f)\, \gamma h\, C + (1 - \alpha_f)\, \beta h^2 K ,

factorized once for a constant step.  Constraints (the generalized-inverse form) enter as eq (5)
with :math:`S` in the place of :math:`M`: the acceleration without constraint,
:math:`a^0 = S^{-1} r`, is corrected by

.. math::  a_{n+1} = a^0 + S^{-1} A^T (A S^{-1} A^T)^+ (c - A a^0), \qquad
           c = (b - A d^*)/(\beta h^2) ,

which makes :math:`A d_{n+1} = b` (:math:`d^*` the predicted displacement; with a moving
ground, :math:`b_{n+1} = b + e g_{n+1}`, :mod:`substruct.analysis.transient.base`).  :math:`S` is
definite where :math:`M` is only semidefinite (massless coordinates with a stiffness, eq 10),
so the same correction serves; where a massless motion has no stiffness either and only the
constraints hold it, the form solves with :math:`S + A^T D A` instead, which gives the same
step (:mod:`substruct.analysis.transient.effective`).  After each step the displacement, velocity and acceleration
are projected (the :math:`S`-orthogonal projector), which removes the rounding that would
otherwise accumulate: :math:`|A d_n - b|` stays at the rounding level of one step.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Mapping, Protocol, TypeAlias

import numpy as np
import scipy.sparse as sp

from substruct.linalg.factorize import Solve
from substruct.vocabulary import INTEGRATORS
from substruct.linalg.solve_type import Matrix

__all__ = ["INTEGRATORS", "Scheme", "Correction", "Sink", "LoadSteps", "Restart", "StepState",
           "StepControl", "scheme", "integrate", "effective_matrix"]




@dataclass(frozen=True)
class Scheme:
    """The parameters of a generalized-alpha step (Newmark's average acceleration included)."""

    name: str
    alpha_m: float
    alpha_f: float
    beta: float
    gamma: float
    #: the spectral radius at infinite frequency (1 for Newmark's average acceleration)
    rho_inf: float = 1.0


def scheme(name: str, rho_inf: float = 1.0) -> Scheme:
    r"""The scheme ``name`` (one of :data:`INTEGRATORS`); ``rho_inf`` is that of
    generalized-alpha (Newmark's average acceleration has 1 whatever is given).

    .. math::  \alpha_m = \frac{2\rho_\infty - 1}{\rho_\infty + 1}, \quad
               \alpha_f = \frac{\rho_\infty}{\rho_\infty + 1}, \quad
               \gamma = \tfrac12 - \alpha_m + \alpha_f, \quad
               \beta = \tfrac14 (1 - \alpha_m + \alpha_f)^2

    Raises:
        ValueError: an unknown name, or ``rho_inf`` outside ``[0, 1]``.
    """
    if name == "newmark":
        return Scheme("newmark", 0.0, 0.0, 0.25, 0.5, 1.0)
    if name == "generalized-alpha":
        if not 0.0 <= rho_inf <= 1.0:
            raise ValueError(f"rho_inf must lie in [0, 1], got {rho_inf!r}")
        am = (2 * rho_inf - 1) / (rho_inf + 1)
        af = rho_inf / (rho_inf + 1)
        return Scheme("generalized-alpha", am, af, 0.25 * (1 - am + af) ** 2, 0.5 - am + af,
                      float(rho_inf))
    raise ValueError(f"unknown integrator {name!r}; expected one of {', '.join(INTEGRATORS)}")


def effective_matrix(M: Matrix, C: Matrix | None, K: Matrix, s: Scheme, h: float) -> Matrix:
    r""":math:`S = (1-\alpha_m) M + (1-\alpha_f)\gamma h C + (1-\alpha_f)\beta h^2 K`."""
    S = (1 - s.alpha_m) * M + (1 - s.alpha_f) * s.beta * h * h * K
    if C is not None:
        S = S + (1 - s.alpha_f) * s.gamma * h * C
    return S


@dataclass(frozen=True)
class Correction:
    r"""The constraint correction of eq (5) with the effective matrix :math:`S`:
    ``gain = S^{-1} A^T (A S^{-1} A^T)^+`` (``n x m``, dense) on equilibrated rows ``A``,
    right-hand side ``b``."""

    A: sp.csr_array
    b: np.ndarray
    gain: np.ndarray
    #: a moving ground (:mod:`substruct.analysis.transient.base`): ``A q_k = b + e g_k``,
    #: ``A v_k = e g'_k``; ``g`` is ``(n_steps + 1) x 3`` (``None``: a fixed ``b``)
    e: np.ndarray | None = None
    g: np.ndarray | None = None
    #: the rows hold every coordinate (rank ``n``): :math:`A x = t` fixes ``x``, and
    #: :meth:`apply` gives :math:`G t` itself, not ``x`` plus a correction of its rounding
    #: (which would be carried from step to step: a zero response of round-off, not 0)
    held: bool = False

    def target(self, step: int) -> np.ndarray:
        """The right-hand side :math:`b + e g_k` of step ``step``."""
        return self.b if self.e is None or self.g is None else self.b + self.e * self.g[step, 0]

    def rate(self, step: int) -> np.ndarray | float:
        r"""The velocity's right-hand side :math:`e \dot g_k` of step ``step``."""
        return 0.0 if self.e is None or self.g is None else self.e * self.g[step, 1]

    def apply(self, x: np.ndarray, target: np.ndarray | float) -> np.ndarray:
        r""":math:`x + G (t - A x)`: the :math:`S`-orthogonal projection onto
        :math:`A x = t` (:math:`G t` when the rows hold every coordinate, ``held``)."""
        if self.held:
            return self.gain @ np.broadcast_to(target, (self.A.shape[0],))
        return x + self.gain @ (target - self.A @ x)

    def apply_both(self, x: np.ndarray, x_target: np.ndarray | float, y: np.ndarray,
                   y_target: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        r""":meth:`apply` to two vectors with one product of the gain (``n x 2``): the gain,
        ``n x m`` and dense, is read once instead of twice (at 100k coordinates and 1,203
        rows it is 0.96 GB, read every step)."""
        if self.held:
            return self.apply(x, x_target), self.apply(y, y_target)
        misfit = np.column_stack([x_target - self.A @ x, y_target - self.A @ y])
        step = self.gain @ misfit
        return x + step[:, 0], y + step[:, 1]


@dataclass
class Work:
    r"""Energy flows accumulated over the steps (trapezoidal, exact for average acceleration).

    Newmark's average acceleration has :math:`d_{n+1} - d_n = h \bar v`,
    :math:`v_{n+1} - v_n = h \bar a` (bars: the averages of the step's ends), so with the
    equation of motion :math:`M a_k + C v_k + K d_k = F_k + Q^c_k` at both ends of the step

    .. math::  \Delta (\tfrac12 v^T M v + \tfrac12 d^T K d)
               = h \bar v^T (M \bar a + K \bar d)
               = (d_{n+1} - d_n)^T \tfrac12 (F_n + F_{n+1} + Q^c_n + Q^c_{n+1})
               - h \bar v^T C \bar v ,

    exactly: :math:`T + V - W + D` is constant to rounding.  The constraint force
    :math:`Q^c = A^T \lambda` does no work while :math:`A (d_{n+1} - d_n) = 0`
    (a constant ``b``); with a moving ground it does, :math:`\bar\lambda^T e\,
    (g_{n+1} - g_n)`, and is counted in ``external``.  Generalized-alpha with
    :math:`\rho_\infty < 1` satisfies the equation at shifted instants and removes energy
    from the high frequencies: there the balance is not constant.

    Attributes:
        external: :math:`\sum (d_{n+1} - d_n)^T (F_{n+1} + F_n + Q^c_{n+1} + Q^c_n)/2`
            (:math:`Q^c` counted only with a moving ground).
        dissipated: :math:`\sum h\, \bar v^T C \bar v`, :math:`\bar v = (v_n + v_{n+1})/2`.
    """

    external: float = 0.0
    dissipated: float = 0.0


class Sink(Protocol):
    """What a march reports to: ``sink(step, d, v, a)`` with the state after every
    ``every``-th step (and at step 0), and ``sink.on_work(step, work)`` with the energy flows
    accumulated up to it (:class:`Work`)."""

    def __call__(self, step: int, d: np.ndarray, v: np.ndarray, a: np.ndarray, /) -> None: ...

    def on_work(self, step: int, work: Work, /) -> None: ...


@dataclass(frozen=True)
class StepState:
    """The displacement ``d``, velocity ``v`` and acceleration ``a`` at one instant (equal
    lengths; ``a`` consistent with the equation of motion).

    Raises:
        ValueError: the three do not have one length.
    """

    d: np.ndarray
    v: np.ndarray
    a: np.ndarray

    def __post_init__(self) -> None:
        shapes = {np.shape(x) for x in (self.d, self.v, self.a)}
        if len(shapes) != 1 or len(next(iter(shapes))) != 1:
            raise ValueError(f"a state needs three vectors of one length, got shapes "
                             f"{sorted(shapes)}")


@dataclass(frozen=True)
class StepControl:
    r"""How a march is made: the scheme ``scheme``, ``n_steps`` steps of size ``h``, the solve
    ``solve`` with the effective matrix :math:`S` (:func:`effective_matrix`) factorized once,
    and the state reported every ``every`` steps.

    Raises:
        ValueError: ``h`` not positive and finite, ``n_steps < 0``, ``every < 1``.
    """

    scheme: Scheme
    h: float
    n_steps: int
    solve: Solve
    every: int = 1

    def __post_init__(self) -> None:
        if not (0 < self.h < np.inf):
            raise ValueError(f"the step must be positive and finite, got {self.h!r}")
        if self.n_steps < 0 or self.every < 1:
            raise ValueError(f"need n_steps >= 0 and every >= 1, got {self.n_steps}, "
                             f"{self.every}")


@dataclass(frozen=True)
class LoadSteps:
    r"""The load factors as the steps see them: the nodal values ``f`` (``(n_steps + 1) x L``,
    :math:`f_k = f(t_k)`) and, for the steps over which a load jumps or kinks, the values at
    the step's start and end that replace them (``pairs[n] = (start, end)``, each ``L``;
    :mod:`substruct.analysis.transient.loads`).  Step ``n`` integrates the load that varies
    linearly from ``start(n)`` to ``end(n)``."""

    f: np.ndarray
    pairs: Mapping[int, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)

    def start(self, n: int) -> np.ndarray:
        """The load factors at the start of step ``n``."""
        return self.pairs[n][0] if n in self.pairs else self.f[n]

    def end(self, n: int) -> np.ndarray:
        """The load factors at the end of step ``n``."""
        return self.pairs[n][1] if n in self.pairs else self.f[n + 1]

    def widened(self, extra: np.ndarray) -> "LoadSteps":
        """These loads with the nodal columns ``extra`` (``(n_steps + 1) x k``) appended (their
        pairs are their nodal values)."""
        ex = np.asarray(extra, dtype=float).reshape(self.f.shape[0], -1)
        return LoadSteps(np.hstack([self.f, ex]),
                         {n: (np.concatenate([a, ex[n]]), np.concatenate([b, ex[n + 1]]))
                          for n, (a, b) in self.pairs.items()})


#: ``restart(step, d, v, f) -> a``: the acceleration the equation of motion gives at step
#: ``step`` for the state ``(d, v)`` under the load factors ``f`` (eq 10 with constraints).
Restart: TypeAlias = Callable[[int, np.ndarray, np.ndarray, np.ndarray], np.ndarray]


def integrate(M: Matrix, C: Matrix | None, K: Matrix, B: Matrix, f: np.ndarray | LoadSteps,
              start: StepState, sink: Sink, control: StepControl, *,
              correction: Correction | None = None, restart: Restart | None = None) -> None:
    r"""March ``control.n_steps`` steps of size ``control.h`` from ``start``.

    A load that jumps (or kinks) within or at the end of a step enters that step as the linear
    function with the same integral and first moment over the step (:class:`LoadSteps`);
    where the load factors at the start of a step differ from those the acceleration was
    computed with, the acceleration is computed again from the equation of motion
    (``restart``), as at ``t = 0``.  So the step keeps the scheme's second order at a
    discontinuity anywhere in time, instead of the first order of nodal values.

    Args:
        M, C, K: the system matrices (``C`` may be ``None``).
        B, f: the load :math:`F(t_k) = B f_k`; ``f`` is ``(n_steps + 1) x L`` or a
            :class:`LoadSteps`.
        start: the initial state (its acceleration consistent with the equation of motion
            under ``f_0``).
        sink: called at step 0 and after every ``control.every``-th step, and after the last,
            with the acceleration under the nodal load :math:`f_k`, and ``sink.on_work`` with
            the energy flows accumulated since step 0.
        control: :class:`StepControl`: the scheme, the step, the number of steps, the solve
            with :math:`S`, how often the state is reported.
        correction: the constraint correction (the generalized-inverse form), or ``None``.
        restart: needed when ``f`` has pairs (:data:`Restart`).
    """
    s, h, n_steps, solve, every = (control.scheme, control.h, control.n_steps, control.solve,
                                   control.every)
    work = Work()
    load = f if isinstance(f, LoadSteps) else LoadSteps(np.asarray(f))
    if load.pairs and restart is None:
        raise ValueError("a load with jumps needs a restart of the acceleration")
    d, v, a = (np.array(x, dtype=float, copy=True) for x in (start.d, start.v, start.a))
    beta, gamma, am, af = s.beta, s.gamma, s.alpha_m, s.alpha_f
    c1, c2, c3 = h * h * (0.5 - beta), h * (1 - gamma), beta * h * h
    Bt = B.T
    damped = C is not None
    Cm: Matrix = C if C is not None else M  # used only when damped
    sink(0, d, v, a)
    sink.on_work(0, work)
    carried = load.f[0]  # the load factors the acceleration a was computed with
    moving = correction is not None and correction.e is not None

    def reaction(d: np.ndarray, v: np.ndarray, a: np.ndarray, f: np.ndarray) -> np.ndarray:
        """:math:`Q^c = M a + C v + K d - B f` (the equation of motion read backwards)."""
        Q = M @ a + K @ d - B @ f
        return Q + Cm @ v if damped else Q

    Qc = reaction(d, v, a, load.f[0]) if moving else None
    for n in range(n_steps):
        fs, fe = load.start(n), load.end(n)
        if restart is not None and not np.array_equal(fs, carried):
            a = restart(n, d, v, fs)
            Qc = reaction(d, v, a, fs) if moving else None
        d_star = d + h * v + c1 * a
        v_star = v + c2 * a
        fa = (1 - af) * fe + af * fs
        rhs = B @ fa - K @ (af * d + (1 - af) * d_star)
        if am:
            rhs -= am * (M @ a)
        if damped:
            rhs -= Cm @ (af * v + (1 - af) * v_star)
        a_new = solve(rhs)
        if correction is not None:
            target = correction.target(n + 1)
            a_new = correction.apply(a_new, (target - correction.A @ d_star) / c3)
        d_new = d_star + c3 * a_new
        v_new = v_star + gamma * h * a_new
        if correction is not None:  # remove the rounding that would drift
            d_new, v_new = correction.apply_both(d_new, target, v_new, correction.rate(n + 1))
        work.external += float((Bt @ (d_new - d)) @ (0.5 * (fs + fe)))
        if Qc is not None:  # the work of the moving supports' reactions
            Qn = reaction(d_new, v_new, a_new, fe)
            work.external += 0.5 * float((d_new - d) @ (Qc + Qn))
            Qc = Qn
        if damped:
            vm = 0.5 * (v + v_new)
            work.dissipated += h * float(vm @ (Cm @ vm))
        d, v, a = d_new, v_new, a_new
        carried = fe
        if (n + 1) % every == 0 or n + 1 == n_steps:
            nodal = load.f[n + 1]
            shown = a if restart is None or np.array_equal(nodal, fe) else \
                restart(n + 1, d, v, nodal)
            sink(n + 1, d, v, shown)
            sink.on_work(n + 1, work)
