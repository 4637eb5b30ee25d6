r"""Nodes and displacement components of meshed substructures: the one box selector, the one
component parser and the one position tolerance of the package.

Node positions come from meshes (files written with finite precision, grids built by
``linspace``), so two positions are *the same place* when they differ by at most

.. math::  \tau = \mathtt{NODE\_TOL} \cdot \max_a \big(\max_k x_{k,a} - \min_k x_{k,a}\big),

:data:`NODE_TOL` times the model size (its largest extent along an axis).  That one tolerance
decides

* which nodes a box ``[[xmin, ymin, zmin], [xmax, ymax, zmax]]`` selects (the box is widened
  by :math:`\tau`, so a flat box ``x0 = x1`` picks a plane of nodes): supports of solids
  (:mod:`substruct.models.solid`), interfaces (:mod:`substruct.assembly.interfaces`), the
  support checks of a case (:mod:`substruct.builder.solids`);
* whether a point is a node (a unit row) or lies between nodes (an interpolated row);
* whether the nodes of two meshes match across an interface
  (:func:`substruct.assembly.interfaces.tie_nodes`);
* which nodes lie on the named faces (``xmin`` ... ``zmax``) of generated boxes.

Components are named ``"x"``, ``"y"``, ``"z"`` (also ``"ux"``, any case) or numbered
``0, 1, 2``; a 2D solid has ``x`` and ``y`` only.
"""

from __future__ import annotations

from typing import Any, Iterable

import numpy as np

from substruct.substructure import PointError

__all__ = ["COMPONENTS", "NODE_TOL", "model_size", "node_tolerance", "component_index",
           "component_indices", "parse_box", "nodes_in_box"]

#: Names of the displacement components, in order (``0, 1, 2`` are accepted too).
COMPONENTS = ("x", "y", "z")

#: Relative position tolerance: positions closer than ``NODE_TOL`` times the model size are
#: the same place.  Far below any element size a mesh can have (10^8 elements along a side),
#: far above the round-off of coordinates written with 15 or more significant digits.
NODE_TOL = 1e-8


def model_size(points: np.ndarray) -> float:
    """Largest extent along an axis of the ``(N, d)`` positions ``points`` (1 if there are
    none, never 0)."""
    pts = np.asarray(points, dtype=float)
    if pts.size == 0:
        return 1.0
    return max(float(np.ptp(pts, axis=0).max()), 1e-300)


def node_tolerance(points: np.ndarray, tol: float | None = None) -> float:
    """``tol`` if given, else :data:`NODE_TOL` times :func:`model_size` of ``points``."""
    return float(tol) if tol is not None else NODE_TOL * model_size(points)


def component_index(c: Any, dim: int, owner: str) -> int:
    """The index (0 .. dim-1) of a displacement component ``"x"``/``"ux"``/``0`` ...

    Raises:
        PointError: not a component of a ``dim``-dimensional substructure (the message starts
            with ``owner``, the substructure's name).
    """
    key = c
    if isinstance(c, str):
        name = c.strip().lower()
        name = name[1:] if len(name) == 2 and name[0] == "u" else name
        key = COMPONENTS.index(name) if name in COMPONENTS else c
    if isinstance(key, (int, np.integer)) and not isinstance(key, bool) and 0 <= key < dim:
        return int(key)
    raise PointError(f"{owner}: no displacement component {c!r} in a {dim}D solid "
                     f"(use one of {list(COMPONENTS[:dim])} or 0..{dim - 1})")


def component_indices(components: Any, dim: int, owner: str) -> list[int]:
    """Indices of a list of components (one component alone is a list of one; ``None`` is
    every component of a ``dim``-dimensional substructure).

    Raises:
        PointError: see :func:`component_index`.
    """
    if components is None:
        return list(range(dim))
    if isinstance(components, (str, int, np.integer)):
        components = [components]
    return [component_index(c, dim, owner) for c in _items(components)]


def _items(values: Any) -> Iterable[Any]:
    try:
        return list(values)
    except TypeError:
        raise PointError(f"components must be a list such as ['x', 'y'], got {values!r}") \
            from None


def parse_box(box: Any, dim: int, owner: str) -> tuple[np.ndarray, np.ndarray]:
    """``(lo, hi)``, each of ``dim`` coordinates, of a box ``[[xmin, ymin(, zmin)], [xmax,
    ymax(, zmax)]]``.  A 2D substructure lies in the plane ``z = 0``: a box with three
    coordinates must hold that plane.

    Raises:
        ValueError: not two corners of ``dim`` (or 3) numbers with ``min <= max``, or a box
            that misses the plane of a 2D substructure.
    """
    try:
        lo, hi = (np.asarray(c, dtype=float).ravel() for c in box)
    except (TypeError, ValueError):
        raise ValueError(f"{owner}: a box is [[xmin, ymin, zmin], [xmax, ymax, zmax]], "
                         f"got {box!r}") from None
    if lo.size not in (dim, 3) or hi.size != lo.size or np.any(lo > hi) or \
            not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
        raise ValueError(f"{owner}: a box is [[xmin, ymin, zmin], [xmax, ymax, zmax]] with "
                         f"min <= max ({dim} or 3 coordinates), got {box!r}")
    if lo.size == 3 and dim == 2 and not lo[2] <= 0.0 <= hi[2]:
        raise ValueError(f"{owner}: the box {box!r} misses the plane z = 0 of a 2D solid")
    return lo[:dim], hi[:dim]


def nodes_in_box(points: np.ndarray, lo: np.ndarray, hi: np.ndarray, tol: float) -> np.ndarray:
    """Indices of the ``(N, dim)`` positions ``points`` inside the box ``[lo, hi]`` widened by
    ``tol`` (:func:`node_tolerance`)."""
    pts = np.asarray(points, dtype=float)
    inside = np.all((pts >= lo - tol) & (pts <= hi + tol), axis=1)
    return np.flatnonzero(inside)
