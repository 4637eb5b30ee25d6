r"""The receptance of constrained systems, eqs (11)-(15), and the generalized-inverse coupler.

Paper equations in the paper's order, each beside its code:

* eqs (5)-(10), the projection of the generalized inverse and the semidefinite mass split
  (:mod:`substruct.analysis.formulations.projection`, whose names are exported here too:
  :class:`MassSplit`, :func:`split_mass`, :func:`constraint_gain`, :func:`projected_inverse`,
  :func:`constrained_acceleration`);
* eq (13), the receptance of the unconstrained system, :func:`receptance_unconstrained`;
* eq (15), ``G`` and ``D`` as printed, :func:`paper_G_D`, and the receptance
  ``\hat H = G^{-1} D`` of a system under ``A q = R F``, :func:`receptance`.

Two independent formulations check the receptance: null-space elimination ``q = N p + q_p`` and
Lagrange multipliers (the KKT system), :mod:`substruct.analysis.formulations.receptance`.  All three
must agree (:func:`receptance_agreement`).
"""

from __future__ import annotations

from typing import Any, Literal, Sequence

import numpy as np
import scipy.sparse as sp

from substruct.analysis.formulations.projection import (
    MassSplit,
    constrained_acceleration,
    constraint_gain,
    projected_inverse,
    split_mass,
)
from substruct.analysis.formulations.forms import formulation
from substruct.analysis.formulations.receptance import impedance, inputs_matrix
from substruct.linalg.constraints import ConstraintError, check_consistent
from substruct.linalg.dense import dense
from substruct.linalg.scaling import equilibrate
from substruct.linalg.system import ConstrainedSystem
from substruct.vocabulary import FORMULATIONS, GENERALIZED_INVERSE

__all__ = [
    "FORMULATIONS",
    "ConstraintError",
    "MassSplit",
    "split_mass",
    "constraint_gain",
    "projected_inverse",
    "constrained_acceleration",
    "receptance_unconstrained",
    "paper_G_D",
    "receptance",
    "receptance_agreement",
    "receptance_of",
]



def _csr(mat: sp.sparray | np.ndarray | None, shape: tuple[int, int]) -> sp.csr_array:
    if mat is None:
        return sp.csr_array(shape, dtype=float)
    return sp.csr_array(mat)


def receptance_unconstrained(K: sp.sparray | np.ndarray, M: sp.sparray | np.ndarray,
                             C: sp.sparray | np.ndarray | None, omega: float) -> np.ndarray:
    r"""Receptance of the unconstrained system, eq (13), dense.

    .. math::  H(\omega) = (-\omega^2 M + i \omega C + K)^{-1}
    """
    K = sp.csr_array(K)
    Z = impedance(K, sp.csr_array(M), _csr(C, K.shape), omega)
    return np.linalg.inv(dense(Z))


