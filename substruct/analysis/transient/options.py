r"""What a transient analysis is given besides the system matrices, in four small objects each
checked once when made:

* :class:`LoadHistory`: the loads :math:`P(t_k) = B f_k` on the time grid
  :math:`t_k = k\, dt`, ``k = 0 .. n_steps``, the steps over which a load jumps, a moving
  ground;
* :class:`InitialConditions`: :math:`q_0`, :math:`\dot q_0`, or the constrained static state;
* :class:`TransientOutputs`: the output rows :math:`y = O q` and their names;
* :class:`TransientOptions`: how the run is made (form, checks, integrator, recording,
  factorization).

So :func:`substruct.analysis.transient.response.transient` takes the matrices and these.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import numpy as np
import scipy.sparse as sp

from substruct.analysis.results import DEFAULT_TOLERANCE
from substruct.analysis.transient.base import BaseMotion
from substruct.analysis.transient.fields import FieldSink
from substruct.analysis.transient.initial import InitialStateError
from substruct.analysis.transient.integrators import Scheme, scheme
from substruct.vocabulary import GENERALIZED_INVERSE, TRANSIENT_FORMS

__all__ = ["LoadHistory", "InitialConditions", "TransientOutputs", "TransientOptions",
           "MODAL_CUTOFF", "MODAL_RESIDUALS"]

#: The AMLS modes of the modal form: those below this multiple of the step's Nyquist
#: frequency :math:`\pi / dt`, unless told.
MODAL_CUTOFF = 1.0
#: The modal form's treatment of the modes left out: their static part, or nothing.
MODAL_RESIDUALS = ("static", "none")


def _count(name: str, value: object, least: int) -> None:
    """Refuse ``value`` unless it is an integer (not a bool) of at least ``least``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < least:
        raise ValueError(f"{name} must be an integer >= {least}, got {value!r}")


@dataclass(frozen=True)
class LoadHistory:
    r"""The loads of a transient run: :math:`P(t_k) = B f_k` at :math:`t_k = k\, dt`.

    Attributes:
        B: ``n x L``, the load distribution (``L`` may be 0).
        f: the load factors, ``(n_steps + 1) x L`` (reshaped to it).
        dt, n_steps: the constant step and the number of steps.
        pairs: step -> the load factors at its start and end, for the steps over which a load
            jumps or kinks (:func:`substruct.analysis.transient.loads.step_pairs`): the
            integration stays second order at the discontinuity.
        base: a prescribed ground motion at grounding rows of ``A``
            (:mod:`substruct.analysis.transient.base`): :math:`A q = b + e g(t)`.

    Raises:
        ValueError: ``dt`` not positive, fewer than one step.
    """

    B: sp.sparray | np.ndarray
    f: np.ndarray
    dt: float
    n_steps: int
    pairs: Mapping[int, tuple[np.ndarray, np.ndarray]] | None = None
    base: BaseMotion | None = None

    def __post_init__(self) -> None:
        if not self.dt > 0 or self.n_steps < 1:
            raise ValueError(f"need dt > 0 and at least one step, got dt={self.dt!r}, "
                             f"{self.n_steps} steps")


@dataclass(frozen=True)
class InitialConditions:
    r"""The start of a transient run.

    Attributes:
        d0, v0: the initial displacement and velocity (zero if ``None``); they must satisfy
            :math:`A q_0 = b`, :math:`A \dot q_0 = 0` (refused by the run otherwise, with the
            residual).  With a moving ground they are relative to the pseudo-static position
            :math:`r g(0)`, :math:`r \dot g(0)`.
        static: start from the constrained static state under :math:`P(0) = B f_0`,
            :math:`K q + A^T \lambda = P(0)`, :math:`A q = b(0)`
            (:func:`substruct.analysis.transient.initial.static_state`).

    Raises:
        InitialStateError: both ``d0`` and ``static`` given.
    """

    d0: np.ndarray | None = None
    v0: np.ndarray | None = None
    static: bool = False

    def __post_init__(self) -> None:
        if self.static and self.d0 is not None:
            raise InitialStateError("give the initial displacement or start from the static "
                                    "state, not both")


