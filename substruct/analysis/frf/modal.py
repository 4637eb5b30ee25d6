r"""Receptances by modal superposition of the coupled modes, with a residual flexibility.

The receptance of a system under ``A q = 0`` is a sum over the roots :math:`\lambda_r` of
``(lambda^2 M + lambda C + K) u = A^T mu``, ``A u = 0`` (eqs 23-34), in the first-order
(state-space) form, which holds for any damping (proportional or not):

.. math::  H(\omega) = \sum_r \frac{u_r u_r^T}{a_r (i\omega - \lambda_r)}, \qquad
           a_r = u_r^T (2 \lambda_r M + C)\, u_r ,

each complex root standing beside its conjugate.  For an undamped model
(:math:`\lambda_r = i \omega_r`, ``u_r^T M u_r = 1``) a pair is the classical
:math:`u_r u_r^T / (\omega_r^2 - \omega^2)`, and for a proportionally damped one
:math:`u_r u_r^T / (\omega_r^2 - \omega^2 + 2 i \zeta_r \omega_r \omega)`.

Only the roots up to a cut-off are computed (:func:`substruct.analysis.api.modes`, dense or
sparse); the truncated ones are replaced by their static part, taken from one static solve of
the constrained system (a Lagrange-multiplier solve with the independent rows of ``A``):

.. math::  H(\omega) \approx \sum_{r \le N} T_r(\omega)
           + \Big( G_{static} - \sum_{r \le N} T_r(0) \Big),
           \qquad G_{static} = H(0) ,

so that the low-frequency limit is exact.  Rigid-body modes (``K u = 0``, ``A u = 0``, found
as zero roots) of an undamped model are handled by inertia relief: their terms
:math:`-\Phi_0 \Phi_0^T / \omega^2` are kept apart and ``G_static`` is the flexibility of the
elastic part,

.. math::  \begin{bmatrix} K & A^T & M \Phi_0 \\ A & 0 & 0 \\ \Phi_0^T M & 0 & 0
           \end{bmatrix} \begin{bmatrix} q \\ \mu \\ \nu \end{bmatrix} =
           \begin{bmatrix} (I - M \Phi_0 \Phi_0^T) F \\ 0 \\ 0 \end{bmatrix} .

A damped model with rigid-body modes, and constraints tied to the force (``R != 0``), are
refused with a one-line ``ValueError``.  The sweep itself costs one small matrix product per
frequency; the direct solve (:func:`substruct.analysis.formulations.coupling.receptance`) at a few check
frequencies is its cross-check.

The roots and the sums over them are in :mod:`substruct.analysis.frf.modal_basis`, the
residual flexibility in :mod:`substruct.analysis.frf.modal_static`.  The sweep computes a block
of frequencies at a time: into the whole array, or, given a sink
(:class:`~substruct.analysis.frf.stream.SweepTap`), into one block handed to it as soon as it
is computed, the checked frequencies kept as the blocks pass; each frequency's value is the
same either way (:func:`~substruct.analysis.frf.modal_basis.modal_terms`).
"""


from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Sequence

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from substruct.analysis.checks import (
    check_methods,
    receptance_difference,
    require_agreement,
)
from substruct.analysis.errors import AnalysisInputError
from substruct.analysis.formulations.coupling import receptance
from substruct.analysis.frf.modal_basis import (
    DEFAULT_CUTOFF,
    RIGID_ROOT_FRACTION,
    ModalBasis,
    modal_basis,
    modal_moment,
    modal_terms,
)
from substruct.analysis.frf.modal_static import static_moments, static_solver
from substruct.analysis.frf.stream import SweepTap
from substruct.analysis.modes.sparse import has_damping
from substruct.analysis.results import Receptance
from substruct.analysis.system import ConstrainedSystem, SweepOptions
from substruct.vocabulary import GENERALIZED_INVERSE, KKT

__all__ = ["MODAL_ABOVE", "ModalOptions", "frf_method", "DEFAULT_CUTOFF",
           "MODAL_CHECK_FREQUENCIES", "ModalBasis", "modal_basis", "static_solver",
           "static_moments", "modal_terms", "modal_moment", "RESIDUAL_ORDER",
           "RIGID_ROOT_FRACTION", "MODAL_BLOCK_BYTES", "modal_receptance_sweep", "check_indices"]

#: ``method: auto`` takes the modal sweep above this many coordinates.
MODAL_ABOVE = 2000
#: Frequencies of the grid at which the direct solve checks the modal sweep.
MODAL_CHECK_FREQUENCIES = 3
#: Residual terms: none, the static flexibility (``G - sum_r T_r(0)``), or the Taylor terms
#: up to ``s^2`` (:func:`static_moments`; error of the truncation then ``O((w / w_c)^3)``).
RESIDUAL_ORDER = {"none": -1, "static": 0, "second-order": 2}
#: Bytes of receptances computed at a time when the sweep keeps the whole array (a sink
#: sets its own block).
MODAL_BLOCK_BYTES = 64 << 20


