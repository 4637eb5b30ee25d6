r"""The state at ``t = 0`` of a constrained transient run: the constrained static state, and the
check that an initial state satisfies the constraints.

The constrained static state under the load at ``t = 0`` solves

.. math::  K q + A^T \lambda = P(0), \qquad A q = b(0)

(the stationary point of :math:`\tfrac12 q^T K q - q^T P(0)` on :math:`A q = b(0)`), by one
factorization of the saddle-point matrix on the independent rows of ``A``, scaled by
:math:`\beta = |K| / |A|` so that both blocks weigh alike.  It is determined when ``K`` is
definite on the null space of ``A``; a structure that can move freely (a rigid-body motion
the constraints do not hold) has no static state, and is refused.

A given initial state must satisfy the constraints and their derivative,
:math:`A q_0 = b(0)`, :math:`A \dot q_0 = \dot b(0)` (eqs 5, 10: the constraint holds at every
instant); one that does not is refused with its residual, never projected silently, since a
projection would start the run from a state other than the one asked for.

A massless coordinate that the constraints leave free follows its static equation
:math:`K_s q = P_s` (eq 10 with no mass): its velocity is that equation differentiated, not a
state of its own.  :func:`massless_velocity` puts the velocity of such motions on it (where
none was given there: a velocity given at the coordinates with mass only), and refuses a
velocity given there that differs from it.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.linalg as sla
import scipy.sparse.linalg as spla

from substruct.linalg.constraints import independent_rows
from substruct.linalg.factorize import factorizer
from substruct.linalg.scaling import massless_coordinates

__all__ = ["INITIAL_TOLERANCE", "InitialStateError", "static_state", "check_initial",
           "massless_velocity"]

#: The largest relative residual of an initial state on the (equilibrated) constraints.
INITIAL_TOLERANCE = 1e-9


class InitialStateError(ValueError):
    """The initial state asked for cannot be taken (bad input about ``initial``)."""


def static_state(K: sp.sparray, A: sp.csr_array, b: np.ndarray, load: np.ndarray
                 ) -> np.ndarray:
    r"""``q``: :math:`K q + A^T \lambda = P`, :math:`A q = b` (module docstring); ``A``
    equilibrated (rows of unit norm).

    Raises:
        InitialStateError: the static problem is singular (a rigid-body motion or a massless
            mechanism the constraints leave free), or its solution misses the constraints.
    """
    n = K.shape[0]
    Ks = sp.csr_array(K, dtype=float)
    if A.shape[0]:
        rows = independent_rows(A)
        Ak, bk = sp.csr_array(A[rows.keep]), np.asarray(b, dtype=float)[rows.keep]
    else:
        Ak, bk = sp.csr_array((0, n)), np.zeros(0)
    beta = max(float(spla.norm(Ks)), 1e-300) / max(float(spla.norm(Ak)) if Ak.shape[0]
                                                    else 1.0, 1e-300)
    big = sp.csc_array(sp.block_array([[Ks, beta * Ak.T], [beta * Ak, None]], format="csc")
                       if Ak.shape[0] else sp.csc_array(Ks))
    rhs = np.concatenate([np.asarray(load, dtype=float), beta * bk])
    try:
        x = factorizer("saddle" if Ak.shape[0] else "superlu", spd=False)(big)(rhs)
    except Exception:
        raise InitialStateError("initial: static: the static state is not determined (the structure "
                         "can move freely: a rigid-body motion or a mechanism the constraints "
                         "do not hold)") from None
    q = np.asarray(x[:n], dtype=float)
    scale = max(float(np.abs(q).max(initial=0.0)), float(np.abs(bk).max(initial=0.0)), 1e-300)
    misfit = float(np.abs(Ak @ q - bk).max(initial=0.0)) if Ak.shape[0] else 0.0
    equilibrium = float(np.abs(Ks @ q + beta * (Ak.T @ x[n:]) - load).max(initial=0.0))
    ref = max(float(np.abs(load).max(initial=0.0)), float(spla.norm(Ks, np.inf)) * scale,
              1e-300)
    if not np.all(np.isfinite(q)) or misfit > 1e-8 * scale or equilibrium > 1e-8 * ref:
        raise InitialStateError("initial: static: the static state is not determined (the structure "
                         "can move freely: a rigid-body motion or a mechanism the constraints "
                         f"do not hold; residual {max(misfit / scale, equilibrium / ref):.3g})")
    return q


def check_initial(A: sp.csr_array, d0: np.ndarray, v0: np.ndarray, b0: np.ndarray,
                  rate0: np.ndarray | float) -> None:
    r"""Refuse an initial state off the constraints: :math:`|A q_0 - b(0)|` or
    :math:`|A \dot q_0 - \dot b(0)|` (``A`` equilibrated) above :data:`INITIAL_TOLERANCE`
    times the scale of the state (module docstring).

    Raises:
        InitialStateError: one line with the residual.
    """
    if not A.shape[0]:
        return
    rate = np.broadcast_to(np.asarray(rate0, dtype=float), b0.shape)
    dscale = max(float(np.abs(d0).max(initial=0.0)), float(np.abs(b0).max(initial=0.0)), 1e-300)
    for name, vec, rhs, scale in (("displacement", d0, b0, dscale),
                                  ("velocity", v0, rate, None)):
        bad = float(np.abs(A @ vec - rhs).max(initial=0.0))
        ref = scale if scale is not None else max(float(np.abs(vec).max(initial=0.0)),
                                                  float(np.abs(rhs).max(initial=0.0)), 1e-300)
        if bad > INITIAL_TOLERANCE * ref:
            raise InitialStateError(f"the initial {name} violates the constraints: residual "
                                    f"{bad:.3g} on the equilibrated rows (relative "
                                    f"{bad / ref:.3g} > {INITIAL_TOLERANCE:g}; "
                             f"the state must satisfy A q = b at t = 0"
                             + (", e.g. initial: static)" if name == "displacement" else ")"))


def massless_velocity(M: sp.sparray, C: sp.sparray | None, K: sp.sparray, A: sp.sparray,
                      v0: np.ndarray) -> np.ndarray:
    r"""``v0`` with the velocity of the massless motions the constraints leave free put on
    their static equation differentiated (the load taken as locally constant, as for the
    initial acceleration):

    .. math::  v = v_0 + Z y, \qquad Z^T K Z\, y = -Z^T K v_0 ,

    ``Z`` an orthonormal basis of the motions with :math:`z_j = 0` at every coordinate with
    mass and :math:`A z = 0` (every massless coordinate when there is no constraint).  Such a
    motion has no velocity of its own; one given there (:math:`Z^T v_0 \ne 0`) must be that
    of the equation, to :data:`INITIAL_TOLERANCE` of the largest velocity.  ``v0`` is
    returned as it is when it is zero, when no massless motion is free, when a free one is
    damped (:math:`Z^T C Z \ne 0`: its velocity is then set by the damper, left to the
    integration) or held by nothing (:math:`Z^T K Z` singular: refused by the initial
    acceleration).

    Raises:
        InitialStateError: a velocity given at a free massless coordinate that differs from
            its static equation's; one line with the coordinate, the value and the one
            expected.
    """
    v0 = np.asarray(v0, dtype=float)
    s = np.flatnonzero(massless_coordinates(M))
    if not s.size or not np.any(v0):
        return v0
    As = sp.csr_array(A)[:, s].toarray() if A.shape[0] else np.zeros((0, s.size))
    Zs = sla.null_space(As) if As.shape[0] else np.eye(s.size)
    if not Zs.shape[1]:
        return v0
    Ks = sp.csr_array(K)[s]
    G = Zs.T @ (Ks[:, s] @ Zs)
    if C is not None and np.any(Zs.T @ (sp.csr_array(C)[s][:, s] @ Zs)):
        return v0
    try:
        y = np.linalg.solve(G, -(Zs.T @ (Ks @ v0)))
    except np.linalg.LinAlgError:
        return v0
    v = v0.copy()
    v[s] += Zs @ y
    scale = max(float(np.abs(v0).max()), float(np.abs(v).max()))
    given = np.abs(Zs.T @ v0[s]).max() > INITIAL_TOLERANCE * scale
    if given and np.abs(v - v0).max() > INITIAL_TOLERANCE * scale:
        j = int(s[np.argmax(np.abs(v[s] - v0[s]))])
        raise InitialStateError(
            f"the initial velocity of coordinate {j + 1}, which has no mass and no "
            f"constraint to fix it, is that of its static equation ({v[j]:.6g}), not a state "
            f"of its own: give the velocity at the coordinates with mass only, got "
            f"{v0[j]:.6g}")
    return v
