r"""Transfer path analysis without the interface: pseudo-forces, and operational TPA from
transmissibilities.

**Pseudo-forces** (Janssens and Verheij, *Applied Acoustics* 61, 2000).  A source ``A`` running on a
receptor ``B`` acts on ``B`` only through its blocked forces at the interface ``c``,
:math:`u_b = Y^{AB}_{bc} f^{bl}`.  A set of forces ``F_ps`` at chosen points ``p`` on the
source side, outside the interface, has the blocked forces
:math:`Y^{A\,-1}_{cc} Y^A_{cp} F_{ps}`, and the assembly's transfers from them factor alike,
:math:`Y^{AB}_{bp} = Y^{AB}_{bc} Y^{A\,-1}_{cc} Y^A_{cp}`.  Forces at ``p`` that reproduce the
responses at indicator points ``i`` (on the receptor, at least as many as pseudo-forces)

.. math::  F_{ps} = (Y^{AB}_{ip})^{\dagger} u_i                                     \qquad (1)

(least squares, optionally regularised) are *equivalent* to the source: they predict the
response at every target ``t`` on the receptor,

.. math::  \hat u_t = Y^{AB}_{tp} F_{ps} ,                                            \qquad (2)

exactly when the pseudo-forces' blocked forces :math:`Y^{A\,-1}_{cc} Y^A_{cp}` span those of
the source (for a rigid interface, six forces at three points not on one line span its six
loads); otherwise the on-board validation
(:func:`~substruct.analysis.frf.tpa.on_board_validation` with ``Y_tp``) measures the part
they miss.  The pseudo-forces are a property of the source alone: the same ``F_ps`` hold on
another receptor.

**Operational TPA** (transmissibility-based, OPA; de Klerk and Ossipov, *Mechanical Systems
and Signal Processing* 24, 2010).  Responses at indicator points ``i`` and at targets ``t`` are
measured under ``n_o`` operating conditions (the columns of :math:`U_i`, :math:`U_t`).  When
the operating forces act at ``n_s <= n_i`` places ``s``, :math:`U_i = H_{is} F`,
:math:`U_t = H_{ts} F`, and the transmissibility from the indicators to the targets

.. math::  T = U_t U_i^{\dagger}                                                   \qquad (3)

(least squares over the conditions, optionally regularised) equals :math:`H_{ts} H_{is}^{-1}`
for square :math:`H_{is}` (:math:`H_{ts} H_{is}^{\dagger}` in general) when the conditions
excite every source independently (:math:`F` of rank :math:`n_s`; hence at least ``n_i``
conditions).  The contribution of indicator (path) ``k`` to the targets under one operating
condition :math:`u_i` is

.. math::  c_k = T_{:,k}\, u_{i,k} , \qquad \sum_k c_k = T u_i = \hat u_t .            \qquad (4)

Arrays are ``(n_omega, rows, cols)``: receptances ``(n_omega, points, forces)``, responses
``(n_omega, points)``, operating responses ``(n_omega, points, conditions)``.
"""

from __future__ import annotations

import numpy as np

from substruct.analysis.frf.vp_coupling import Regularisation, regularised_inverse

__all__ = ["pseudo_forces", "transmissibility", "operational_contributions"]


def _finite(arr: np.ndarray, name: str, what: str) -> None:
    bad = ~np.isfinite(arr)
    if bad.any():
        at = tuple(int(v) for v in np.argwhere(bad)[0])
        raise ValueError(f"{what}: the {name} are not finite at index {list(at)}")