@dataclass(frozen=True)
class ModalOptions:
    """How the modal sweep is made (``analysis.frf.modal`` in a case file).

    Attributes:
        count: the number of roots kept (``None``: those up to ``cutoff`` times the highest
            frequency of the grid).
        cutoff: the cut-off as a multiple of the highest frequency.
        residual: one of :data:`RESIDUAL_ORDER`.
        n_check: how many frequencies of the grid the direct solve checks.
        solver: the eigensolver strategy (:func:`substruct.analysis.api.choose_solver`), or
            ``"amls"``: every root below the cut-off on the AMLS basis
            (:func:`substruct.analysis.modes.amls.amls_damped_basis`).
        amls: with ``solver="amls"``, the reduction
            (:class:`~substruct.analysis.modes.amls.AmlsOptions`; its defaults if ``None``).
    """

    count: int | None = None
    cutoff: float = DEFAULT_CUTOFF
    residual: str = "second-order"
    n_check: int = MODAL_CHECK_FREQUENCIES
    solver: str = "auto"
    amls: Any = None


def frf_method(method: str, n: int, R: sp.sparray | np.ndarray | None) -> str:
    """``method`` with ``"auto"`` resolved: ``"modal"`` above :data:`MODAL_ABOVE` coordinates
    (unless a constraint is tied to the force), ``generalized-inverse`` otherwise."""
    if method != "auto":
        return method
    tied = R is not None and bool(np.any(sp.csr_array(R).data != 0))
    return "modal" if n > MODAL_ABOVE and not tied else GENERALIZED_INVERSE


def check_indices(count: int, k: int = MODAL_CHECK_FREQUENCIES) -> np.ndarray:
    """``k`` indices spread over a grid of ``count`` frequencies (first, last, between)."""
    return np.unique(np.round(np.linspace(0, count - 1, min(k, count))).astype(int))


def _block_sum(basis: ModalBasis, P: np.ndarray, Q: np.ndarray, rigid: np.ndarray | None,
               moments: list[np.ndarray]) -> Callable[[np.ndarray, np.ndarray], None]:
    r"""``fill(w, out)``: ``out[k] = H(w_k)`` of :func:`modal_receptance_sweep`, a frequency at
    a time (:func:`~substruct.analysis.frf.modal_basis.modal_terms`), then the rigid-body terms
    ``- rigid / w^2`` and the residual moments :math:`\sum_k s^k D_k`."""
    def fill(w: np.ndarray, out: np.ndarray) -> None:
        modal_terms(basis, P, Q, w, out)
        if rigid is not None:
            out -= rigid[None] / w[:, None, None] ** 2
        s = 1j * w
        for k, Dk in enumerate(moments):
            out += (s ** k)[:, None, None] * Dk[None]

    return fill


