r"""Constrained transient response (paper eqs 5 and 10): time histories of coupled
substructures,

.. math::  M \ddot q + C \dot q + K q = P(t) + Q^c, \qquad A q = b, \qquad
           Q^c = M \ddot q - (P - C \dot q - K q) \quad \text{(eq 5)},

integrated by Newmark's average acceleration or the generalized-alpha method
(:mod:`substruct.analysis.transient.integrators`) in one of three forms:

* ``generalized-inverse``: every coordinate is integrated and the acceleration of each step
  is eq (5) with the effective matrix :math:`S` of the step in the place of :math:`M`
  (:math:`S` is definite where :math:`M` is semidefinite, eq 10; where a massless motion is
  held by the constraints alone, :math:`S + A^T D A`,
  :mod:`substruct.analysis.transient.effective`); displacements, velocities
  and accelerations are projected onto :math:`A q = b` with the :math:`S`-orthogonal projector
  at every step, so the constraints hold to rounding over any number of steps;
* ``null-space``: :math:`q = T p + q_p` with ``T`` from the master-slave elimination
  (:func:`substruct.linalg.nullspace.master_slave`), and :math:`T^T M T \ddot p + \dots
  = T^T (P - K q_p)`;
* ``"modal"``: superposition of the coupled modes (:func:`substruct.analysis.api.modes`) with
  a static correction for the truncated ones (:mod:`substruct.analysis.transient.modal`).

The initial acceleration is eq (10) (:func:`substruct.analysis.formulations.projection.constrained_acceleration`):
consistent with the constraints and with the massless coordinates of the absorbers.  Each
form factorizes its effective matrix once for the run.  The forms named in ``checks`` are
computed as well and their agreement held to ``tolerance``
(:func:`substruct.analysis.checks.require_agreement`), and each run's energy balance
:math:`T + V - W + D` to the same tolerance
(:func:`substruct.analysis.transient.record.require_energy_balance`).
"""

from __future__ import annotations

import dataclasses
from typing import Callable, Mapping, Sequence

import numpy as np
import scipy.sparse as sp

from substruct.analysis.errors import AnalysisInputError
from substruct.analysis.checks import (
    check_methods,
    receptance_difference,
    require_agreement,
)
from substruct.analysis.transient.integrators import (
    Restart,
    Scheme,
    StepControl,
    StepState,
    effective_matrix,
    integrate,
)
from substruct.analysis.modes.krylov import eliminate
from substruct.analysis.formulations.projection import constrained_acceleration
from substruct.analysis.transient.base import (BaseMotion, Motion, ground_history, influence,
                                               load_acceleration)
from substruct.analysis.transient.effective import (
    constraint_correction,
    effective_solver,
    spd_solver,
)
from substruct.analysis.transient.fields import FieldStore, field_steps
from substruct.analysis.transient.loads import for_scheme
from substruct.analysis.transient.initial import (
    InitialStateError,
    check_initial,
    massless_velocity,
    static_state,
)
from substruct.analysis.transient.modal import modal_run
from substruct.analysis.transient.record import (
    Physical,
    Recorder,
    constraint_force_solver,
    require_energy_balance,
    roundoff_energy,
)
from substruct.analysis.transient.options import (
    InitialConditions,
    LoadHistory,
    TransientOptions,
    TransientOutputs,
)
from substruct.analysis.transient.results import Transient
from substruct.linalg.constraints import independent_rows, particular_solution
from substruct.linalg.factorize import factorizer
from substruct.linalg.scaling import (
    equilibrate,
    mass_column_scale,
    massless_coordinates,
)
from substruct.vocabulary import GENERALIZED_INVERSE, MODAL, NULL_SPACE, TRANSIENT_FORMS

__all__ = ["TRANSIENT_FORMS", "DENSE_STEP", "LoadHistory", "InitialConditions",
           "TransientOutputs", "TransientOptions", "transient", "direct_run", "initial_state"]

#: Up to this many coordinates the step runs on dense arrays (an explicit inverse of S).
DENSE_STEP = 200


def _small(*mats: sp.sparray | np.ndarray | None) -> list[np.ndarray | None]:
    """Dense copies of small matrices (``None`` kept)."""
    return [None if m is None else np.asarray(sp.csr_array(m).toarray()) if sp.issparse(m)
            else np.asarray(m, float) for m in mats]


