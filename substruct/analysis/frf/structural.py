r"""Structural (hysteretic) damping: a loss factor :math:`\eta` on the stiffness.

A loss factor :math:`\eta_s \ge 0` on the stiffness part :math:`K_s` (one substructure's, or the
whole :math:`K`) makes the harmonic dynamic stiffness

.. math::  Z(\omega) = \sum_s K_s (1 + i \eta_s) + i \omega C - \omega^2 M ,

with the constraint :math:`A q = R F` unchanged (eq 15).  At one frequency this is the viscous
system with the equivalent damping :math:`C_{eq}(\omega) = C + \sum_s \eta_s K_s / \omega`
(:func:`equivalent_damping`), so the receptance at each :math:`\omega > 0` is that of eq (15)
with :math:`C_{eq}(\omega)`, by the same formulations and checks
(:func:`hysteretic_sweep`).  In a time history a loss factor has no causal real form; the
transient takes no loss factor (the equivalent viscous damping at one frequency is the user's
choice, :func:`equivalent_damping` at that frequency).

The complex modes of :math:`(\sum_s K_s (1 + i \eta_s), M)` on the constraint null space give
the modal loss factors :math:`\eta_r = \operatorname{Im} \lambda_r / \operatorname{Re}
\lambda_r` (:func:`modal_loss_factors`); for one :math:`\eta` on all of :math:`K` every
:math:`\eta_r = \eta` exactly, and for small :math:`\eta_s` they approach the modal strain
energy estimate :math:`\sum_s \eta_s \phi_r^T K_s \phi_r / \phi_r^T K \phi_r`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Sequence

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from substruct.analysis.api import receptance_sweep
from substruct.analysis.errors import AnalysisInputError
from substruct.analysis.results import Receptance
from substruct.linalg.dense import dense

__all__ = ["LossFactor", "check_loss", "equivalent_damping", "hysteretic_sweep",
           "modal_loss_factors"]


@dataclass(frozen=True)
class LossFactor:
    r"""A loss factor ``eta`` on the stiffness part ``K`` (``n x n``; the whole stiffness for
    a global loss factor)."""

    eta: float
    K: sp.sparray


def check_loss(parts: Sequence[LossFactor]) -> None:
    """Refuse a negative or non-finite loss factor.

    Raises:
        ValueError: ``eta < 0`` or not finite.
    """
    for p in parts:
        if not np.isfinite(p.eta) or p.eta < 0:
            raise ValueError(f"a loss factor must be >= 0 and finite, got {p.eta!r}")


def equivalent_damping(C: sp.sparray | np.ndarray | None, parts: Sequence[LossFactor],
                       omega: float, n: int) -> sp.csr_array:
    r""":math:`C_{eq}(\omega) = C + \sum_s \eta_s K_s / \omega` (``omega > 0``).

    Raises:
        AnalysisInputError: ``omega <= 0`` with a nonzero loss factor (the hysteretic force
            has no static limit).
    """
    out = sp.csr_array((n, n)) if C is None else sp.csr_array(C, dtype=float)
    active = [p for p in parts if p.eta != 0]
    if active and omega <= 0:
        raise AnalysisInputError("a loss factor needs frequencies > 0 (K (1 + i eta) / "
                                 f"(i omega) at omega = {omega:g})")
    for p in active:
        out = out + sp.csr_array(p.K, dtype=float) * (p.eta / omega)
    return sp.csr_array(out)


def hysteretic_sweep(K: sp.sparray | np.ndarray, M: sp.sparray | np.ndarray,
                     C: sp.sparray | np.ndarray | None, A: sp.sparray | np.ndarray | None,
                     omegas: Sequence[float] | np.ndarray, inputs: sp.sparray | np.ndarray,
                     outputs: sp.sparray | np.ndarray, parts: Sequence[LossFactor], **kw: object
                     ) -> Receptance:
    r"""Receptances under ``A q = R F`` with loss factors: at each :math:`\omega_k` the
    receptance of eq (15) for :math:`(K, M, C_{eq}(\omega_k))`
    (:func:`substruct.analysis.api.receptance_sweep`, one frequency a call, so its
    formulation, checks and constraint residual apply), i.e.

    .. math::  H(\omega) = o\,[\textstyle\sum_s K_s (1 + i \eta_s) + i\omega C
               - \omega^2 M]^{-1}_{A q = R F} e .

    ``kw`` is passed on (``R``, ``method``, ``checks``, ``tolerance``, names); ``method`` must
    be a direct formulation (the modal sum would recompute modes at each frequency).

    Raises:
        ValueError: a negative loss factor or ``method`` ``modal``/``auto``.
        AnalysisInputError: a frequency <= 0 with a loss factor.
    """
    check_loss(parts)
    if kw.get("method") in ("modal", "auto"):
        raise ValueError("a loss factor is taken by the direct formulations only, not "
                         f"method {kw.get('method')}")
    w = np.atleast_1d(np.asarray(omegas, dtype=float))
    n = K.shape[0]
    if not any(p.eta for p in parts):
        return receptance_sweep(K, M, C, A, w, inputs, outputs, **kw)  # type: ignore[arg-type]
    results = [receptance_sweep(K, M, equivalent_damping(C, parts, float(wk), n), A, [wk],
                                inputs, outputs, **kw)  # type: ignore[arg-type]
               for wk in w]
    first = results[0]
    agreement = {key: max(r.agreement.get(key, 0.0) for r in results)
                 for key in first.agreement}
    return replace(first, omega=w, H=np.concatenate([r.H for r in results], axis=0),
                   agreement=agreement,
                   constraint_residual=max(r.constraint_residual for r in results))


def modal_loss_factors(M: sp.sparray | np.ndarray, parts: Sequence[LossFactor],
                       A: sp.sparray | np.ndarray | None = None
                       ) -> tuple[np.ndarray, np.ndarray]:
    r"""Complex modes of :math:`(\sum_s K_s (1 + i\eta_s), M)` on the null space ``N`` of
    ``A`` (:math:`q = N p`, dense: small models):

    .. math::  N^T K^* N \phi = \lambda N^T M N \phi, \quad
               \omega_r = \sqrt{\operatorname{Re} \lambda_r}, \quad
               \eta_r = \operatorname{Im} \lambda_r / \operatorname{Re} \lambda_r

    Returns:
        ``(omega_r, eta_r)`` sorted by ``Re lambda`` (finite eigenvalues only).

    Raises:
        AnalysisInputError: the constrained mass is singular (massless coordinates).
    """
    check_loss(parts)
    Kc = sum((dense(p.K).astype(complex) * (1 + 1j * p.eta) for p in parts),
             np.zeros(M.shape, dtype=complex))
    Md = dense(M)
    if A is not None and np.size(A):
        N = sla.null_space(dense(A))
        Kc, Md = N.T @ Kc @ N, N.T @ Md @ N
    if np.linalg.matrix_rank(Md) < Md.shape[0]:
        raise AnalysisInputError("modal loss factors need a nonsingular constrained mass")
    lam = sla.eigvals(Kc, Md)
    lam = lam[np.isfinite(lam)]
    lam = lam[np.argsort(lam.real)]
    return np.sqrt(np.maximum(lam.real, 0.0)), lam.imag / np.where(lam.real == 0, 1.0, lam.real)