def modal_receptance_sweep(system: ConstrainedSystem, omegas: Sequence[float] | np.ndarray,
                           inputs: sp.sparray | np.ndarray, outputs: sp.sparray | np.ndarray,
                           *, options: SweepOptions, sink: SweepTap | None = None
                           ) -> Receptance:
    r"""Receptances at ``omegas`` by modal superposition plus residual flexibility, checked by
    the direct solve at ``n_check`` frequencies of the grid.

    .. math::  H[k] = O \Big[ \sum_{r \le N} T_r(\omega_k) + G_{static}
               - \sum_{r \le N} T_r(0) \Big] E

    Args:
        system: the assembled model (:class:`~substruct.linalg.system.ConstrainedSystem`); its
            ``R`` must be zero: a force-tied constraint is refused.
        omegas: circular frequencies (rad/s).
        inputs, outputs: ``n x p`` force patterns and ``q x n`` output rows.
        options: the checks, tolerance, names and ``what`` of the sweep
            (:class:`~substruct.analysis.system.SweepOptions`), and in ``options.modal`` the
            roots kept, the residual (:data:`RESIDUAL_ORDER`: ``"static"``, exact at
            ``omega = 0``; ``"second-order"``, also the ``s`` and ``s^2`` terms from two more
            back-substitutions; ``"none"`` only to show what the others are worth), the
            number of check frequencies, the eigensolver (:class:`ModalOptions`).
            ``options.checks`` are the direct formulations (``kkt`` if none) and
            ``options.tolerance`` the largest ``max |H_direct - H| / max |H|`` at the check
            frequencies.
        sink: where the receptances go, a block of frequencies at a time as they are
            computed (:class:`~substruct.analysis.frf.stream.SweepTap`: it keeps the checked
            frequencies as the blocks pass); the result's ``H`` is then its
            :class:`~substruct.analysis.frf.stream.StreamedArray`, and the sweep holds one
            block, never the whole output.  The numbers are those of the sweep without a
            sink, bit for bit.

    Returns:
        A :class:`~substruct.analysis.results.Receptance` with ``method`` naming the roots
        kept, ``agreement`` keyed ``"<check> (<n> frequencies)"`` and ``constraint_residual``
        the largest :math:`|A x|_\infty / (|A|_F |x|_\infty)` over the retained shapes and
        the static responses (everything the sum is made of).

    Raises:
        CheckError: a direct solve disagrees by more than ``tolerance``.
        ValueError: ``R != 0``; a damped model with rigid-body modes; a zero frequency with
            rigid-body modes.
    """
    Ks, Ms, Cs, As = system.K, system.M, system.C, system.A
    modal = options.modal if options.modal is not None else ModalOptions()
    checks, tolerance, what = options.checks, options.tolerance, options.what
    input_names, output_names = options.input_names, options.output_names
    if system.R is not None:
        raise AnalysisInputError("the modal receptance needs A q = 0; a constraint tied to the force "
                         "(R) needs method: generalized-inverse")
    w = np.atleast_1d(np.asarray(omegas, dtype=float))
    E = sp.csc_array(inputs, dtype=float).toarray()
    O = sp.csr_array(outputs, dtype=float)
    basis = modal_basis(Ms, Cs, Ks, As, float(w.max(initial=0.0)), count=modal.count,
                        cutoff=modal.cutoff, solver=modal.solver, amls=modal.amls)
    residual = modal.residual
    if basis.rigid.shape[1] and np.any(w <= 0):
        raise AnalysisInputError("the receptance of a model with rigid-body modes is infinite at "
                         "omega = 0")
    P = O @ basis.shapes
    Q = basis.shapes.T @ E
    rigid = (O @ basis.rigid) @ (basis.rigid.T @ E) if basis.rigid.shape[1] else None
    if residual not in RESIDUAL_ORDER:
        raise ValueError(f"unknown residual {residual!r}; expected one of "
                         f"{', '.join(RESIDUAL_ORDER)}")
    order = RESIDUAL_ORDER[residual]
    moments: list[np.ndarray] = []
    if order >= 0:
        flex = static_solver(Ks, Ms, As, basis.rigid)
        X = static_moments(flex, Ms, Cs if has_damping(Cs) else None, E, order)
        moments = [np.asarray(O @ Xk - modal_moment(basis, P, Q, k)) for k, Xk in enumerate(X)]
        vectors = np.hstack([basis.shapes, *X])
    else:
        vectors = basis.shapes
    norm_a = max(float(spla.norm(As)), 1e-300) if As.shape[0] else 1.0
    size = np.maximum(np.abs(vectors).max(axis=0, initial=0.0), 1e-300) * norm_a
    constraint_residual = float((np.abs(As @ vectors).max(axis=0, initial=0.0) / size).max(
        initial=0.0)) if As.shape[0] and vectors.shape[1] else 0.0
    idx = check_indices(len(w), modal.n_check)
    fill = _block_sum(basis, P, Q, rigid, moments)
    shape = (len(w), O.shape[0], E.shape[1])
    H: Any
    if sink is None:
        H = np.empty(shape, dtype=complex)
        rows = max(1, MODAL_BLOCK_BYTES // max(1, 16 * shape[1] * shape[2]))
        for start in range(0, len(w), rows):
            fill(w[start:start + rows], H[start:start + rows])
        checked = H[idx]
    else:
        sink.keep(idx)
        rows = max(1, min(len(w), int(sink.open(shape, np.dtype(complex)))))
        block = np.empty((rows, *shape[1:]), dtype=complex)
        for start in range(0, len(w), rows):
            out = block[:min(rows, len(w) - start)]
            fill(w[start:start + rows], out)
            sink.write(start, out)
        H, checked = sink.array(), sink.checked
    agreement = {}
    for check in check_methods("modal", list(checks) or [KKT]) if idx.size else []:
        Hd = receptance(Ks, Ms, Cs, As, w[idx], None, method=check, inputs=E, outputs=O)
        agreement[f"{check} ({len(idx)} frequencies)"] = receptance_difference(Hd, checked)
    what_modes = f"modal: {basis.count} root(s) up to {basis.highest:.4g} rad/s" + \
        (" (AMLS basis)" if modal.solver == "amls" else "") + \
        (f", {basis.rigid.shape[1]} rigid" if basis.rigid.shape[1] else "") + \
        (f" + {residual} residual" if order >= 0 else ", no residual")
    require_agreement(what, what_modes, agreement, tolerance)
    names_in = list(input_names) if input_names is not None else \
        [str(j + 1) for j in range(E.shape[1])]
    names_out = list(output_names) if output_names is not None else \
        [str(i + 1) for i in range(O.shape[0])]
    return Receptance(method=what_modes, omega=w, H=H, inputs=names_in, outputs=names_out,
                      agreement=agreement, constraint_residual=constraint_residual,
                      tolerance=float(tolerance))
