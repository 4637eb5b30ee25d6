r"""Base-driven frequency response: enforced harmonic motion of constrained supports.

A support moved by :math:`g(t) = G e^{i\omega t}` is the nonhomogeneous constraint of the
transient's ground motion (:mod:`substruct.analysis.transient.base`): the rows ``E`` of ``A``
that ground the excited points get the right-hand side :math:`A q = E\, G` (``E`` is
``m x p``: one column per independent base input).  In the paper's form :math:`A q = R F`
(eqs 11-15) this is a force that the constraints absorb whole plus an ``R`` that turns it into
the motion:

.. math::  F = A^T E\, G, \qquad R = E\, (A^T E)^{+}, \qquad R F = E\, G ,

since :math:`F = A^T E G` is cancelled by the multiplier shift :math:`\lambda \to \lambda - E G`
and leaves only the right-hand side.  So :func:`base_drive_sweep` is one call of
:func:`substruct.analysis.api.receptance_sweep` with these inputs and ``R``: the
transmissibility :math:`T = \hat q / G` (absolute displacement per base displacement, equal to
absolute acceleration per base acceleration).

Check (``"relative-coordinates"``): with the influence vector ``r`` (:math:`K r + A^T \mu = 0`,
:math:`A r = E`) and :math:`q = r G + w`, :math:`A w = 0`,

.. math::  T = r + \omega^2 H_0 M r - i \omega H_0 C r ,

:math:`H_0` the receptance under :math:`A w = 0`.  For a mass ``m`` on a spring ``k`` and a
dashpot ``c`` to a moving base both give
:math:`T = (1 + 2 i \zeta r) / (1 - r^2 + 2 i \zeta r)`, :math:`r = \omega / \omega_n`.

``per``: ``"displacement"`` reports :math:`\hat q / G`; ``"acceleration"`` reports
:math:`\hat q / \ddot G = -\hat q / (\omega^2 G)` (output displacement per base acceleration,
converted to output velocity or acceleration by
:func:`substruct.analysis.frf.quantity.quantity_factor`).  Loss factors (structural damping,
:mod:`substruct.analysis.frf.structural`) enter both paths through :math:`C_{eq}(\omega)`.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Sequence

import numpy as np
import scipy.sparse as sp

from substruct.analysis.checks import require_agreement
from substruct.analysis.errors import AnalysisInputError
from substruct.analysis.frf.structural import LossFactor, equivalent_damping, hysteretic_sweep
from substruct.analysis.results import DEFAULT_TOLERANCE, Receptance
from substruct.analysis.transient.base import influence
from substruct.vocabulary import GENERALIZED_INVERSE
from substruct.analysis.system import SweepOptions

__all__ = ["RELATIVE", "base_frequencies", "base_inputs", "base_drive_sweep"]

#: Key of the relative-coordinates check in :attr:`Receptance.agreement`.
RELATIVE = "relative-coordinates"


def base_frequencies(omegas: Sequence[float] | np.ndarray, per: str) -> np.ndarray:
    """The frequencies of a base-driven sweep as an array, checked for the base input ``per``
    (``"displacement"`` or ``"acceleration"``: the response per unit base acceleration is
    unbounded at ``omega = 0``).

    Raises:
        AnalysisInputError: ``per == "acceleration"`` with a frequency ``<= 0``.
        ValueError: an unknown ``per`` (a programming error).
    """
    if per not in ("displacement", "acceleration"):
        raise ValueError(f"unknown base input {per!r}")
    w = np.atleast_1d(np.asarray(omegas, dtype=float))
    if per == "acceleration" and np.any(w <= 0):
        raise AnalysisInputError("a base acceleration needs frequencies > 0 (the response per "
                                 "unit acceleration is unbounded at omega = 0)")
    return w


def base_inputs(A: sp.sparray | np.ndarray, E: np.ndarray) -> tuple[sp.csc_array, sp.csr_array]:
    r"""``(F, R)`` with :math:`F = A^T E` (``n x p``) and :math:`R = E (A^T E)^+` (``m x n``),
    so that :math:`R F = E` (module docstring).

    Raises:
        AnalysisInputError: a column of ``E`` moves no constraint row (``A^T E`` loses rank).
    """
    As = sp.csr_array(A, dtype=float)
    E = np.asarray(E, dtype=float).reshape(As.shape[0], -1)
    F = np.asarray((As.T @ E))
    pinv = np.linalg.pinv(F)
    R = E @ pinv
    bad = float(np.abs(R @ F - E).max(initial=0.0))
    if bad > 1e-9 * max(float(np.abs(E).max(initial=0.0)), 1e-300):
        raise AnalysisInputError("the base inputs are not independent motions of the "
                                 f"constraint rows (|R A^T E - E| = {bad:.3g})")
    return sp.csc_array(F), sp.csr_array(R)


def base_drive_sweep(K: sp.sparray | np.ndarray, M: sp.sparray | np.ndarray,
                     C: sp.sparray | np.ndarray | None, A: sp.sparray | np.ndarray,
                     omegas: Sequence[float] | np.ndarray, E: np.ndarray,
                     outputs: sp.sparray | np.ndarray, *, per: str = "displacement",
                     loss: Sequence[LossFactor] = (), options: SweepOptions | None = None
                     ) -> Receptance:
    r"""Output displacement per base motion, :math:`H[k, i, j] = o_i \hat q / G_j` (or per
    base acceleration, ``per="acceleration"``), by the paper's ``R`` (module docstring),
    checked by the relative-coordinates form (``agreement["relative-coordinates"]``).

    Args:
        E: ``m x p``: column ``j`` the coefficients of base input ``j`` in the rows of ``A``.
        per: ``"displacement"`` or ``"acceleration"`` (then ``omega > 0``).
        loss: loss factors (:mod:`substruct.analysis.frf.structural`).
        options: the main formulation, checks, tolerance and names, as for
            :func:`substruct.analysis.api.receptance_sweep` (its defaults if ``None``)
            (a direct formulation).

    Raises:
        CheckError: a check (or the relative form) disagrees by more than ``tolerance``.
        AnalysisInputError: a mechanism with the supports held, or ``omega = 0`` per base
            acceleration.
        ValueError: an unknown ``per`` (a programming error).
    """
    opts = options if options is not None else SweepOptions()
    method, checks, tolerance = opts.method, opts.checks, opts.tolerance
    input_names, output_names = opts.input_names, opts.output_names
    w = base_frequencies(omegas, per)
    As = sp.csr_array(A, dtype=float)
    Ks = sp.csr_array(K, dtype=float)
    E = np.asarray(E, dtype=float).reshape(As.shape[0], -1)
    F, R = base_inputs(As, E)
    kw = dict(R=R, method=method, checks=checks, tolerance=tolerance,
              input_names=input_names, output_names=output_names, what="base drive")
    main = hysteretic_sweep(Ks, M, C, As, w, F, outputs, loss, **kw)
    # the check: q = r G + w, w the response to -M r g'' - C_eq r g' under A w = 0
    r = np.column_stack([influence(Ks, As, E[:, j]) for j in range(E.shape[1])])
    Ms = sp.csr_array(M, dtype=float)
    out = sp.csr_array(outputs, dtype=float)
    p = E.shape[1]
    if not any(lf.eta for lf in loss):  # C_eq = C at every frequency: one sweep
        Cs = sp.csr_array(C if C is not None else (Ks.shape[0], Ks.shape[0]), dtype=float)
        H0 = hysteretic_sweep(Ks, Ms, Cs, As, w, np.column_stack([Ms @ r, Cs @ r]), out, (),
                              method=method, tolerance=tolerance, what="base drive").H
    else:
        H0 = np.concatenate([_relative_loads(Ks, Ms, C, As, float(wk), r, out, loss, method,
                                             tolerance) for wk in w], axis=0)
    T = (out @ r)[None] + (w ** 2)[:, None, None] * H0[:, :, :p] \
        - 1j * w[:, None, None] * H0[:, :, p:]
    scale = max(float(np.abs(main.H).max(initial=0.0)), 1e-300)
    agreement = dict(main.agreement)
    agreement[RELATIVE] = float(np.abs(T - main.H).max(initial=0.0)) / scale
    require_agreement("base drive", main.method, agreement, tolerance)
    H = main.H if per == "displacement" else main.H / (-(w ** 2))[:, None, None]
    names = list(input_names) if input_names is not None else \
        [f"base{j + 1}" for j in range(p)]
    return replace(main, H=H, inputs=names, agreement=agreement)


def _relative_loads(K: sp.csr_array, M: sp.csr_array, C: sp.sparray | np.ndarray | None,
                    A: sp.csr_array, wk: float, r: np.ndarray, out: sp.csr_array,
                    loss: Sequence[LossFactor], method: str, tolerance: float) -> np.ndarray:
    """``H0 [M r, C_eq r]`` at one frequency (``(1, q, 2 p)``)."""
    Ceq = equivalent_damping(C, loss, wk, K.shape[0])
    return hysteretic_sweep(K, M, Ceq, A, [wk], np.column_stack([M @ r, Ceq @ r]), out, (),
                            method=method, tolerance=tolerance, what="base drive").H