def paper_G_D(K: sp.sparray | np.ndarray, M: sp.sparray | np.ndarray,
              C: sp.sparray | np.ndarray | None, A: sp.sparray | np.ndarray, omega: float,
              R: sp.sparray | np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    r"""The matrices ``G`` and ``D`` of eq (15), dense (the paper prints ``G`` as "C").

    .. math::
        G &= -H^{-1} + M^{1/2} (A M^{-1/2})^+ A M^{-1} (H^{-1} + \omega^2 M) \\
        D &= M^{1/2} (A M^{-1/2})^+ (\omega^2 R + A M^{-1}) - I

    with ``M^{1/2} (A M^{-1/2})^+ = A^T (A M^{-1} A^T)^+``.  ``R`` ties the constraint to the
    force at displacement level, ``A q = R F`` (read so, the printed eq 40 is reproduced; see
    ``docs/verification.md``).  With massless coordinates ``M_d`` replaces ``M`` outside ``H``.
    """
    K = sp.csr_array(K, dtype=float)
    n = K.shape[0]
    ms = split_mass(M)
    Ad = dense(sp.csr_array(A, dtype=float))
    Rd = np.zeros(Ad.shape) if R is None else dense(sp.csr_array(R, dtype=float))
    if Ad.shape[0]:  # G and D do not change when the rows of A and R are scaled together
        eq = equilibrate(Ad, R=Rd)
        Ad, Rd = np.asarray(eq.A), np.asarray(eq.R)
    Z = dense(impedance(K, sp.csr_array(M), _csr(C, K.shape), omega))
    Y, Sp = constraint_gain(ms, Ad)
    AMinv = Y.T  # A M_d^{-1}
    Md = dense(ms.Md)
    G = -Z + Ad.T @ Sp @ AMinv @ (Z + omega**2 * Md)
    D = Ad.T @ Sp @ (omega**2 * Rd + AMinv) - np.eye(n)
    return G, D


def receptance(K: sp.sparray | np.ndarray, M: sp.sparray | np.ndarray,
               C: sp.sparray | np.ndarray | None, A: sp.sparray | np.ndarray,
               omegas: float | Sequence[float] | np.ndarray,
               R: sp.sparray | np.ndarray | None = None, method: str = GENERALIZED_INVERSE,
               inputs: sp.sparray | np.ndarray | None = None,
               outputs: sp.sparray | np.ndarray | None = None,
               labels: list[str] | None = None) -> np.ndarray:
    r"""Receptance of a system under linear constraints ``A q = R F`` (eqs 11-15).

    .. math::  \hat q = \hat H(\omega) \bar F, \qquad \hat H = G^{-1} D \quad (15)

    Args:
        K, M, C: sparse ``n x n`` matrices (``C`` may be ``None``); ``M`` may have massless rows.
        A: ``m x n`` constraint matrix, any rank.
        omegas: one circular frequency (rad/s) or a sequence.
        R: ``m x n`` matrix tying the constraint to the force, ``A q = R F`` (``None``: ``A q = 0``).
        method: ``generalized-inverse`` (eq 15), ``null-space`` or ``kkt``.
        inputs: ``n x k`` force patterns (columns of ``F``); ``None`` for all coordinates.
        outputs: ``k_o x n`` rows giving the outputs; ``None`` for all coordinates.
        labels: constraint names used in error messages.

    Returns:
        ``(n_omega, k_o, k)`` complex array, or ``(k_o, k)`` for a scalar ``omega``.

    The rows of ``A`` and ``R`` are equilibrated together first,
    :math:`D A q = D R F` (:func:`substruct.linalg.scaling.equilibrate`): the same receptance,
    and rank and consistency decided whatever the scale of a row (``1e-8 q_1 = 0`` and
    ``1e-300 q_1 = 0`` both mean ``q_1 = 0``).

    Raises:
        ConstraintError: if a redundant constraint row carries an inconsistent ``R``.
        substruct.linalg.scaling.ZeroRowError: a constraint row that is exactly zero.
    """
    system = ConstrainedSystem.of(M, C, K, A, R=R, constraint_labels=labels)
    return receptance_of(system, omegas, method, inputs, outputs)


def receptance_of(system: ConstrainedSystem, omegas: float | Sequence[float] | np.ndarray,
                  method: str = GENERALIZED_INVERSE,
                  inputs: sp.sparray | np.ndarray | None = None,
                  outputs: sp.sparray | np.ndarray | None = None) -> np.ndarray:
    r""":func:`receptance` of a :class:`~substruct.linalg.system.ConstrainedSystem` (rows
    already equilibrated): a force-tied ``R`` checked for consistency, then the sweep of the
    formulation object ``method`` (:func:`substruct.analysis.formulations.forms.formulation`).

    Raises:
        ConstraintError: if a redundant constraint row carries an inconsistent ``R``.
        ValueError: an unknown method.
    """
    form = formulation(method)
    n = system.n
    scalar = np.ndim(omegas) == 0
    w = np.atleast_1d(np.asarray(omegas, dtype=float))
    E = inputs_matrix(inputs, n)
    O = sp.eye_array(n).tocsr() if outputs is None else sp.csr_array(outputs).reshape(-1, n)
    if system.R is not None:
        labels = None if system.constraint_labels is None else list(system.constraint_labels)
        check_consistent(system.A, system.R, system.independent, labels)
    H = form.receptance(system, w, E, O)
    return H[0] if scalar else H


def receptance_agreement(K: sp.sparray | np.ndarray, M: sp.sparray | np.ndarray,
                         C: sp.sparray | np.ndarray | None, A: sp.sparray | np.ndarray,
                         omegas: float | Sequence[float] | np.ndarray,
                         R: sp.sparray | np.ndarray | None = None,
                         methods: Sequence[str] = FORMULATIONS, **kwargs: Any) -> dict[str, float]:
    r"""Largest relative difference of each method's receptance from the first method's.

    .. math::  \delta = \max_\omega \|\hat H_{method} - \hat H_{ref}\|_\max / \|\hat H_{ref}\|_\max
    """
    results = {mth: receptance(K, M, C, A, omegas, R, method=mth, **kwargs) for mth in methods}
    ref = results[methods[0]]
    scale = np.abs(ref).reshape(np.shape(ref)[0] if np.ndim(ref) == 3 else 1, -1).max(axis=1)
    out = {}
    for mth, H in results.items():
        diff = np.abs(H - ref).reshape(scale.size, -1).max(axis=1)
        out[mth] = float(np.max(diff / np.where(scale > 0, scale, 1.0)))
    return out
