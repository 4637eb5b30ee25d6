"""What the rod makers share (:mod:`substruct.models.rod`, :mod:`substruct.models.enrichment`):
support names, checked lengths and distributions, positions of points on a rod, a rod's
drawing, and the Ritz functions of the uniform rod.

Points on a rod are positions ``x`` (a float, or a string ``"x=..."``); a point outside
``[0, L]`` (tolerance ``1e-9 L``) raises :class:`~substruct.substructure.PointError`.
"""

from __future__ import annotations

from typing import Any, Callable, Sequence

import numpy as np
import scipy.sparse as sp

from substruct.substructure import Geometry, PointError
from substruct.vocabulary import SUPPORTS

__all__ = ["SUPPORTS", "Profile", "check_support", "check_length", "as_profile",
           "check_positive", "rod_point", "point_label", "line_geometry", "drawing_points",
           "ritz_functions"]

"""Support names: end condition at ``x = 0``, then at ``x = L``."""

#: A distribution along the rod: a numpy-vectorized callable of ``x``.
Profile = Callable[[np.ndarray], np.ndarray]


def check_support(support: str, name: str) -> None:
    """Raise ``ValueError`` unless ``support`` is one of :data:`SUPPORTS`."""
    if support not in SUPPORTS:
        raise ValueError(f"{name}: unknown support {support!r}; expected one of {SUPPORTS}")


def check_length(name: str, length: float) -> float:
    """The length as a float; ``ValueError`` unless it is positive and finite."""
    L = float(length)
    if not np.isfinite(L) or L <= 0:
        raise ValueError(f"{name}: length must be positive and finite, got {length!r}")
    return L


def as_profile(name: str, field: str, f: Profile | float) -> Profile:
    """A vectorized callable for a constant or a callable distribution."""
    if callable(f):
        return lambda x: np.broadcast_to(np.asarray(f(x), dtype=float), np.shape(x))
    value = float(f)
    return lambda x: np.full(np.shape(x), value)


def check_positive(name: str, field: str, values: np.ndarray) -> None:
    """Raise ``ValueError`` naming ``field`` unless every value is positive and finite."""
    if not np.all(np.isfinite(values)) or np.any(values <= 0):
        bad = values[~(np.isfinite(values) & (values > 0))][0]
        raise ValueError(f"{name}: {field}(x) must be positive and finite on [0, L]; "
                         f"found {field} = {bad!r}")


def rod_point(name: str, where: Any, L: float) -> float:
    """The position ``x`` of a point reference on a rod of length ``L`` (clipped to ``[0, L]``)."""
    ref = where
    if isinstance(ref, str):
        ref = ref.strip()
        ref = ref[2:] if ref.startswith("x=") else ref
    if isinstance(ref, bool):
        raise PointError(f"{name}: a point on a rod is a position x, got {where!r}")
    try:
        x = float(ref)
    except (TypeError, ValueError):
        raise PointError(f"{name}: a point on a rod is a position x in [0, {L:g}], "
                         f"got {where!r}") from None
    tol = 1e-9 * L
    if not np.isfinite(x) or x < -tol or x > L + tol:
        raise PointError(f"{name}: point x = {x!r} is not on the rod [0, {L:g}]")
    return min(max(x, 0.0), L)


def point_label(x: float) -> str:
    """The glyph name of a drawing node at ``x`` (``"x=50"``)."""
    return f"x={float(x):.12g}"


def line_geometry(xs: np.ndarray, rows: sp.csr_array, glyphs: dict[str, int]) -> Geometry:
    """Drawing nodes at ``(xs, 0, 0)``; ``rows`` (N x n) gives their axial displacement."""
    N, n = rows.shape
    points = np.column_stack([xs, np.zeros(N), np.zeros(N)])
    rows = sp.coo_array(rows)
    interp = sp.csr_array((rows.data, (3 * rows.row, rows.col)), shape=(3 * N, n))
    cells = [("line", np.column_stack([np.arange(N - 1), np.arange(1, N)]))]
    return Geometry(points=points, cells=cells, interp=interp, glyphs=glyphs)


def drawing_points(L: float, base: np.ndarray, nodes_at: Sequence[float], name: str
                    ) -> tuple[np.ndarray, dict[str, int]]:
    """``base`` drawing positions merged with ``nodes_at``; glyphs name the latter."""
    marks = [rod_point(name, x, L) for x in nodes_at]
    xs = np.unique(np.concatenate([base, marks]))
    glyphs = {point_label(x): int(np.argmin(abs(xs - x))) for x in marks}
    return xs, glyphs


def ritz_functions(support: str, L: float, n: int
                    ) -> Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]:
    """``x -> (phi, dphi)``, each ``(n, len(x))``: the eigenfunctions of the uniform rod."""
    i = np.arange(1, n + 1, dtype=float)[:, None]
    kind, k = {
        "fixed-free": ("sin", (2 * i - 1) * np.pi / (2 * L)),
        "fixed-fixed": ("sin", i * np.pi / L),
        "free-free": ("cos", (i - 1) * np.pi / L),
        "free-fixed": ("cos", (2 * i - 1) * np.pi / (2 * L)),
    }[support]

    def functions(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        kx = k * np.asarray(x, dtype=float)[None, :]
        if kind == "sin":
            return np.sin(kx), k * np.cos(kx)
        return np.cos(kx), -k * np.sin(kx)

    return functions
