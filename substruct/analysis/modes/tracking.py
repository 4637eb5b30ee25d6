r"""Modes tracked through a study: identity kept by shape, not by frequency order.

Between consecutive samples ``s`` and ``s + 1`` of a parameter, the modes are paired by the
assignment that maximizes the total modal assurance criterion
(:func:`substruct.analysis.modes.mac.mac_matrix`), i.e. the Hungarian algorithm
(:func:`scipy.optimize.linear_sum_assignment`) on the cost

.. math::  c_{jk} = 1 - \mathrm{MAC}(\phi^{(s)}_j, \phi^{(s+1)}_k)
           + w_f \frac{|f^{(s)}_j - f^{(s+1)}_k|}{\max(f^{(s)}_j, f^{(s+1)}_k)} ,

(``w_f`` = ``frequency_weight``, 0 by default: shape alone).  The pairing is a permutation, so
two modes never take the same track.  A track's frequencies then cross another's where two
modes exchange their frequency order (a **crossing**: uncoupled modes pass through each
other); two neighbouring sorted frequencies that approach to a local minimum of their gap
without crossing while their shapes rotate into each other (the MAC of each track's shape
from the first sample to the last drops below ``veer_mac``) is a **veering** (coupled modes repel).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
from scipy.optimize import linear_sum_assignment

from substruct.analysis.modes.mac import mac_matrix

__all__ = ["Tracked", "pair_by_assignment", "track_modes"]


@dataclass(frozen=True)
class Tracked:
    """Modes followed through ``n_s`` samples.

    Attributes:
        order: ``(n_s, n_m)``: ``order[s, t]`` is the index, among sample ``s``'s modes, of
            track ``t`` (track ``t`` is mode ``t`` of the first sample).
        frequency: ``(n_s, n_m)`` the tracked frequencies.
        mac: ``(n_s - 1, n_m)`` the MAC of each track between consecutive samples.
        crossings: ``(s, t, u)``: tracks ``t < u`` exchange their order after sample ``s``
            (at the next sample, or through a tie).
        veerings: ``(s, t, u)``: tracks ``t`` and ``u`` (neighbours) approach closest at
            sample ``s`` without crossing, their shapes exchanged.
    """

    order: np.ndarray
    frequency: np.ndarray
    mac: np.ndarray
    crossings: list[tuple[int, int, int]]
    veerings: list[tuple[int, int, int]]


def pair_by_assignment(mac: np.ndarray, f0: np.ndarray | None = None,
                       f1: np.ndarray | None = None, frequency_weight: float = 0.0
                       ) -> np.ndarray:
    """``pair[j]``: the mode of the second set that mode ``j`` of the first becomes (the
    assignment of least cost, module docstring; ``-1`` if the second set is shorter).

    Raises:
        ValueError: a negative ``frequency_weight``.
    """
    if frequency_weight < 0:
        raise ValueError(f"frequency_weight must be >= 0, got {frequency_weight!r}")
    cost = 1.0 - np.asarray(mac, dtype=float)
    if frequency_weight and f0 is not None and f1 is not None:
        a = np.asarray(f0, dtype=float)[:, None]
        b = np.asarray(f1, dtype=float)[None, :]
        cost = cost + frequency_weight * np.abs(a - b) / np.maximum(
            np.maximum(np.abs(a), np.abs(b)), 1e-300)
    rows, cols = linear_sum_assignment(cost)
    pair = -np.ones(cost.shape[0], dtype=int)
    pair[rows] = cols
    return pair


def track_modes(frequencies: Sequence[np.ndarray], shapes: Sequence[np.ndarray],
                frequency_weight: float = 0.0, veer_mac: float = 0.5) -> Tracked:
    r"""Follow the modes of the first sample through the others (module docstring).

    Args:
        frequencies: per sample, ``n_m`` frequencies (any order).
        shapes: per sample, ``n x n_m`` shapes (columns, the same coordinates throughout).
        frequency_weight: ``w_f`` of the cost.
        veer_mac: a veering needs the track's MAC between its shapes at the first and the last
            sample below this.

    Raises:
        ValueError: no sample, or samples with different numbers of modes or coordinates.
    """
    if not frequencies or len(frequencies) != len(shapes):
        raise ValueError("mode tracking needs frequencies and shapes for each sample")
    F = [np.asarray(f, dtype=float) for f in frequencies]
    P = [np.asarray(p) for p in shapes]
    nm = F[0].size
    if any(f.size != nm or p.shape != P[0].shape or p.shape[1] != nm for f, p in zip(F, P)):
        raise ValueError("every sample needs the same number of modes and coordinates")
    ns = len(F)
    order = np.empty((ns, nm), dtype=int)
    order[0] = np.arange(nm)
    macs = np.empty((max(ns - 1, 0), nm))
    for s in range(ns - 1):
        cur = order[s]
        M = mac_matrix(P[s][:, cur], P[s + 1])
        pair = pair_by_assignment(M, F[s][cur], F[s + 1], frequency_weight)
        order[s + 1] = pair
        macs[s] = M[np.arange(nm), pair]
    freq = np.take_along_axis(np.stack(F), order, axis=1)
    crossings = [(s, t, u) for t in range(nm) for u in range(t + 1, nm)
                 for s in _sign_changes(freq[:, t] - freq[:, u])]
    veerings = _veerings(freq, order, P, crossings, veer_mac)
    return Tracked(order=order, frequency=freq, mac=macs, crossings=crossings,
                   veerings=veerings)


def _sign_changes(d: np.ndarray) -> list[int]:
    """The samples after which ``d`` changes sign (exact ties skipped: the sample before a
    tie that the sign passes through)."""
    out, last, at = [], 0.0, -1
    for s, v in enumerate(np.sign(d)):
        if v == 0:
            continue
        if last and v != last:
            out.append(at)
        last, at = v, s
    return out


def _veerings(freq: np.ndarray, order: np.ndarray, P: list[np.ndarray],
              crossings: list[tuple[int, int, int]], veer_mac: float
              ) -> list[tuple[int, int, int]]:
    """Local minima of the gap between tracks adjacent in frequency, with no crossing of the
    pair and the track's shape changed over the study (MAC below ``veer_mac``)."""
    ns, nm = freq.shape
    crossed = {(t, u) for _, t, u in crossings}
    out = []
    for t in range(nm):
        for u in range(t + 1, nm):
            if (t, u) in crossed:
                continue
            lo, hi = np.minimum(freq[:, t], freq[:, u]), np.maximum(freq[:, t], freq[:, u])
            between = [np.any((freq[:, v] > lo) & (freq[:, v] < hi)) for v in range(nm)
                       if v not in (t, u)]
            if any(between):
                continue  # not neighbours
            gap = hi - lo
            for s in range(1, ns - 1):
                if gap[s] < gap[s - 1] and gap[s] <= gap[s + 1]:
                    first = P[0][:, [order[0, t]]]
                    last = P[-1][:, [order[-1, t]]]
                    if float(mac_matrix(first, last)[0, 0]) < veer_mac:
                        out.append((s, t, u))
    return out
