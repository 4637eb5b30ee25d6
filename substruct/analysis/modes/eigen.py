r"""The eigen entry point: coupled modes of an assembled model with their cross-checks.

:func:`modes` solves the constrained free vibration (eqs 23-34)

.. math::  (\lambda^2 M + \lambda C + K)\, u = A^T \mu, \qquad A u = 0,

by a main formulation and the check formulations, and returns one
:class:`~substruct.analysis.results.Modes`.  How it is solved is a strategy chosen here, in
:func:`choose_solver`, and nowhere else:

* ``"dense"``: every root of the balanced pencils
  (:func:`substruct.analysis.modes.dense.coupled_modes`; the generalized-inverse one is the
  paper's eqs 28-34);
* ``"sparse"``: the lowest roots of an undamped model, computed by the null-space form with
  the others as residual checks (:mod:`substruct.analysis.modes.production`);
* ``"sparse-damped"``: the lowest roots of a damped model by shift-invert Arnoldi on the
  first-order pencil of the null-space form
  (:func:`substruct.analysis.modes.damped.damped_sparse_modes`), the others again as
  residual checks (:mod:`substruct.analysis.modes.production`);
* ``"amls"``: the modes of an undamped model by automated multilevel substructuring on the
  null-space eliminated pencil, each checked by its residual
  (:mod:`substruct.analysis.modes.amls`); only when asked for.

It fails with :class:`~substruct.analysis.errors.CheckError` when a check disagrees with the
main formulation by more than ``tolerance``, and with ``ValueError`` on input it cannot analyse.
:mod:`substruct.analysis.api` is the front door that also holds the receptance sweep; the
modal receptance and the modal transient call :func:`modes` from here.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np
import scipy.sparse as sp

from substruct.analysis.checks import (
    check_methods,
    holds_every_coordinate,
    modes_agreement,
    require_agreement,
)
from substruct.analysis.modes.dense import FORMULATIONS, coupled_modes
from substruct.analysis.errors import INPUT_ERRORS, AnalysisInputError
from substruct.analysis.events import Phase
from substruct.analysis.modes.krylov import (
    DENSE_FREE,
    check_inputs,
    eliminate,
    free_coordinates,
    krylov_size,
)
from substruct.analysis.modes.production import production_modes
from substruct.analysis.results import DEFAULT_TOLERANCE, Modes
from substruct.analysis.system import ConstrainedSystem, ModesOptions
from substruct.linalg.system import Matrix
from substruct.analysis.modes.sparse import has_damping, sparse_coupled_modes
from substruct.linalg.nullspace import Elimination
from substruct.vocabulary import GENERALIZED_INVERSE, NULL_SPACE, SOLVERS

__all__ = ["SOLVERS", "SPARSE_ABOVE", "SolverChoice", "choose_solver", "modes", "system_modes"]


#: ``solver="auto"`` takes the sparse path above this many coordinates, damped or not: the dense
#: state-space pencil (eqs 28-34) of a 605-coordinate free-free rod took 62 s on two busy
#: cores, the sparse path 1 s with the same frequencies to 1e-13.
SPARSE_ABOVE = 400


@dataclass(frozen=True)
class SolverChoice:
    """The strategy :func:`choose_solver` picked.

    Attributes:
        strategy: ``"dense"``, ``"sparse"``, ``"sparse-damped"`` or ``"amls"``.
        note: why it is not the one asked for (empty if it is).
        elimination: the master-slave elimination of ``A`` computed to decide (reused by the
            sparse solvers), or ``None``.
    """

    strategy: str
    note: str = ""
    elimination: Elimination | None = None

    @property
    def label(self) -> str:
        """``strategy``, with the note in parentheses if there is one."""
        return f"{self.strategy} ({self.note})" if self.note else self.strategy


def choose_solver(M: sp.sparray | np.ndarray, C: sp.sparray | np.ndarray | None,
                  A: sp.sparray | np.ndarray | None, count: int | None,
                  solver: str = "auto", full_checks: bool = False) -> SolverChoice:
    """The strategy for the lowest ``count`` modes of a model: the one place where it is chosen.

    ``solver``: ``"dense"`` always dense; ``"sparse"`` sparse (``"sparse-damped"`` if ``C`` has
    nonzeros); ``"amls"`` AMLS (never chosen otherwise); ``"auto"`` dense up to :data:`SPARSE_ABOVE` coordinates and sparse above.  An
    undamped sparse choice whose constraints leave too few free coordinates for ``count``
    roots and a Krylov basis around them (:func:`substruct.analysis.modes.krylov.krylov_size`;
    ARPACK fails there) stays sparse, the null-space pencil solved densely, when that pencil
    has at most :data:`~substruct.analysis.modes.krylov.DENSE_FREE` coordinates (and
    ``full_checks`` does not ask for every formulation's eigensolve); otherwise it falls back
    to dense, with a note saying so, as when every mode is asked for (``count`` ``None``).  (The damped sparse solver takes pencils that small
    densely itself.)

    Raises:
        ValueError: an unknown ``solver``; bad shapes or an empty constraint row.
    """
    if solver not in SOLVERS:
        raise ValueError(f"unknown solver {solver!r}; expected one of {', '.join(SOLVERS)}")
    if solver == "amls":
        return SolverChoice("amls")
    n = M.shape[0]
    if solver == "dense" or (solver == "auto" and n <= SPARSE_ABOVE):
        return SolverChoice("dense")
    if count is None:
        return SolverChoice("dense", "sparse solvers compute the lowest count modes; all asked")
    if has_damping(C):
        return SolverChoice("sparse-damped")
    Ms, _, As, k = check_inputs(M, M, A, count)
    el = eliminate(Ms, As)
    free = free_coordinates(el, Ms)
    try:
        krylov_size(k, free)
    except AnalysisInputError:
        if el.T.shape[1] <= DENSE_FREE and not full_checks:
            return SolverChoice("sparse", f"{el.T.shape[1]} coordinates left by the "
                                          f"constraints: their pencil solved densely", el)
        return SolverChoice("dense", f"sparse asked, but {free} free coordinates are too few "
                                     f"for {k} modes and a Krylov basis")
    return SolverChoice("sparse", "", el)


def _sparse(M: sp.sparray | np.ndarray, C: sp.sparray | np.ndarray | None,
            K: sp.sparray | np.ndarray, A: sp.sparray | np.ndarray | None, count: int,
            method: str, choice: SolverChoice) -> Modes:
    n = K.shape[0]
    As = sp.csr_array((0, n)) if A is None or np.size(A) == 0 else sp.csr_array(A, dtype=float)
    Cs = None if C is None else sp.csr_array(C, dtype=float)
    try:
        return sparse_coupled_modes(sp.csr_array(M, dtype=float), sp.csr_array(K, dtype=float),
                                    As, count, method=method, C=Cs,
                                    elimination=choice.elimination)
    except INPUT_ERRORS as err:
        text = " ".join(str(err).split()).replace("(use the dense coupled_modes)",
                                                   "(use solver: dense)")
        raise AnalysisInputError(f"sparse eigensolver: {text}") from None


def _amls(system: ConstrainedSystem, count: int | None, opts: ModesOptions) -> Modes:
    """The ``"amls"`` strategy: modes, residual check (held to the tolerance) and label."""
    from substruct.analysis.modes.amls import AmlsOptions, amls_coupled_modes  # when used

    amls = opts.amls if opts.amls is not None else AmlsOptions()
    checks = check_methods(opts.method, opts.checks) if opts.checks else []
    try:
        main, agreement, label = amls_coupled_modes(system.M, system.C, system.K, system.A,
                                                    count, amls, checks, opts.events)
    except INPUT_ERRORS as err:
        raise AnalysisInputError(f"amls eigensolver: {' '.join(str(err).split())}") from None
    require_agreement(opts.what, main.method, agreement, opts.tolerance)
    return dataclasses.replace(main, agreement=agreement, solver=label,
                               tolerance=float(opts.tolerance))


def modes(system: ConstrainedSystem | Matrix, *args: Any, options: ModesOptions | None = None,
          **kwargs: Any) -> Modes:
    r"""Coupled modes of ``M u'' + C u' + K u = 0`` under ``A u = 0``, with their cross-checks.

    The call is ``modes(system, count=None, *, options=None)`` with a
    :class:`~substruct.linalg.system.ConstrainedSystem` and
    :class:`~substruct.analysis.system.ModesOptions` (:func:`system_modes`, which see).

    The compatibility form ``modes(M, C, K, A, count=None, *, method=..., checks=(),
    solver="auto", tolerance=1e-6, what="modes", full_checks=False, events=None)`` takes the
    matrices and the options loose, as before the system type: it builds both and calls
    :func:`system_modes`.

    Examples
    --------
    Two unit masses, the first on a spring of 2 to the ground, a spring of 1 between them, held
    together by ``q_1 = q_2``: one mode, a mass of 2 on a spring of 2 (``omega = 1``), checked
    by the null-space form.

    >>> import numpy as np
    >>> from substruct.analysis.api import modes
    >>> from substruct.analysis.system import ConstrainedSystem, ModesOptions
    >>> s = ConstrainedSystem.of(np.eye(2), None, [[3.0, -1.0], [-1.0, 1.0]], [[1.0, -1.0]])
    >>> res = modes(s, 1, options=ModesOptions(checks=["null-space"]))
    >>> np.round(res.omega, 6), res.solver
    (array([1.]), 'dense')
    >>> bool(res.agreement["null-space"] < 1e-9)
    True
    """
    if isinstance(system, ConstrainedSystem):
        return system_modes(system, *args, options=options, **kwargs)
    if options is not None:
        raise TypeError("modes(): options= goes with a ConstrainedSystem; the matrix form takes "
                        "the options as keywords")
    return _compatible_modes(system, *args, **kwargs)


def _compatible_modes(M: Matrix, C: Matrix | None, K: Matrix, A: Matrix | None,
                      count: int | None = None, *, method: str = GENERALIZED_INVERSE,
                      checks: Sequence[str] = (), solver: str = "auto",
                      tolerance: float = DEFAULT_TOLERANCE, what: str = "modes",
                      full_checks: bool = False, events: Phase | None = None) -> Modes:
    """The loose-argument form of :func:`modes`: the options, then the system, then the call."""
    options = ModesOptions(method=method, checks=checks, solver=solver, tolerance=tolerance,
                           what=what, full_checks=full_checks, events=events)
    return system_modes(ConstrainedSystem.of(M, C, K, A), count, options=options)


def system_modes(system: ConstrainedSystem, count: int | None = None, *,
                 options: ModesOptions | None = None) -> Modes:
    r"""Coupled modes of ``M u'' + C u' + K u = 0`` under ``A u = 0``, with their cross-checks.

    .. math::  (\lambda^2 M + \lambda C + K)\, u = A^T \mu, \qquad A u = 0
               \qquad \text{(eqs 23-34)}

    The strategy (dense, sparse, sparse-damped) is :func:`choose_solver`'s.  Dense: the main
    formulation is ``method``, each check formulation is solved by the same strategy and
    compared with it (:func:`substruct.analysis.checks.modes_agreement`).  Sparse and
    sparse-damped: the production path (:func:`substruct.analysis.modes.production.production_modes`),
    whatever ``method`` names: the numbers from the null-space form (``method`` of the result
    ``"null-space/sparse"``), the KKT and generalized-inverse forms as residual checks
    (``agreement`` keys ``"kkt-residual"`` and ``"generalized-inverse-residual"``; a check
    skipped as too costly is named in ``solver``); ``full_checks`` solves the named method and
    checks in full instead (the sparse eigensolves of each formulation, compared).  On a
    damped model the sparse ``null-space`` and ``generalized-inverse`` are one pencil, so
    with ``full_checks`` neither is reported as a check of the other (``kkt`` is an
    independent one).

    Args:
        system: ``M``, ``C``, ``K`` (``M`` may be singular on massless coordinates, eq 6) and
            the rows ``A`` of any rank (:class:`~substruct.linalg.system.ConstrainedSystem`).
        count: the lowest ``count`` modes (all if ``None``; the sparse solvers need a count).
        options: the main formulation ``method``, the ``checks``, the ``solver``
            (:func:`choose_solver`), the ``tolerance`` (the largest relative eigenvalue
            disagreement a check may have), ``what`` (the name in error messages),
            ``full_checks`` and ``events`` (:class:`~substruct.analysis.system.ModesOptions`;
            its defaults if ``None``).

    Returns:
        The main formulation's :class:`~substruct.analysis.results.Modes`, with ``agreement``
        (check -> figure), ``solver`` (the strategy, and why if it fell back) and
        ``tolerance`` filled in; eigenvalues and shapes complex, whatever the strategy.

    Raises:
        CheckError: a check disagrees by more than ``tolerance``.
        AnalysisInputError: a model the solver cannot take (a motion with no mass, stiffness
            or constraint; more modes than a sparse solver can give).
    """
    opts = options if options is not None else ModesOptions()
    method, checks, solver = opts.method, opts.checks, opts.solver
    tolerance, what, full_checks, events = opts.tolerance, opts.what, opts.full_checks, \
        opts.events
    M, C, K, A = system.M, system.C, system.K, system.A
    if not np.any(sp.csr_array(M).data):
        raise AnalysisInputError("the model has no mass (M = 0): every root is infinite, "
                                 "there is no mode to compute")
    choice = choose_solver(M, C, A, count, solver, full_checks)
    if choice.strategy == "amls":
        return _amls(system, count, opts)
    others = check_methods(method, checks)
    if choice.strategy == "sparse-damped":  # one pencil for both: no check of one by the other
        same = {NULL_SPACE, GENERALIZED_INVERSE}
        others = [m for m in others if not (m in same and method in same)]

    def solve(formulation: str) -> Modes:
        if events is not None:
            kind = "dense-eigen" if choice.strategy == "dense" else "sparse-eigen"
            events(kind, f"{what} ({formulation}): {choice.strategy} eigen solve", M.shape[0])
        if choice.strategy == "dense":
            return coupled_modes(M, C, K, A, formulation, count)
        assert count is not None  # choose_solver is dense when every mode is asked
        return _sparse(M, C, K, A, count, formulation, choice)

    if choice.strategy != "dense" and not full_checks:
        assert count is not None
        if events is not None:
            events("sparse-eigen", f"{what}: sparse factorization and shift-invert eigen solve",
                   M.shape[0])
        damped = choice.strategy == "sparse-damped"
        try:
            main, agreement, note = production_modes(
                M, K, A, count, C=C if damped else None, elimination=choice.elimination)
        except INPUT_ERRORS as err:
            raise AnalysisInputError(f"sparse eigensolver: {' '.join(str(err).split())}") \
                from None
        require_agreement(what, main.method, agreement, tolerance)
        notes = "; ".join(text for text in (choice.note, note) if text)
        solver_label = f"{choice.strategy} ({notes})" if notes else choice.strategy
    else:
        main = solve(method)
        agreement = {m: modes_agreement(solve(m), main) for m in others}
        require_agreement(what, method, agreement, tolerance)
        solver_label = main.solver
        if choice.note or not main.solver or main.solver == choice.strategy:
            solver_label = choice.label
    n = M.shape[0]
    if not len(main.omega) and n and system.m and holds_every_coordinate(A, None, n):
        solver_label += f"; no free coordinate: the constraints hold all {n} coordinates"
    # one type, one set of scalar types whatever the strategy: complex roots and shapes (the
    # undamped sparse solvers compute real ones), real frequencies, ratios and residuals
    return dataclasses.replace(
        main, eigenvalues=np.asarray(main.eigenvalues, dtype=complex),
        omega=np.asarray(main.omega, dtype=float),
        damping_ratio=np.asarray(main.damping_ratio, dtype=float),
        shapes=np.asarray(main.shapes, dtype=complex),
        residual=np.asarray(main.residual, dtype=float),
        spurious=np.asarray(main.spurious, dtype=complex),
        spurious_reason=list(main.spurious_reason), agreement=agreement, solver=solver_label,
        tolerance=float(tolerance))


