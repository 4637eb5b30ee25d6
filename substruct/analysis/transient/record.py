r"""What a transient run keeps of each recorded step: outputs at points, the constraint force of
eq (5), the constraint residual, the energies, and the full field every k steps (into a
:class:`~substruct.analysis.transient.fields.FieldStore`: whole, or a block at a time to a
sink).

The constraint force is eq (5) read backwards,

.. math::  Q^c = M \ddot q - (P - C \dot q - K q) = A^T \lambda ,

reported as the multipliers :math:`\lambda` of the independent rows of ``A`` (least squares
through :math:`A_k A_k^T`, one sparse factorization; a redundant row gets 0).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Mapping, TypeAlias, cast

import numpy as np
import scipy.sparse as sp

from substruct.analysis.errors import CheckError
from substruct.analysis.transient.integrators import LoadSteps, Scheme, Work
from substruct.analysis.transient.base import Motion
from substruct.analysis.transient.fields import FieldStore, StoredFields
from substruct.linalg.factorize import factorizer
from substruct.linalg.solve_type import Matrix

__all__ = ["Physical", "Recorder", "constraint_force_solver", "energy_change",
           "require_energy_balance", "roundoff_energy"]



def constraint_force_solver(A: sp.csr_array, keep: np.ndarray
                            ) -> Callable[[np.ndarray], np.ndarray]:
    r"""``Q -> lambda`` with :math:`A_k A_k^T \lambda_k = A_k Q` on the rows ``keep``; the
    other rows 0."""
    m = A.shape[0]
    Ak = sp.csr_array(A[keep]) if m else A
    if Ak.shape[0] == 0:
        return lambda Q: np.zeros(m)
    solve = factorizer("superlu", spd=True)(sp.csc_array(Ak @ Ak.T))

    def forces(Q: np.ndarray) -> np.ndarray:
        lam = np.zeros(m)
        lam[keep] = solve(Ak @ Q)
        return lam

    return forces


@dataclass(frozen=True)
class Physical:
    r"""The physical model beside the integrated coordinates ``x``: :math:`q = T x + q_p`
    (``T`` ``None`` for the identity).

    Attributes:
        M, C, K: physical matrices; ``B``: the load map (``n x L``); ``f``: load values per
            step.
        A, b: equilibrated constraint rows.
        O: output rows (``n_out x n``).
        T, qp: the integrated coordinates' map and particular solution.
        motion: a moving ground (:mod:`substruct.analysis.transient.base`), or ``None``.
        pairs: step -> the load factors at its start and end, where a load jumps or kinks
            within it (:mod:`substruct.analysis.transient.loads`).
    """

    M: Matrix
    C: Matrix | None
    K: Matrix
    B: Matrix
    f: np.ndarray
    A: sp.csr_array
    b: np.ndarray
    O: Matrix
    T: Matrix | None = None
    qp: np.ndarray | None = None
    motion: Motion | None = None
    pairs: Mapping[int, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)

    @property
    def loads(self) -> LoadSteps:
        """The load factors as the steps see them (:class:`~substruct.analysis.transient.integrators.
        LoadSteps`: nodal values, pairs where a load jumps)."""
        return LoadSteps(self.f, self.pairs)

    def position(self, x: np.ndarray, step: int = 0) -> np.ndarray:
        """:math:`q = T x + q_p + r g_k` (``r g_k``: a moving ground, only when ``T`` is
        given; the generalized-inverse form integrates ``q`` itself)."""
        q = x if self.T is None else self.T @ x
        if self.T is not None and self.motion is not None:
            q = q + self.motion.r * self.motion.g[step, 0]
        return q if self.qp is None else q + self.qp

    def rate(self, x: np.ndarray, step: int = 0, order: int = 1) -> np.ndarray:
        """:math:`\\dot q = T \\dot x + r \\dot g_k` (``order`` 2: the accelerations)."""
        if self.T is None:
            return x
        q = self.T @ x
        return q if self.motion is None else q + self.motion.r * self.motion.g[step, order]


@dataclass
class Recorder:
    """Collects the recorded steps of one run (a :class:`substruct.analysis.transient.integrators.Sink`).

    ``M_x``, ``K_x``: the matrices of the integrated coordinates (for the energies);
    ``forces``: ``Q -> lambda`` or ``None`` (no constraint forces); ``fields``: where the full
    displacement of the steps it names goes (``None``: kept of none); ``offset``: added to the
    physical displacement (the static correction of modal superposition), per step; ``basis``:
    the modes of a modal run (how many, by what).  The displacement of the last step recorded
    is kept in any case (:attr:`last`).
    """

    phys: Physical
    M_x: Matrix
    K_x: Matrix
    dt: float
    forces: Callable[[np.ndarray], np.ndarray] | None = None
    fields: FieldStore | None = None
    offset: Callable[[int], np.ndarray] | None = None
    basis: str = ""
    t: list[float] = field(default_factory=list)
    d: list[np.ndarray] = field(default_factory=list)
    v: list[np.ndarray] = field(default_factory=list)
    a: list[np.ndarray] = field(default_factory=list)
    lam: list[np.ndarray] = field(default_factory=list)
    residual: list[float] = field(default_factory=list)
    qmax: float = 0.0
    energy: list[list[float]] = field(default_factory=list)
    last: np.ndarray | None = None

    def __call__(self, step: int, x: np.ndarray, xd: np.ndarray, xdd: np.ndarray) -> None:
        """Record step ``step`` of the integrated state ``(x, x', x'')``."""
        p = self.phys
        q = p.position(x, step)
        if self.offset is not None:
            q = q + self.offset(step)
        qd, qdd = p.rate(xd, step, 1), p.rate(xdd, step, 2)
        self.t.append(step * self.dt)
        self.d.append(np.asarray(p.O @ q))
        self.v.append(np.asarray(p.O @ qd))
        self.a.append(np.asarray(p.O @ qdd))
        rhs = p.b if p.motion is None else p.b + p.motion.e * p.motion.g[step, 0]
        self.residual.append(float(np.abs(p.A @ q - rhs).max(initial=0.0)))
        self.qmax = max(self.qmax, float(np.abs(q).max(initial=0.0)))
        self.energy.append([0.5 * float(xd @ (self.M_x @ xd)), 0.5 * float(x @ (self.K_x @ x)),
                            0.0, 0.0])
        if self.forces is not None:
            Q = p.M @ qdd + p.K @ q - p.B @ p.f[step]
            if p.C is not None:
                Q = Q + p.C @ qd
            self.lam.append(self.forces(np.asarray(Q)))
        if self.fields is not None and self.fields.wants(step):
            self.fields.add(step, q)
        self.last = q

    def on_work(self, step: int, work: Work) -> None:
        """Put the accumulated work and dissipation beside the energies of step ``step``."""
        self.energy[-1][2] = work.external
        self.energy[-1][3] = work.dissipated

    def arrays(self) -> dict[str, np.ndarray]:
        """The records as arrays (``t``, ``d``, ``v``, ``a``, ``lam``, ``residual``,
        ``energy``, ``field_t``, ``field``; ``field`` a
        :class:`~substruct.analysis.transient.fields.StoredFields` when the fields went to a
        sink)."""
        n_out = self.phys.O.shape[0]
        m = self.phys.A.shape[0]

        def stack(rows: list[np.ndarray], width: int) -> np.ndarray:
            return np.vstack(rows) if rows else np.zeros((len(self.t), width))

        n = self.phys.M.shape[0]
        stored: np.ndarray | StoredFields = np.zeros((0, n)) if self.fields is None else \
            self.fields.stored()
        return {"t": np.asarray(self.t), "d": stack(self.d, n_out), "v": stack(self.v, n_out),
                "a": stack(self.a, n_out),
                "lam": stack(self.lam, m) if self.forces is not None else np.zeros((0, m)),
                "residual": np.asarray(self.residual), "energy": np.asarray(self.energy),
                "field_t": np.zeros(0) if self.fields is None else self.fields.t,
                "field": cast(np.ndarray, stored)}


def energy_change(energy: np.ndarray) -> tuple[float, float]:
    r"""``(change, gain)`` of the balance :math:`E_k = T_k + V_k - W_k + D_k` (``energy``:
    ``n x 4``, the columns of :class:`Recorder`) relative to the largest energy:
    :math:`\max_k |E_k - E_0| / s` and :math:`\max_k (E_k - E_0) / s`,
    :math:`s = \max |\text{energy}|` (both 0 without samples)."""
    e = np.asarray(energy, dtype=float)
    if e.shape[0] == 0:
        return 0.0, 0.0
    E = e[:, 0] + e[:, 1] - e[:, 2] + e[:, 3]
    scale = max(float(np.abs(e).max()), 1e-300)
    return float(np.abs(E - E[0]).max() / scale), float((E - E[0]).max() / scale)


#: The relative size of a response that is the rounding of a zero one: a load on a coordinate
#: the constraints hold leaks into the others by about ``eps`` of its own response, whose
#: energies are about ``eps^2`` of the load's; :func:`roundoff_energy` allows 1000 times that.
ROUNDOFF_RESPONSE = 1e3 * np.finfo(float).eps


def roundoff_energy(K: sp.sparray, M: sp.sparray, B: sp.sparray, f: np.ndarray,
                    dt: float) -> float:
    r"""The energy below which a run's whole response is rounding:
    :math:`(10^3 \epsilon)^2 F^2 \min(1/\|K\|_\infty, h^2/\|M\|_\infty)`, ``F`` the largest
    entry of :math:`|B| \max_k |f_k|` (``f``: the load samples, one row a step; ``1/0`` is
    infinite).  Since :math:`\lambda_{max}(K) \le \|K\|_\infty`, :math:`F^2/\|K\|_\infty`
    is at most twice the static energy :math:`F^T K^{-1} F / 2` of the largest load, and
    :math:`(F h)^2/\|M\|_\infty` twice the kinetic energy of its first step ``h`` on the
    mass: a response the loads drive has more than the bound unless it is
    :math:`10^3 \epsilon` of theirs (a load on a held coordinate, whose response is exactly 0,
    is computed as about :math:`10^{-50}` of the load's energy).  0 without loads."""
    if f.size == 0 or B.shape[1] == 0:
        return 0.0
    F = float(np.max(abs(sp.csr_array(B)) @ np.abs(f).max(axis=0), initial=0.0))
    k, m = (float(np.max(abs(sp.csr_array(X)).sum(axis=1), initial=0.0)) for X in (K, M))
    bound = min(1.0 / k if k > 0 else np.inf, dt * dt / m if m > 0 else np.inf)
    return float(ROUNDOFF_RESPONSE ** 2 * F * F * bound) if np.isfinite(bound) else 0.0


def require_energy_balance(what: str, form: str, energy: np.ndarray, s: Scheme,
                           tolerance: float, floor: float = 0.0) -> float:
    r"""Hold the energy balance of one run to ``tolerance``; return its change.

    The energies are those of the integrated coordinates (:class:`Recorder`) and ``W``
    counts the work of every load of the integrated equations (the effective loads of a moving
    ground, of a nonhomogeneous constraint, the reactions of moving supports;
    :class:`~substruct.analysis.transient.integrators.Work`).  Newmark's average acceleration
    (and generalized-alpha with :math:`\rho_\infty = 1`) keeps :math:`T + V - W + D`
    constant to rounding, so its change relative to the largest energy is held to
    ``tolerance``.  Generalized-alpha with :math:`\rho_\infty < 1` satisfies the equation at
    shifted instants and dissipates numerically; measured in :math:`T + V` at the nodes the
    balance is not even monotone (a mode at :math:`\omega h = 10^3` released from rest,
    :math:`\rho_\infty = 0`: it its balance rises by 1.0 of the largest energy within five steps),
    so no bound derived from the scheme applies and its change is reported, not held.
    A run whose energies are all at most ``floor`` (:func:`roundoff_energy`) is the rounding
    of a zero response: its change is reported, not held.

    Raises:
        CheckError: the change of an energy-conserving scheme exceeds ``tolerance``; one
            line, e.g. ``transient: energy balance T + V - W + D of
            generalized-inverse changes by 1.5e+00 of the largest energy (tolerance 1e-06)``.
    """
    if not np.all(np.isfinite(energy)):
        # histories that overflowed: refused by the run's own check of non-finite results
        # (substruct.analysis.checks.require_finite), which names them
        return float("nan")
    change = energy_change(energy)[0]
    exact = s.alpha_m == s.alpha_f and s.beta == 0.25 and s.gamma == 0.5
    rounding = energy.size > 0 and float(np.abs(energy).max()) <= floor
    if exact and not rounding and not change <= tolerance:
        raise CheckError(f"{what}: energy balance T + V - W + D of {form} changes by "
                         f"{change:.1e} of the largest energy (tolerance {tolerance:g})")
    return change
