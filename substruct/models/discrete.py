"""Discrete secondary systems (paper eqs 17-20): one mass on a spring and a damper.

A *fixed-free* system is a mass on a spring (and damper) to ground; it is attached to the primary
structure at the mass itself, so its single coordinate is both its mass and its boundary DOF.
A *free-free* system (an absorber) has an inner DOF with the mass and a massless boundary DOF
attached to the primary structure (eqs 19-20):

.. math::

    M = \\begin{bmatrix} m & 0 \\\\ 0 & 0 \\end{bmatrix}, \\quad
    C = c \\begin{bmatrix} 1 & -1 \\\\ -1 & 1 \\end{bmatrix}, \\quad
    K = k \\begin{bmatrix} 1 & -1 \\\\ -1 & 1 \\end{bmatrix}, \\quad
    z = \\begin{bmatrix} z^i \\\\ z^b \\end{bmatrix}

Points are named ``"mass"`` and ``"boundary"``.  Both systems displace along the global ``x``
axis.  Their drawings use *local* coordinates: the boundary (attachment point) at the origin
and the other end of the spring at ``(0, -1, 0)``; an assembler places them by translating the
points to the attachment position.

Two more discrete elements join structures and load them at a point:

* a *spring* (:func:`spring`): a spring ``k`` and damper ``c`` between two massless coordinates
  ``"i"`` and ``"j"``, or, ``grounded``, between one massless coordinate ``"i"`` and ground;
* a *point mass* (:func:`point_mass`): a mass ``m`` with one coordinate ``"mass"`` and no
  stiffness.

Their drawings follow the same convention: point ``"i"`` (or ``"mass"``) at the local origin,
the other end of a spring (``"j"`` or ``"ground"``) at ``(0, -1, 0)``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp

from substruct.substructure import Geometry, PointError, Substructure, as_csr

__all__ = ["fixed_free", "free_free", "spring", "point_mass"]


def _value(name: str, field: str, value: Any, *, positive: bool) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        v = float("nan")
    ok = np.isfinite(v) and (v > 0 if positive else v >= 0) and not isinstance(value, bool)
    if not ok:
        need = "positive" if positive else "non-negative"
        raise ValueError(f"{name}: {field} must be a finite {need} number, got {value!r}")
    return v


def _locator(name: str, rows: dict[str, int], n: int):
    def locate(where: Any) -> sp.csr_array:
        if not isinstance(where, str) or where not in rows:
            raise PointError(f"{name}: no point {where!r}; the points of this discrete system "
                             f"are {sorted(rows)}")
        return sp.csr_array(([1.0], ([0], [rows[where]])), shape=(1, n))
    return locate


def _geometry(row_origin: int | None, row_below: int | None, n: int,
              glyphs: dict[str, int]) -> Geometry:
    """Two drawing nodes, the origin and ``(0, -1, 0)``; ``None`` means a node that stays put."""
    points = np.array([[0.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
    pairs = ((0, row_origin), (1, row_below))
    entries = [(3 * node, col) for node, col in pairs if col is not None]
    r, c = zip(*entries)
    interp = sp.csr_array((np.ones(len(r)), (r, c)), shape=(6, n))
    return Geometry(points=points, cells=[("line", np.array([[0, 1]]))], interp=interp,
                    glyphs=glyphs)


def fixed_free(name: str, mass: float, stiffness: float, damping: float = 0.0) -> Substructure:
    """A mass on a spring and a damper to ground (the ``fd`` block of eqs 17-18).

    .. math::  m \\ddot z + c \\dot z + k z = f, \\qquad \\omega = \\sqrt{k/m}

    One coordinate, labelled ``"mass"``; ``locate("mass")`` and ``locate("boundary")`` both give
    the row ``[1]`` (the boundary DOF is the mass).  Drawing: the mass at the local origin, the
    grounded end of the spring at ``(0, -1, 0)``; glyphs ``mass``, ``boundary``, ``ground``.

    Raises:
        ValueError: ``mass`` or ``stiffness`` not positive, ``damping`` negative, or not finite.
    """
    m = _value(name, "mass", mass, positive=True)
    k = _value(name, "stiffness", stiffness, positive=True)
    c = _value(name, "damping", damping, positive=False)
    return Substructure(
        name=name, M=as_csr([[m]]), K=as_csr([[k]]), C=as_csr([[c]]), dof_labels=("mass",),
        locate=_locator(name, {"mass": 0, "boundary": 0}, 1), kind="fixed-free",
        geometry=_geometry(0, None, 1, {"mass": 0, "boundary": 0, "ground": 1}),
        meta={"mass": m, "stiffness": k, "damping": c},
    )


def free_free(name: str, mass: float, stiffness: float, damping: float = 0.0) -> Substructure:
    """An absorber: inner mass joined by a spring and a damper to a massless boundary DOF.

    .. math::

        \\begin{bmatrix} m & 0 \\\\ 0 & 0 \\end{bmatrix} \\ddot z
        + c \\begin{bmatrix} 1 & -1 \\\\ -1 & 1 \\end{bmatrix} \\dot z
        + k \\begin{bmatrix} 1 & -1 \\\\ -1 & 1 \\end{bmatrix} z = f       \\qquad (19, 20)

    Coordinates ``("mass", "boundary")``; the boundary one is massless (``M`` is singular, the
    ``s`` block of eq 6).  Grounded at its boundary it has :math:`\\omega = \\sqrt{k/m}`.
    Drawing: the boundary at the local origin, the mass at ``(0, -1, 0)``.

    Raises:
        ValueError: ``mass`` or ``stiffness`` not positive, ``damping`` negative, or not finite.
    """
    m = _value(name, "mass", mass, positive=True)
    k = _value(name, "stiffness", stiffness, positive=True)
    c = _value(name, "damping", damping, positive=False)
    pattern = np.array([[1.0, -1.0], [-1.0, 1.0]])
    return Substructure(
        name=name, M=as_csr([[m, 0.0], [0.0, 0.0]]), K=as_csr(k * pattern),
        C=as_csr(c * pattern), dof_labels=("mass", "boundary"),
        locate=_locator(name, {"mass": 0, "boundary": 1}, 2), kind="free-free",
        geometry=_geometry(1, 0, 2, {"boundary": 0, "mass": 1}),
        meta={"mass": m, "stiffness": k, "damping": c},
    )


def spring(name: str, stiffness: float, damping: float = 0.0, grounded: bool = False
           ) -> Substructure:
    """A massless spring (and damper) between two points, or between a point and ground.

    Between two points, coordinates ``z = (z_i, z_j)`` (the displacements of its ends):

    .. math::

        M = 0, \\quad
        C = c \\begin{bmatrix} 1 & -1 \\\\ -1 & 1 \\end{bmatrix}, \\quad
        K = k \\begin{bmatrix} 1 & -1 \\\\ -1 & 1 \\end{bmatrix}

    so the end forces are ``f_i = -f_j = k (z_i - z_j) + c (dz_i - dz_j)``.  Grounded
    (``grounded=True``), one coordinate ``z_i`` with :math:`K = [k]`, :math:`C = [c]`,
    :math:`M = [0]`.  Every coordinate is massless (the ``s`` block of eq 6): an end that no
    connection reaches is an infinite root of the coupled problem, and the spring then carries
    no force.

    Points ``"i"`` and ``"j"`` (``"i"`` only when grounded).  Drawing: ``"i"`` at the local
    origin, ``"j"`` (or the grounded end, glyph ``"ground"``) at ``(0, -1, 0)``; an assembler
    may move each end to where it is connected.

    Raises:
        ValueError: ``stiffness`` not positive, ``damping`` negative, or not finite.
    """
    k = _value(name, "stiffness", stiffness, positive=True)
    c = _value(name, "damping", damping, positive=False)
    meta = {"stiffness": k, "damping": c, "grounded": bool(grounded)}
    if grounded:
        return Substructure(
            name=name, M=as_csr(np.zeros((1, 1))), K=as_csr([[k]]), C=as_csr([[c]]),
            dof_labels=("i",), locate=_locator(name, {"i": 0}, 1), kind="spring/grounded",
            geometry=_geometry(0, None, 1, {"i": 0, "ground": 1}), meta=meta,
        )
    pattern = np.array([[1.0, -1.0], [-1.0, 1.0]])
    return Substructure(
        name=name, M=as_csr(np.zeros((2, 2))), K=as_csr(k * pattern), C=as_csr(c * pattern),
        dof_labels=("i", "j"), locate=_locator(name, {"i": 0, "j": 1}, 2), kind="spring",
        geometry=_geometry(0, 1, 2, {"i": 0, "j": 1}), meta=meta,
    )


def point_mass(name: str, mass: float) -> Substructure:
    """A point mass: one coordinate ``"mass"`` with :math:`M = [m]`, :math:`K = C = [0]`.

    .. math::  m \\ddot z = f

    On its own it is a rigid-body mode (``omega = 0``); attached to a point of a structure
    (a connection ``[rod@x, m1]``) it adds ``m`` to the mass matrix there.  Drawing: one node
    at the local origin, glyph ``"mass"``.

    Raises:
        ValueError: ``mass`` not positive, or not finite.
    """
    m = _value(name, "mass", mass, positive=True)
    geometry = Geometry(points=np.zeros((1, 3)), cells=[("vertex", np.array([[0]]))],
                        interp=sp.csr_array(([1.0], ([0], [0])), shape=(3, 1)),
                        glyphs={"mass": 0})
    return Substructure(
        name=name, M=as_csr([[m]]), K=as_csr(np.zeros((1, 1))), C=as_csr(np.zeros((1, 1))),
        dof_labels=("mass",), locate=_locator(name, {"mass": 0}, 1), kind="mass",
        geometry=geometry, meta={"mass": m},
    )
