r"""Transfer path analysis (TPA) with blocked forces: which interface path carries a source's
vibration to a target.

A source part ``A`` runs (operating forces inside ``A``) and is mounted on a receptor ``B`` at
interface coordinates ``c`` (interface DOFs or virtual-point coordinates).  Its blocked forces
:math:`f^{bl}` are the interface forces with the interface held fixed, a property of the source
alone (:math:`f^{bl} = Y^{A\,-1}_{cc} Y^A_{cs} F_s`), and they reproduce the assembly's response
at every receptor point ``b`` (and at the interface itself):

.. math::  u_b = Y^{AB}_{bc} f^{bl} .

* :func:`blocked_forces_matrix_inverse`: from the responses at the interface,
  :math:`f^{bl} = (Y^{AB}_{cc})^{-1} u_c` (a solve per frequency);
* :func:`blocked_forces_in_situ`: from responses at indicator points ``b`` (at least as many as
  interface coordinates, usually more: overdetermined),
  :math:`f^{bl} = (Y^{AB}_{bc})^{\dagger} u_b` (least squares, optionally regularised:
  :class:`~substruct.analysis.frf.vp_coupling.Regularisation`);
* :func:`on_board_validation`: the response predicted at validation points ``t`` not used to
  find the forces, :math:`\hat u_t = Y^{AB}_{tc} f^{bl}`, against the measured :math:`u_t`,
  with the relative error :math:`\lVert \hat u_t - u_t \rVert / \lVert u_t \rVert` per frequency;
* :func:`path_contributions`: the terms :math:`Y^{AB}_{tc_j} f^{bl}_j` whose sum over the
  paths ``j`` is the prediction at each target.

Arrays are ``(n_omega, rows, cols)`` receptances and ``(n_omega, n)`` responses and forces.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from substruct.analysis.frf.vp_coupling import Regularisation, regularised_inverse

__all__ = ["blocked_forces_matrix_inverse", "blocked_forces_in_situ", "Validation",
           "on_board_validation", "path_contributions"]


def _check(Y: np.ndarray, u: np.ndarray, what: str) -> None:
    if Y.ndim != 3 or u.ndim != 2 or u.shape != Y.shape[:2]:
        raise ValueError(f"{what}: receptances of shape {list(Y.shape)} and responses of shape "
                         f"{list(u.shape)} do not match (frequencies, points)")
    for name, arr in (("receptances", Y), ("responses", u)):
        bad = ~np.isfinite(arr)
        if bad.any():
            at = tuple(int(v) for v in np.argwhere(bad)[0])
            raise ValueError(f"{what}: the {name} are not finite at index {list(at)}")


def blocked_forces_matrix_inverse(Y_cc: np.ndarray, u_c: np.ndarray) -> np.ndarray:
    r""":math:`f^{bl} = (Y^{AB}_{cc})^{-1} u_c` at every frequency (module docstring).

    Raises:
        ValueError: shapes that do not match, ``Y_cc`` not square or singular, values not
            finite.
    """
    _check(Y_cc, u_c, "blocked forces")
    if Y_cc.shape[1] != Y_cc.shape[2]:
        raise ValueError(f"blocked forces by matrix inverse need the square interface "
                         f"receptance, got {Y_cc.shape[1]} x {Y_cc.shape[2]}: use in-situ")
    try:
        return np.linalg.solve(Y_cc, u_c[:, :, None])[:, :, 0]
    except np.linalg.LinAlgError:
        raise ValueError("the interface receptance is singular at a frequency") from None


def blocked_forces_in_situ(Y_bc: np.ndarray, u_b: np.ndarray,
                           reg: Regularisation = Regularisation(),
                           scale: np.ndarray | None = None) -> np.ndarray:
    r""":math:`f^{bl} = (Y^{AB}_{bc})^{\dagger} u_b` from ``n_b >= n_c`` indicator responses
    (module docstring; ``reg`` chooses the pseudo-inverse).

    ``scale`` (``n_c`` positive numbers) makes the unknowns of one unit before a regularised
    inversion: :math:`f = S (Y_{bc} S)^\dagger u_b`, :math:`S = \mathrm{diag}(s)`; for a
    virtual point, ``1`` for the forces and a length ``L`` of the joint for the moments (the
    unknowns are then forces and moments divided by ``L``).

    Raises:
        ValueError: fewer indicators than interface coordinates, shapes that do not match,
            values not finite.
    """
    _check(Y_bc, u_b, "in-situ blocked forces")
    n_b, n_c = Y_bc.shape[1:]
    if n_b < n_c:
        raise ValueError(f"in-situ blocked forces need at least as many indicator responses "
                         f"as interface coordinates: {n_b} < {n_c}")
    sc = np.ones(n_c) if scale is None else np.asarray(scale, dtype=float).ravel()
    if sc.shape != (n_c,) or not np.all(np.isfinite(sc)) or not np.all(sc > 0):
        raise ValueError(f"in-situ blocked forces: scale must be {n_c} finite positive numbers")
    g = (regularised_inverse(Y_bc * sc[None, None, :], reg) @ u_b[:, :, None])[:, :, 0]
    return g * sc[None, :]


@dataclass(frozen=True)
class Validation:
    """On-board validation: ``predicted`` and ``measured`` ``(n_omega, n_t)`` responses and
    ``error`` ``(n_omega,)``, :math:`\\lVert \\hat u_t - u_t \\rVert / \\lVert u_t \\rVert`."""

    predicted: np.ndarray
    measured: np.ndarray
    error: np.ndarray


def on_board_validation(Y_tc: np.ndarray, f_bl: np.ndarray, u_t: np.ndarray) -> Validation:
    r"""Predict the responses at validation points, :math:`\hat u_t = Y^{AB}_{tc} f^{bl}`, and
    compare them with the measured ones (module docstring).

    Raises:
        ValueError: shapes that do not match, values not finite.
    """
    _check(Y_tc, u_t, "on-board validation")
    if f_bl.shape != (Y_tc.shape[0], Y_tc.shape[2]):
        raise ValueError(f"on-board validation: {Y_tc.shape[2]} interface forces expected per "
                         f"frequency, got shape {list(f_bl.shape)}")
    pred = (Y_tc @ f_bl[:, :, None])[:, :, 0]
    err = np.linalg.norm(pred - u_t, axis=1) / np.maximum(np.linalg.norm(u_t, axis=1), 1e-300)
    return Validation(pred, u_t, err)


def path_contributions(Y_tc: np.ndarray, f_bl: np.ndarray) -> np.ndarray:
    r"""The contribution of each interface path ``j`` to each target ``t``,
    ``(n_omega, n_t, n_c)``: :math:`Y^{AB}_{tc_j} f^{bl}_j`; summed over ``j`` it is the
    predicted response."""
    if f_bl.shape != (Y_tc.shape[0], Y_tc.shape[2]):
        raise ValueError(f"path contributions: {Y_tc.shape[2]} interface forces expected per "
                         f"frequency, got shape {list(f_bl.shape)}")
    return Y_tc * f_bl[:, None, :]