def _kkt_acceleration(M: sp.csr_array, A: sp.csr_array, target: np.ndarray,
                      force: np.ndarray) -> np.ndarray | None:
    r"""Eq (10) by one sparse factorization: :math:`M a + A_k^T \lambda = F`,
    :math:`A_k a = c_k` on the independent rows (``None`` if singular: a massless coordinate
    the constraints leave undetermined)."""
    rows = independent_rows(A, col_scale=mass_column_scale(M))
    Ak = sp.csr_array(A[rows.keep])
    big = sp.block_array([[M, Ak.T], [Ak, None]], format="csc")
    try:
        x = factorizer("superlu", spd=False)(big)(np.concatenate([force, target[rows.keep]]))
    except RuntimeError:
        return None
    a = np.asarray(x[:M.shape[0]])
    return a if np.all(np.isfinite(a)) else None


def initial_state(M: sp.csr_array, K: sp.csr_array, A: sp.csr_array, load: np.ndarray,
                  d0: np.ndarray, force: Callable[[np.ndarray], np.ndarray],
                  accel: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    r"""``(d0, a0)``: the initial displacement and acceleration, consistent with
    :math:`A \ddot q = 0` and the massless coordinates.  The acceleration is eq (10)
    (:func:`substruct.analysis.formulations.projection.constrained_acceleration`, ``force(d0)`` the force
    :math:`P - C \dot q - K q`; ``accel``: :math:`A \ddot q` of a moving ground, else 0).
    Where eq (10) cannot determine a massless coordinate (one held
    by springs only, not by a constraint), its equation is algebraic, :math:`K_s q = P_s`: the
    massless rows of the displacement are put on it first (massed coordinates kept), and the
    acceleration solved with those rows differentiated twice, the load taken as locally
    constant (:math:`K_s \ddot q = 0`),

    .. math::  \begin{bmatrix} \tilde M & A^T \\ A & 0 \end{bmatrix}
               \begin{bmatrix} x \\ \lambda \end{bmatrix} =
               \begin{bmatrix} \tilde F \\ 0 \end{bmatrix}

    (:math:`\tilde M`: ``I`` then ``M`` on the massed rows and ``K`` on the massless ones).

    Raises:
        ValueError: the system is singular (a massless coordinate with no stiffness).
    """
    target = np.zeros(A.shape[0]) if accel is None else np.asarray(accel, dtype=float)
    try:
        return d0, constrained_acceleration(M, A, target, force(d0))
    except MemoryError:  # its n x m gain is too large to copy: the same eq 10 as a sparse KKT
        a = _kkt_acceleration(M, A, target, force(d0))
        if a is not None:
            return d0, a
    except ValueError:
        pass
    s = massless_coordinates(M)
    keep: np.ndarray | list[int] = (independent_rows(A, col_scale=mass_column_scale(M)).keep
                                    if A.shape[0] else [])
    Ak = sp.csr_array(A[keep]) if A.shape[0] else A
    on, off = sp.diags_array(s.astype(float)), sp.diags_array((~s).astype(float))
    zero = target[keep] if A.shape[0] else np.zeros(0)

    def kkt(rows: sp.sparray, rhs: np.ndarray, held: np.ndarray) -> np.ndarray:
        big = sp.block_array([[rows, Ak.T], [Ak, None]], format="csc")
        try:
            x = factorizer("superlu", spd=False)(big)(np.concatenate([rhs, held]))
        except RuntimeError:
            raise AnalysisInputError("initial state (eq 10): a massless coordinate held neither by a "
                             "constraint nor by a stiffness") from None
        return np.asarray(x[:M.shape[0]])

    d = d0 + kkt(off + on @ K, np.where(s, load - K @ d0, 0.0), 0.0 * zero)  # A d kept
    return d, kkt(off @ M + on @ K, np.where(s, 0.0, force(d)), zero)


def restarter(M: sp.sparray | np.ndarray, C: sp.sparray | np.ndarray | None,
              K: sp.sparray | np.ndarray, B: sp.sparray | np.ndarray, A: sp.csr_array,
              accel: Callable[[int], np.ndarray] | None = None) -> Restart:
    r"""``restart(step, d, v, f)``: the acceleration of eq (10) for the state ``(d, v)`` under
    the load :math:`B f` (:func:`initial_state`; ``accel(step)``: :math:`A \ddot q` of a
    moving ground, else 0): where a load jumps, the integration restarts as at ``t = 0``."""
    Ms, Ks, Bs = (sp.csr_array(X, dtype=float) for X in (M, K, B))
    Cs = None if C is None else sp.csr_array(C, dtype=float)

    def restart(step: int, d: np.ndarray, v: np.ndarray, f: np.ndarray) -> np.ndarray:
        load = np.asarray(Bs @ f)

        def force(x: np.ndarray) -> np.ndarray:
            return np.asarray(load - Ks @ x - (Cs @ v if Cs is not None else 0.0))

        return initial_state(Ms, Ks, A, load, d, force,
                             None if accel is None else accel(step))[1]

    return restart


def direct_run(phys: Physical, form: str, s: Scheme, h: float, n_steps: int, d0: np.ndarray,
               v0: np.ndarray, a0: np.ndarray, opts: TransientOptions,
               fields: FieldStore | None = None) -> Recorder:
    """One run of the generalized-inverse or the null-space form (module docstring); the
    fields of the steps ``fields`` names go to it."""
    M, C, K, B = phys.M, phys.C, phys.K, phys.B
    mo = phys.motion
    n = M.shape[0]
    rows = independent_rows(phys.A, col_scale=mass_column_scale(M))
    forces = constraint_force_solver(phys.A, rows.keep) if opts.forces else None
    if form == GENERALIZED_INVERSE:
        if n <= DENSE_STEP:
            M, C, K, B = _small(M, C, K, B)  # type: ignore[assignment]
        eff = effective_solver(effective_matrix(M, C, K, s, h), phys.A, opts.factorization)
        corr = (constraint_correction(eff.S, eff.solve, phys.A, phys.b, phys.motion)
                if phys.A.shape[0] else None)
        # the generalized-inverse form integrates q itself: no particular solution to add
        rec = Recorder(dataclasses.replace(phys, qp=None), M, K, h, forces, fields)
        ground = None if mo is None else (lambda k: mo.e * mo.g[k, 2])
        restart = restarter(phys.M, phys.C, phys.K, phys.B, phys.A, ground)
        if corr is not None and corr.held:  # every coordinate prescribed: A a = e g'' fixes a
            held = corr

            def restart(step: int, d: np.ndarray, v: np.ndarray, f: np.ndarray) -> np.ndarray:
                return held.apply(d, 0.0 if ground is None else ground(step))

            a0 = restart(0, d0, v0, phys.f[0])
        integrate(M, C, K, B, phys.loads, StepState(d0, v0, a0), rec,
                  StepControl(s, h, n_steps, eff.solve, opts.every), correction=corr,
                  restart=restart)
        return rec
    el = eliminate(sp.csr_array(M), phys.A)
    T = sp.csr_array(el.T)
    qp = phys.qp if phys.qp is not None else np.zeros(n)
    Mt, Kt = T.T @ M @ T, T.T @ K @ T
    Ct = None if C is None else T.T @ C @ T
    cols = [T.T @ sp.csc_array(B), sp.csc_array(-(T.T @ (K @ qp))[:, None])]
    extra = [np.ones((phys.f.shape[0], 1))]
    if mo is not None:  # q = T p + q_p + r g: the effective loads -M r g'' - C r g' - K r g
        cols += [sp.csc_array(-(T.T @ (X @ mo.r))[:, None]) for X in (M, K, C) if X is not None]
        extra.append(mo.load_columns(len(cols) - 2))
        d0, v0, a0 = (x - mo.r * mo.g[0, k] for k, x in enumerate((d0, v0, a0)))
    loads = phys.loads.widened(np.hstack(extra))
    ft = loads.f
    Bt = sp.hstack(cols).tocsr()
    p0, pv0 = d0[el.masters] - qp[el.masters], v0[el.masters]
    pa0 = a0[el.masters]
    if not massless_coordinates(Mt).any() and Mt.shape[0]:  # independent of eq 10
        r0 = Bt @ ft[0] - Kt @ p0 - (Ct @ pv0 if Ct is not None else 0.0)
        pa0 = spd_solver(Mt if Mt.shape[0] > DENSE_STEP else Mt.toarray(), "superlu")(r0)
    if Mt.shape[0] <= DENSE_STEP:
        Mt, Ct, Kt, Bt = _small(Mt, Ct, Kt, Bt)  # type: ignore[assignment]
    S = effective_matrix(Mt, Ct, Kt, s, h)
    solve = spd_solver(S, opts.factorization)
    nphys = Physical(phys.M, phys.C, phys.K, phys.B, phys.f, phys.A, phys.b, phys.O, T, qp,
                     phys.motion, phys.pairs)
    rec = Recorder(nphys, Mt, Kt, h, forces, fields)
    integrate(Mt, Ct, Kt, Bt, loads, StepState(p0, pv0, pa0), rec,
              StepControl(s, h, n_steps, solve, opts.every),
              restart=restarter(Mt, Ct, Kt, Bt, sp.csr_array((0, Mt.shape[0]))))
    return rec


def _difference(a: Recorder, b: Recorder) -> float:
    """``max |y_a - y_b| / max |y_b|`` over the output displacements and the final field."""
    ra, rb = a.arrays(), b.arrays()
    out = receptance_difference(ra["d"], rb["d"]) if rb["d"].size else 0.0
    last = 0.0
    if a.last is not None and b.last is not None:
        last = receptance_difference(a.last, b.last)
    return max(out, last)


def transient(M: sp.sparray | np.ndarray, C: sp.sparray | np.ndarray | None,
              K: sp.sparray | np.ndarray, A: sp.sparray | np.ndarray | None,
              b: np.ndarray | None, load: LoadHistory, outputs: TransientOutputs, *,
              constraint_labels: Sequence[str] = (), initial: InitialConditions | None = None,
              options: TransientOptions | None = None) -> Transient:
    r"""Time histories of :math:`M \ddot q + C \dot q + K q = B f(t) + Q^c`, :math:`A q = b`
    (eqs 5, 10), by ``options.method``, checked by ``options.checks``.

    Args:
        M, C, K: ``n x n`` (``M`` may be singular on massless coordinates; ``C`` may be
            ``None``).
        A, b: ``m x n`` constraint rows and their right-hand side (``None``: none, ``0``);
            ``constraint_labels`` the names of the rows.
        load: :class:`~substruct.analysis.transient.options.LoadHistory`, the loads
            :math:`P(t_k) = B f_k` at :math:`t_k = k\, dt`, ``k = 0 .. n_steps``, their jumps
            and a moving ground.
        outputs: :class:`~substruct.analysis.transient.options.TransientOutputs`, the rows
            recorded and their names, and where the full fields go (``outputs.fields``).
        initial: :class:`~substruct.analysis.transient.options.InitialConditions` (``None``:
            at rest, :math:`q_0 = 0`).
        options: :class:`~substruct.analysis.transient.options.TransientOptions`: the form,
            its checks and their tolerance, the integrator, what is recorded.

    Returns:
        :class:`~substruct.analysis.transient.results.Transient` of the main form, with the
        checks' ``agreement``.

    Raises:
        ValueError: bad input (inconsistent initial conditions, massless coordinates the
            constraints leave undetermined).
        CheckError: a check disagrees by more than ``options.tolerance``, or a run's energy
            balance changes by more (gains, for generalized-alpha with
            :math:`\rho_\infty < 1`).

    Examples:
        A unit mass on a unit spring released from ``q = 1``: :math:`q(t) = \cos t`.

        >>> import numpy as np
        >>> load = LoadHistory(np.zeros((1, 0)), np.zeros((101, 0)), 0.01, 100)
        >>> r = transient(np.eye(1), None, np.eye(1), None, None, load,
        ...               TransientOutputs(np.eye(1), ["q"]),
        ...               initial=InitialConditions(d0=np.ones(1)))
        >>> bool(abs(r.displacement[-1, 0] - np.cos(1.0)) < 1e-4)
        True
    """
    opts = options or TransientOptions()
    init = initial or InitialConditions()
    B, dt, n_steps, base = load.B, load.dt, load.n_steps, load.base
    method, tolerance = opts.method, opts.tolerance
    d0, v0, static = init.d0, init.v0, init.static
    s = opts.scheme
    Ms, Ks = sp.csr_array(M, dtype=float), sp.csr_array(K, dtype=float)
    Cs = None if C is None or sp.csr_array(C).count_nonzero() == 0 else sp.csr_array(C)
    n = Ms.shape[0]
    A0 = sp.csr_array((0, n)) if A is None or np.size(A) == 0 else sp.csr_array(A, dtype=float)
    b0 = np.zeros(A0.shape[0]) if b is None else np.asarray(b, dtype=float).ravel()
    eq = equilibrate(A0, b0, labels=list(constraint_labels) or None)
    Ae, be = sp.csr_array(eq.A), np.asarray(eq.b)
    Bs = sp.csr_array(B, dtype=float)
    f = np.asarray(load.f, dtype=float).reshape(n_steps + 1, -1)
    O = sp.csr_array(outputs.rows, dtype=float)
    d0 = (static_state(Ks, Ae, be, np.asarray(Bs @ f[0])) if static else np.zeros(n)
          if d0 is None else np.asarray(d0, dtype=float).ravel())
    v0 = np.zeros(n) if v0 is None else np.asarray(v0, dtype=float).ravel()
    for name, vec in (("displacement", d0), ("velocity", v0)):
        if vec.shape != (n,) or not np.all(np.isfinite(vec)):
            raise InitialStateError(f"the initial {name} needs {n} finite values, got "
                                    f"{vec.size}")
    v0 = massless_velocity(Ms, Cs, Ks, A0, v0)
    motion = None
    if base is not None:
        e = np.asarray(eq.scale.apply(np.asarray(base.rows, dtype=float)))
        g = ground_history(base.kind, base.values, s, dt, base.rate0, base.accel0)
        if g.shape[0] != n_steps + 1 or e.shape != be.shape:
            raise ValueError(f"the ground motion has {g.shape[0]} samples and {e.size} rows "
                             f"for {n_steps + 1} instants and {be.size} constraint rows")
        motion = Motion(e=e, g=g, r=influence(Ks, Ae, e), load=load_acceleration(g, s))
        d0, v0 = d0 + motion.r * g[0, 0], v0 + motion.r * g[0, 1]
    bt = be if motion is None else be + motion.e * motion.g[0, 0]
    vt = 0.0 * be if motion is None else motion.e * motion.g[0, 1]
    try:
        check_initial(Ae, d0, v0, bt, vt)
    except InitialStateError as err:
        if motion is None:
            raise
        raise InitialStateError(f"{err}; with a moving ground the initial state is measured "
                                f"from the pseudo-static position r g(0), r g'(0) (give it "
                                f"relative to the ground)") from None
    qp = particular_solution(Ae, be) if np.any(be) else None
    qp = None if qp is None else np.asarray(qp).ravel()
    def force0(d: np.ndarray) -> np.ndarray:
        return np.asarray(Bs @ f[0] - Ks @ d - (Cs @ v0 if Cs is not None else 0.0))

    d0, a0 = initial_state(Ms, Ks, Ae, np.asarray(Bs @ f[0]), d0, force0,
                           None if motion is None else motion.e * motion.g[0, 2])
    phys = Physical(Ms, Cs, Ks, Bs, f, Ae, be, O, None, qp, motion,
                    for_scheme(load.pairs or {}, s))

    def run(form: str, store: FieldStore | None = None) -> Recorder:
        rec = (modal_run(phys, s, dt, n_steps, d0, v0, opts, store) if form == "modal" else
               direct_run(phys, form, s, dt, n_steps, d0, v0, a0, opts, store))
        require_energy_balance(opts.what, form, np.asarray(rec.energy).reshape(-1, 4), s,
                               tolerance, floor)
        return rec

    floor = roundoff_energy(Ks, Ms, Bs, f, dt)
    steps = field_steps(n_steps, opts.every, opts.field_every)
    main = run(method, FieldStore(n, steps, dt, outputs.fields) if steps.size else None)
    agreement = {m: _difference(run(m), main) for m in check_methods(method, opts.checks)}
    require_agreement(opts.what, method, agreement, tolerance)
    r = main.arrays()
    lam = np.asarray(eq.scale.apply(r["lam"].T)).T if r["lam"].size else r["lam"]
    return Transient(method=method, integrator=s.name, rho_inf=s.rho_inf, dt=dt,
                     t=r["t"], outputs=list(outputs.names), displacement=r["d"],
                     velocity=r["v"], acceleration=r["a"],
                     constraint_labels=list(constraint_labels), constraint_forces=lam,
                     constraint_residual=r["residual"],
                     drift=float(r["residual"].max(initial=0.0) / max(main.qmax, 1e-300)),
                     energy=r["energy"], snapshot_t=r["field_t"], snapshots=r["field"],
                     agreement=agreement, tolerance=float(tolerance),
                     solver=(main.basis if method == "modal" else
                             "dense step" if n <= DENSE_STEP else opts.factorization),
                     base_motion=(np.zeros((0, 3)) if motion is None else
                                  motion.g[np.rint(r["t"] / dt).astype(int)]),
                     base_influence=(np.zeros(0) if motion is None else
                                     np.asarray(O @ motion.r)))
