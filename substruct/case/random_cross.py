r"""Correlated inputs of ``analysis.random``: the off-diagonal terms of the input cross-spectral
matrix, given pair by pair as an ordinary coherence and a phase.

For force or base acceleration PSDs :math:`S_{ii}(f)`, :math:`S_{jj}(f)` (their tables) and a pair ``[i, j]`` with
coherence :math:`\gamma^2 = |S_{ij}|^2 / (S_{ii} S_{jj})` in [0, 1] and phase :math:`\theta`
(degrees, input ``i`` leading ``j``),

.. math::  S_{ij}(f) = \sqrt{\gamma^2 S_{ii}(f) S_{jj}(f)}\; e^{i\theta},
           \qquad S_{ji} = \overline{S_{ij}} ,

pairs not listed are uncorrelated (0).  Each 2 x 2 block is semidefinite by construction; with
three or more inputs the whole matrix need not be (coherences 1, 1 and phases 0, 0, 180 degrees
between three inputs cannot all hold), which the run refuses at the first frequency where its
smallest eigenvalue is negative.
"""

from __future__ import annotations

from typing import Annotated, Sequence

import numpy as np
from pydantic import Field

from substruct.case.errors import FieldError
from substruct.case.fields import Number, Point, StrictModel

__all__ = ["CrossPsd", "check_cross", "cross_matrix"]


class CrossPsd(StrictModel):
    """One correlated pair of inputs: ``between: [P@a, Q@b]`` (two of ``forces``' points, or two
    names of ``bases``),
    ``coherence`` :math:`\\gamma^2` in [0, 1] and ``phase`` in degrees (default 0)."""

    between: Annotated[list[Point], Field(min_length=2, max_length=2)]
    coherence: Annotated[Number, Field(ge=0, le=1)]
    phase: Annotated[Number, Field(ge=-360, le=360)] = 0.0


def check_cross(points: Sequence[str], cross: Sequence[CrossPsd]) -> None:
    """Refuse a pair naming an input (a force point, a base's name) that is not one of ``points`` (or is two of them), a
    point paired with itself, or a pair given twice.

    Raises:
        FieldError: at ``cross[k].between``.
    """
    seen: set[frozenset[str]] = set()
    for k, c in enumerate(cross):
        for i, p in enumerate(c.between):
            if p not in points:
                raise FieldError(("cross", k, "between", i), "not one of the inputs ("
                                 f"{', '.join(points) or 'none: cross needs forces or bases'})",
                                 p)
            if list(points).count(p) > 1:
                raise FieldError(("cross", k, "between", i), "a point with two force PSDs "
                                 "(give it one table)", p)
        if c.between[0] == c.between[1]:
            raise FieldError(("cross", k, "between"), "a pair of two different inputs (an "
                             "input's own PSD is its table)", c.between)
        key = frozenset(c.between)
        if key in seen:
            raise FieldError(("cross", k, "between"), "this pair is given twice", c.between)
        seen.add(key)


def cross_matrix(points: Sequence[str], cross: Sequence[CrossPsd], auto: np.ndarray
                 ) -> np.ndarray:
    r"""The input cross-spectral matrix ``(n_f, p, p)`` from the auto-PSDs ``auto``
    ``(n_f, p)`` (columns in the order of ``points``) and the pairs (module docstring)."""
    nf, p = auto.shape
    S = np.zeros((nf, p, p), dtype=complex)
    idx = np.arange(p)
    S[:, idx, idx] = auto
    for c in cross:
        i, j = points.index(c.between[0]), points.index(c.between[1])
        sij = np.sqrt(c.coherence * auto[:, i] * auto[:, j]) * np.exp(1j * np.deg2rad(c.phase))
        S[:, i, j] = sij
        S[:, j, i] = np.conj(sij)
    return S