def pseudo_forces(Y_ip: np.ndarray, u_i: np.ndarray,
                  reg: Regularisation = Regularisation(),
                  scale: np.ndarray | None = None) -> np.ndarray:
    r"""Pseudo-forces :math:`F_{ps} = (Y^{AB}_{ip})^{\dagger} u_i`, equation (1) of the module
    docstring, ``(n_omega, n_p)``, from the assembly's receptances ``Y_ip``
    ``(n_omega, n_i, n_p)`` between the indicators and the pseudo-force points and the
    operating responses ``u_i`` ``(n_omega, n_i)`` at the indicators.

    ``reg`` chooses the pseudo-inverse (the default drops singular values below ``1e-12`` of
    the largest); ``scale`` (``n_p`` positive numbers) makes the unknowns of one unit before a
    regularised inversion, :math:`F = S (Y_{ip} S)^\dagger u_i`, :math:`S = \mathrm{diag}(s)`.
    The prediction at targets, equation (2), and its error are
    :func:`~substruct.analysis.frf.tpa.on_board_validation` ``(Y_tp, F_ps, u_t)``.

    Raises:
        ValueError: fewer indicators than pseudo-forces, shapes that do not match, values not
            finite.
    """
    what = "pseudo-forces"
    if Y_ip.ndim != 3 or u_i.ndim != 2 or u_i.shape != Y_ip.shape[:2]:
        raise ValueError(f"{what}: receptances of shape {list(Y_ip.shape)} and responses of "
                         f"shape {list(u_i.shape)} do not match (frequencies, points)")
    _finite(Y_ip, "receptances", what)
    _finite(u_i, "responses", what)
    n_i, n_p = Y_ip.shape[1:]
    if n_i < n_p:
        raise ValueError(f"pseudo-forces need at least as many indicator responses as "
                         f"pseudo-forces: {n_i} < {n_p}")
    sc = np.ones(n_p) if scale is None else np.asarray(scale, dtype=float).ravel()
    if sc.shape != (n_p,) or not np.all(np.isfinite(sc)) or not np.all(sc > 0):
        raise ValueError(f"{what}: scale must be {n_p} finite positive numbers")
    g = (regularised_inverse(Y_ip * sc[None, None, :], reg) @ u_i[:, :, None])[:, :, 0]
    return g * sc[None, :]


def transmissibility(U_i: np.ndarray, U_t: np.ndarray,
                     reg: Regularisation = Regularisation()) -> np.ndarray:
    r"""The transmissibility :math:`T = U_t U_i^{\dagger}` from indicators to targets,
    equation (3) of the module docstring, ``(n_omega, n_t, n_i)``, from operating responses
    ``U_i`` ``(n_omega, n_i, n_o)`` and ``U_t`` ``(n_omega, n_t, n_o)`` under ``n_o``
    operating conditions (least squares over the conditions; ``reg`` chooses the
    pseudo-inverse of :math:`U_i`).

    With fewer conditions than indicators :math:`U_i U_i^{\dagger} \ne I` and ``T`` is not
    determined by the data: refused.  Conditions that are not independent, or fewer sources
    than indicators (a rank below ``n_i``), are not detected here (the singular values of
    ``U_i`` show them); the default inversion drops the singular values that are round-off,
    so that ``T`` is then the minimum-norm least-squares one, :math:`H_{ts} H_{is}^{\dagger}`
    when the ``n_s < n_i`` sources are all excited (an untruncated pseudo-inverse would
    divide by that round-off).

    Raises:
        ValueError: fewer conditions than indicators, shapes that do not match, values not
            finite.
    """
    what = "operational TPA"
    if U_i.ndim != 3 or U_t.ndim != 3 or U_i.shape[0] != U_t.shape[0] \
            or U_i.shape[2] != U_t.shape[2]:
        raise ValueError(f"{what}: indicator responses of shape {list(U_i.shape)} and target "
                         f"responses of shape {list(U_t.shape)} do not match (frequencies, "
                         f"points, conditions)")
    _finite(U_i, "indicator responses", what)
    _finite(U_t, "target responses", what)
    n_i, n_o = U_i.shape[1:]
    if n_o < n_i:
        raise ValueError(f"operational TPA needs at least as many operating conditions as "
                         f"indicators: {n_o} conditions < {n_i} indicators")
    return U_t @ regularised_inverse(U_i, reg)


def operational_contributions(T: np.ndarray, u_i: np.ndarray) -> np.ndarray:
    r"""The contribution of each indicator path ``k`` to each target under one operating
    condition, :math:`c_k = T_{:,k} u_{i,k}`, equation (4), ``(n_omega, n_t, n_i)``; summed
    over ``k`` it is the predicted target response :math:`T u_i`.

    Raises:
        ValueError: ``u_i`` not ``(n_omega, n_i)`` for ``T`` of shape ``(n_omega, n_t, n_i)``.
    """
    if T.ndim != 3 or u_i.shape != (T.shape[0], T.shape[2]):
        raise ValueError(f"operational contributions: transmissibility of shape "
                         f"{list(T.shape)} and indicator responses of shape "
                         f"{list(u_i.shape)} do not match")
    return T * u_i[:, None, :]
