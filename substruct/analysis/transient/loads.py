r"""Loads with discontinuities, integrated to second order at any instant.

A one-step scheme of the Newmark family sees the load through its values at the ends of each
step, as if it varied linearly over the step.  A load that jumps inside a step (a step load
that starts between two instants), or at an instant where the nodal value is the value after
the jump, is then off by a fraction of the jump over a whole step: an error in the impulse of
order :math:`h`, and a first-order response.  Here each step :math:`[t_n, t_{n+1}]` that holds
a breakpoint of a load (where the load or its slope jumps) gets instead the linear function
:math:`\ell(s) = p\,(1 - s/h) + q\, s/h` with the same integral and first moment as the load
over the step,

.. math::  \int_0^h \ell\, ds = \int_0^h f(t_n + s)\, ds = m_0, \qquad
           \int_0^h s\, \ell\, ds = \int_0^h s\, f(t_n + s)\, ds = m_1,

.. math::  q = \frac{6 m_1}{h^2} - \frac{2 m_0}{h}, \qquad p = \frac{4 m_0}{h} - \frac{6 m_1}{h^2}.

The forced response over a step is :math:`\int_0^h e^{A(h - s)} g(t_n + s)\, ds
= \sum_k A^k/k! \int_0^h (h - s)^k g\, ds`: matching :math:`m_0` and :math:`m_1` leaves an error
of order :math:`h^3` in the one step that holds the breakpoint, so the scheme stays second order
(:func:`substruct.analysis.transient.integrators.integrate` recomputes the acceleration where the load at
the start of a step differs from the one it was computed with, as at :math:`t = 0`).  The
moments are Gauss-Legendre sums over the smooth pieces between the breakpoints (5 points each,
exact for polynomials of degree 9), so the load is never evaluated at a breakpoint.  A step at
:math:`t = 0` has nothing to correct: its first step already sees the value after the jump.
"""

from __future__ import annotations

from typing import Callable, Mapping, Sequence

import numpy as np

from substruct.analysis.transient.integrators import Scheme

__all__ = ["GAUSS_POINTS", "step_pairs", "merge_pairs", "for_scheme"]

#: Gauss-Legendre points per smooth piece of a step.
GAUSS_POINTS = 5


def _moments(values: Callable[[np.ndarray], np.ndarray], t0: float, h: float,
             cuts: Sequence[float]) -> tuple[float, float]:
    r"""``(m0, m1)``: :math:`\int_0^h f(t_0 + s) ds` and :math:`\int_0^h s f(t_0 + s) ds`,
    Gauss-Legendre on the pieces between ``cuts`` (offsets in ``(0, h)``)."""
    x, w = np.polynomial.legendre.leggauss(GAUSS_POINTS)
    edges = [0.0, *sorted(c for c in cuts if 0.0 < c < h), h]
    s_all, w_all = [], []
    for lo, hi in zip(edges[:-1], edges[1:]):
        if hi > lo:
            s_all.append(lo + (hi - lo) * (x + 1) / 2)
            w_all.append(w * (hi - lo) / 2)
    s, wt = np.concatenate(s_all), np.concatenate(w_all)
    fv = np.asarray(values(t0 + s), dtype=float)
    return float(wt @ fv), float(wt @ (s * fv))


def step_pairs(values: Callable[[np.ndarray], np.ndarray], breaks: Sequence[float], dt: float,
               n_steps: int) -> dict[int, tuple[float, float]]:
    """For each step ``n`` (over :math:`[n\\,dt, (n+1)\\,dt]`) that holds a breakpoint of the
    load (ends included), the ``(start, end)`` values of the linear function with the load's
    integral and first moment over the step (module docstring).

    Args:
        values: the load at an array of instants.
        breaks: the instants where the load or its slope jumps.
        dt, n_steps: the constant step and the number of steps.
    """
    out: dict[int, tuple[float, float]] = {}
    for b in breaks:
        if not np.isfinite(b) or b < 0.0 or b > n_steps * dt:
            continue
        k = b / dt
        steps = {int(np.floor(k)) - 1, int(np.floor(k)), int(np.ceil(k))}
        for n in sorted(steps):
            if n < 0 or n >= n_steps or n in out:
                continue
            t0 = n * dt
            if not t0 <= b <= t0 + dt:
                continue
            cuts = [c - t0 for c in breaks if t0 < c < t0 + dt]
            m0, m1 = _moments(values, t0, dt, cuts)
            q = 6.0 * m1 / dt ** 2 - 2.0 * m0 / dt
            out[n] = (4.0 * m0 / dt - 6.0 * m1 / dt ** 2, q)
    return out


def merge_pairs(columns: Sequence[dict[int, tuple[float, float]]], f: np.ndarray
                ) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """The pairs of every load column in one map ``step -> (start, end)`` (``L`` each), the
    nodal values of ``f`` for the columns without a pair at that step."""
    out: dict[int, tuple[np.ndarray, np.ndarray]] = {}
    for j, col in enumerate(columns):
        for n, (p, q) in col.items():
            if n not in out:
                out[n] = (np.array(f[n], dtype=float), np.array(f[n + 1], dtype=float))
            out[n][0][j], out[n][1][j] = p, q
    return out


def for_scheme(pairs: Mapping[int, tuple[np.ndarray, np.ndarray]], s: Scheme
               ) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    r"""The pairs as the scheme ``s`` must see them to take the load's impulse over the step.

    The velocity gained over a step from a load varying linearly from :math:`p` to :math:`q`
    is :math:`h\,[(1 - c)\, p + c\, q]/m` to leading order, with
    :math:`c = \gamma (1 - \alpha_f) / (1 - \alpha_m)` (the acceleration at the start from
    :math:`p`, the one at the end from the balance at :math:`t_{n+1-\alpha_f}`); the load's
    impulse is :math:`h (p_0 + q_0)/2 = m_0`.  Shifting both values by
    :math:`\delta = (c - \tfrac12)(p_0 - q_0)` makes them equal, so the velocity is right to
    :math:`O(h^2)` over the step that holds the jump and the response stays second order.
    Newmark's average acceleration has :math:`c = \tfrac12` (no shift); so has
    generalized-alpha with :math:`\rho_\infty = 1`.
    """
    c = s.gamma * (1.0 - s.alpha_f) / (1.0 - s.alpha_m)
    if c == 0.5:
        return dict(pairs)
    out = {}
    for n, (p, q) in pairs.items():
        shift = (c - 0.5) * (np.asarray(p) - np.asarray(q))
        out[n] = (p + shift, q + shift)
    return out
