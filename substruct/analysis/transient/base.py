r"""Base excitation of grounded supports: a prescribed ground motion :math:`g(t)` as the
nonhomogeneous constraint of eqs (5) and (10),

.. math::  A q = b + e\, g(t), \qquad A \ddot q = e\, \ddot g(t),

``e`` the rows of ``A`` that ground the excited points (a row :math:`c\, u(p) = b_i` becomes
:math:`c\, u(p) = b_i + c\, g(t)`).  The motion enters the generalized-inverse step as the
right-hand side of its correction; the structure's response is absolute.

The ground history is made consistent with the integrator: given the acceleration
:math:`\ddot g(t_k)` (an accelerogram), the scheme's acceleration variable :math:`\ddot g_k`
solves its balance at the shifted instants, :math:`(1 - \alpha_m) \ddot g_{k+1} + \alpha_m
\ddot g_k = (1 - \alpha_f) \ddot g(t_{k+1}) + \alpha_f \ddot g(t_k)` (the identity for
Newmark), and :math:`g_k`, :math:`\dot g_k` follow from the scheme's own updates from rest,

.. math::  g_{k+1} = g_k + h \dot g_k + h^2 [(\tfrac12 - \beta) \ddot g_k + \beta \ddot g_{k+1}],
           \qquad \dot g_{k+1} = \dot g_k + h [(1 - \gamma) \ddot g_k + \gamma \ddot g_{k+1}];

given the displacement :math:`g_k`, the same updates are solved for :math:`\ddot g_{k+1}`
from :math:`\dot g_0, \ddot g_0`.  So :math:`A q_k = b + e g_k`, :math:`A \dot q_k = e \dot g_k`,
:math:`A \ddot q_k = e \ddot g_k` hold together at every step, and the projections of the step
are exact.

The relative motion is measured from the pseudo-static position :math:`r g(t)`, ``r`` the
influence vector: the static displacement of a unit ground motion,

.. math::  K r + A^T \mu = 0, \qquad A r = e ,

(the rigid translation for a structure held only at the moving supports), so that
:math:`q = r g + w` with :math:`A w = b` and
:math:`M \ddot w + C \dot w + K w = P - M r \ddot g - C r \dot g + Q^c`: the relative-motion
form with the effective load :math:`-M r \ddot g`, which the null-space and modal forms integrate.

That load is a load like any other, which generalized-alpha takes at the shifted instant
:math:`t_{k+1-\alpha_f}`, while the generalized-inverse step puts the ground's acceleration
variable at :math:`t_{k+1-\alpha_m}`.  The two forms integrate the same motion only if the load's
values :math:`p_k` satisfy :math:`(1 - \alpha_f) p_{k+1} + \alpha_f p_k = (1 - \alpha_m) \ddot
g_{k+1} + \alpha_m \ddot g_k`, :math:`p_0 = \ddot g_0` (:func:`load_acceleration`): the physical
acceleration :math:`\ddot g(t_k)` (the accelerogram itself, or the displacement's second
derivative to second order), not the scheme's variable, which generalized-alpha puts
:math:`O(h)` away from it (with :math:`\ddot g_k` as the load the relative forms are first
order).  For Newmark :math:`p_k = \ddot g_k`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from substruct.analysis.errors import AnalysisInputError
from substruct.analysis.transient.integrators import Scheme
from substruct.linalg.constraints import independent_rows
from substruct.linalg.factorize import factorizer

__all__ = ["BaseMotion", "Motion", "ground_history", "influence", "load_acceleration"]


@dataclass(frozen=True)
class BaseMotion:
    r"""A prescribed ground motion at the constraint rows ``rows`` (``m``, unequilibrated:
    :math:`A q = b + \text{rows}\, g(t)`).

    Attributes:
        rows: ``m``, the coefficient of :math:`g` in each row of ``A`` (0 for the others).
        kind: ``"acceleration"`` or ``"displacement"``: what ``values`` are.
        values: ``n_steps + 1``, :math:`\ddot g` or :math:`g` at :math:`t_k = k\, dt`.
        rate0, accel0: :math:`\dot g(0)`, :math:`\ddot g(0)` of a displacement (ignored for an
            acceleration, which starts from rest).
    """

    rows: np.ndarray
    kind: str
    values: np.ndarray
    rate0: float = 0.0
    accel0: float = 0.0


@dataclass(frozen=True)
class Motion:
    r"""The ground motion as the integration uses it.

    Attributes:
        e: ``m``, the equilibrated rows' coefficients of :math:`g`.
        g: ``(n_steps + 1) x 3``: :math:`g, \dot g, \ddot g` at every step.
        r: ``n``, the influence vector (module docstring).
        load: ``(n_steps + 1) x 3``: :math:`p_k, g_k, \dot g_k`, the ground's factors of the
            effective loads :math:`-M r \ddot g`, :math:`-K r g`, :math:`-C r \dot g` of the
            relative-motion form (:func:`load_acceleration`); ``g`` when not given.
    """

    e: np.ndarray
    g: np.ndarray
    r: np.ndarray
    load: np.ndarray | None = None

    def load_columns(self, count: int) -> np.ndarray:
        r"""``(n_steps + 1) x count``: the first ``count`` of :math:`p, g, \dot g`, the factors
        of the effective loads :math:`-M r \ddot g, -K r g, -C r \dot g`."""
        cols = self.g[:, [2, 0, 1]] if self.load is None else self.load
        return np.asarray(cols[:, :count])


def ground_history(kind: str, values: np.ndarray, s: Scheme, h: float, rate0: float = 0.0,
                   accel0: float = 0.0) -> np.ndarray:
    r"""``(n_steps + 1) x 3``: :math:`g_k, \dot g_k, \ddot g_k` consistent with the scheme's
    updates (module docstring).

    Raises:
        ValueError: an unknown ``kind``.
    """
    x = np.asarray(values, dtype=float).ravel()
    out = np.zeros((x.size, 3))
    c1, c2, c3 = h * h * (0.5 - s.beta), h * (1 - s.gamma), s.beta * h * h
    if kind == "acceleration":
        out[0, 2] = x[0]
        for k in range(x.size - 1):
            g, gv, ga = out[k]
            a = ((1 - s.alpha_f) * x[k + 1] + s.alpha_f * x[k] - s.alpha_m * ga) / (1 - s.alpha_m)
            out[k + 1] = g + h * gv + c1 * ga + c3 * a, gv + c2 * ga + s.gamma * h * a, a
        return out
    if kind != "displacement":
        raise ValueError(f"unknown ground motion kind {kind!r}")
    out[0] = x[0], rate0, accel0
    out[:, 0] = x
    for k in range(x.size - 1):
        g, gv, ga = out[k]
        a = (x[k + 1] - g - h * gv - c1 * ga) / c3
        out[k + 1, 1] = gv + c2 * ga + s.gamma * h * a
        out[k + 1, 2] = a
    return out


def load_acceleration(g: np.ndarray, s: Scheme) -> np.ndarray:
    r"""``(n_steps + 1) x 3``: :math:`p_k, g_k, \dot g_k`, the ground history ``g``
    (:func:`ground_history`) as the factors of the relative-motion form's effective loads, with
    :math:`(1 - \alpha_f) p_{k+1} + \alpha_f p_k = (1 - \alpha_m) \ddot g_{k+1} + \alpha_m
    \ddot g_k` and :math:`p_0 = \ddot g_0` (module docstring): the scheme's balance at the
    shifted instants then sees the same ground acceleration in both forms.

    Examples:
        From an accelerogram the load is the accelerogram itself:

        >>> import numpy as np
        >>> from substruct.analysis.transient.integrators import scheme
        >>> s, x = scheme("generalized-alpha", 0.5), np.array([1.0, 3.0, -2.0, 0.5])
        >>> p = load_acceleration(ground_history("acceleration", x, s, 0.1), s)
        >>> bool(np.allclose(p[:, 0], x))
        True
    """
    g = np.asarray(g, dtype=float)
    a = g[:, 2]
    p = np.empty_like(a)
    p[0] = a[0]
    for k in range(a.size - 1):
        p[k + 1] = ((1 - s.alpha_m) * a[k + 1] + s.alpha_m * a[k] - s.alpha_f * p[k]) / (1 - s.alpha_f)
    return np.column_stack([p, g[:, 0], g[:, 1]])


def influence(K: sp.sparray, A: sp.csr_array, e: np.ndarray) -> np.ndarray:
    r"""The influence vector ``r``: :math:`K r + A^T \mu = 0`, :math:`A r = e` (module
    docstring), by one factorization of the saddle-point matrix on the independent rows of
    ``A`` (scaled by :math:`\beta = |K| / |A|`).

    Raises:
        ValueError: the system is singular (the structure is a mechanism with the supports
            held) or ``e`` is inconsistent with dependent rows of ``A``.
    """
    n = K.shape[0]
    rows = independent_rows(A)
    Ak = sp.csr_array(A[rows.keep])
    ek = np.asarray(e, dtype=float)[rows.keep]
    beta = max(float(spla.norm(K)), 1e-300) / max(float(spla.norm(Ak)), 1e-300)
    big = sp.csc_array(sp.block_array([[sp.csr_array(K), beta * Ak.T], [beta * Ak, None]],
                                      format="csc"))
    try:
        x = factorizer("saddle")(big)(np.concatenate([np.zeros(n), beta * ek]))
    except Exception:
        raise AnalysisInputError("the influence vector of the ground motion is not determined: the "
                         "structure is a mechanism with its supports held") from None
    r = np.asarray(x[:n], dtype=float)
    bad = float(np.abs(A @ r - e).max(initial=0.0))
    if not np.all(np.isfinite(r)) or bad > 1e-8 * max(float(np.abs(e).max()), 1e-300):
        raise AnalysisInputError("the ground motion moves constraint rows that other rows hold fixed "
                         f"(residual {bad:.3g})")
    return r