@dataclass(frozen=True)
class TransientOutputs:
    """The output rows of a transient run, :math:`y = O q`, and where its full fields go.

    Attributes:
        rows: ``n_out x n``, the rows :math:`O`.
        names: their names (empty, or one per row).
        fields: where the main form's fields (every ``options.field_every`` steps) go, a
            block of instants at a time as they are recorded
            (:class:`~substruct.analysis.transient.fields.FieldSink`; ``None``: kept whole).
            The result's ``snapshots`` is then a
            :class:`~substruct.analysis.transient.fields.StoredFields` (selections read back).
            The checks compare the final fields, which every run keeps; they store none.

    Raises:
        ValueError: a count of names that is neither 0 nor the number of rows.
    """

    rows: sp.sparray | np.ndarray
    names: Sequence[str] = ()
    fields: FieldSink | None = None

    def __post_init__(self) -> None:
        n_rows = self.rows.shape[0] if self.rows.ndim == 2 else 1
        if len(self.names) not in (0, n_rows):
            raise ValueError(f"{len(self.names)} output names for {n_rows} output rows")


@dataclass(frozen=True)
class TransientOptions:
    r"""How a transient run is made.

    Attributes:
        method, checks: forms of :data:`~substruct.vocabulary.TRANSIENT_FORMS`: the one
            returned and those it is checked against.
        tolerance: the largest agreement a check may have.
        what: the analysis as a failed check's message names it.
        integrator, rho_inf: :func:`substruct.analysis.transient.integrators.scheme`.
        every: record every this many steps; ``field_every``: keep the full field every this
            many steps (0: never).
        forces: compute the constraint forces.
        factorization: of the effective matrix (:func:`substruct.linalg.factorize.factorizer`).
        modal_count: the modes of the modal form (``None``: all of a dense model).
        modal_solver: their eigensolver strategy (:func:`substruct.analysis.api.choose_solver`),
            or ``"amls"``: the modes of an AMLS reduction
            (:func:`substruct.analysis.modes.amls.amls_coupled_modes`), every one below
            ``modal_cutoff`` times the step's Nyquist frequency :math:`\pi / dt` (or the
            lowest ``modal_count``).
        modal_cutoff: with ``modal_solver="amls"``, that multiple (> 0; ``None``:
            :data:`MODAL_CUTOFF`).
        modal_amls: with ``modal_solver="amls"``, the reduction
            (:class:`~substruct.analysis.modes.amls.AmlsOptions`; its defaults if ``None``).
        modal_residual: ``"static"``, the static correction of the modes left out (the
            mode-acceleration method), or ``"none"`` (the bare modal sum, to show what the
            correction is worth).

    Raises:
        ValueError: an unknown form or integrator, ``rho_inf`` outside ``[0, 1]``, a
            negative or NaN tolerance, ``every < 1``, ``field_every < 0``, ``modal_count < 1``,
            a ``modal_cutoff`` not positive, a ``modal_cutoff`` or ``modal_amls`` without
            ``modal_solver="amls"``, an unknown ``modal_residual``.
    """

    method: str = GENERALIZED_INVERSE
    checks: Sequence[str] = ()
    tolerance: float = DEFAULT_TOLERANCE
    what: str = "transient"
    integrator: str = "newmark"
    rho_inf: float = 1.0
    every: int = 1
    field_every: int = 0
    forces: bool = True
    factorization: str = "auto"
    modal_count: int | None = None
    modal_solver: str = "auto"
    modal_cutoff: float | None = None
    modal_amls: Any = None  # AmlsOptions (read by the modal form only)
    modal_residual: str = "static"
    #: the integration scheme of ``integrator`` and ``rho_inf``
    scheme: Scheme = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        for name in (self.method, *self.checks):
            if name not in TRANSIENT_FORMS:
                raise ValueError(f"unknown method {name!r}; expected one of "
                                 f"{', '.join(TRANSIENT_FORMS)}")
        if not (self.tolerance >= 0 and not math.isnan(self.tolerance)):
            raise ValueError(f"tolerance must be >= 0, got {self.tolerance!r}")
        _count("every", self.every, 1)
        _count("field_every", self.field_every, 0)
        if self.modal_count is not None:
            _count("modal_count", self.modal_count, 1)
        if self.modal_residual not in MODAL_RESIDUALS:
            raise ValueError(f"unknown modal_residual {self.modal_residual!r}; expected one "
                             f"of {', '.join(MODAL_RESIDUALS)}")
        if self.modal_cutoff is not None and not (math.isfinite(self.modal_cutoff)
                                                  and self.modal_cutoff > 0):
            raise ValueError(f"modal_cutoff must be > 0, got {self.modal_cutoff!r}")
        if self.modal_solver != "amls" and (self.modal_cutoff is not None
                                            or self.modal_amls is not None):
            raise ValueError(f"modal_cutoff and modal_amls are for modal_solver amls, got "
                             f"{self.modal_solver!r}")
        object.__setattr__(self, "checks", tuple(self.checks))
        object.__setattr__(self, "scheme", scheme(self.integrator, self.rho_inf))
