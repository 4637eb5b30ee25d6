r"""Cartesian, cylindrical and spherical coordinate systems of a Universal File (datasets 18
and 2420, record "coordinate system type": 0 cartesian, 1 cylindrical, 2 spherical): a node's
coordinates in its definition system to a global position, and the three directions of its
displacement system at that position.

A system is a rotation :math:`A` (its rows the unit axes in global coordinates), an origin
:math:`o` and a type.  A point of local cartesian coordinates :math:`x_l` is at
:math:`x = o + A^T x_l`, where, for the three coordinates :math:`(c_1, c_2, c_3)` a node
gives (angles in degrees):

* cartesian: :math:`x_l = (c_1, c_2, c_3)`;
* cylindrical :math:`(r, \theta, z)`: :math:`x_l = (r\cos\theta, r\sin\theta, z)`, the angle
  :math:`\theta` from the local +x axis towards +y;
* spherical :math:`(r, \theta, \varphi)`: :math:`x_l = (r\sin\theta\cos\varphi,
  r\sin\theta\sin\varphi, r\cos\theta)`, :math:`\theta` the polar angle from the local +z
  axis and :math:`\varphi` the azimuth from +x towards +y.

The direction codes 1, 2, 3 of a function at a node whose displacement system is
cylindrical are the unit vectors :math:`e_r, e_\theta, e_z` at the node, spherical
:math:`e_r, e_\theta, e_\varphi` (in the order of the coordinates; each right-handed):

.. math::

    e_r = (\cos\theta, \sin\theta, 0),\ e_\theta = (-\sin\theta, \cos\theta, 0),\
    e_z = (0, 0, 1) \quad\text{(cylindrical)}

    e_r = (\sin\theta\cos\varphi, \sin\theta\sin\varphi, \cos\theta),\
    e_\theta = (\cos\theta\cos\varphi, \cos\theta\sin\varphi, -\sin\theta),\
    e_\varphi = (-\sin\varphi, \cos\varphi, 0) \quad\text{(spherical)}

in the system's cartesian axes, then turned by :math:`A^T`.  The angles are the node's own
when it is defined in its displacement system; otherwise they are those of its global
position seen from the displacement system, and a node on the axis of that system (where
the angle is not defined) is refused.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["UffFrame", "SYSTEM_TYPES", "AXIS_RTOL", "local_to_cartesian", "angles_of",
           "frame_axes", "length_components"]

#: A point whose distance from a system's axis is at most this times its distance from the
#: origin is on the axis (its angle is not defined).
AXIS_RTOL = 1e-12

#: The coordinate system types of 18 and 2420 (record 1 field 2 / record 3 field 2).
SYSTEM_TYPES = {0: "cartesian", 1: "cylindrical", 2: "spherical"}


class UffFrame(NamedTuple):
    """A coordinate system: ``A`` (rows: the unit axes, global), ``o`` (the origin, global),
    ``kind`` (0 cartesian, 1 cylindrical, 2 spherical)."""

    A: np.ndarray
    o: np.ndarray
    kind: int


def length_components(kind: int) -> tuple[int, ...]:
    """The coordinates of a point that are lengths in a system of type ``kind`` (the others
    are angles in degrees): all three when cartesian, :math:`r, z` cylindrical, :math:`r`
    spherical."""
    return {1: (0, 2), 2: (0,)}.get(kind, (0, 1, 2))


def local_to_cartesian(kind: int, c: np.ndarray) -> np.ndarray:
    r"""The local cartesian coordinates :math:`x_l` of a point given as ``c`` in a system of
    type ``kind`` (module docstring; angles in degrees)."""
    c = np.asarray(c, dtype=float)
    if kind == 1:
        t = np.deg2rad(c[1])
        return np.array([c[0] * np.cos(t), c[0] * np.sin(t), c[2]])
    if kind == 2:
        t, p = np.deg2rad(c[1]), np.deg2rad(c[2])
        return np.array([c[0] * np.sin(t) * np.cos(p), c[0] * np.sin(t) * np.sin(p),
                         c[0] * np.cos(t)])
    return c.copy()


def angles_of(kind: int, x_l: np.ndarray) -> tuple[float, float] | None:
    r"""The angles (radians) of the point of local cartesian coordinates ``x_l`` in a system
    of type ``kind``: :math:`(\theta, 0)` cylindrical, :math:`(\theta, \varphi)` spherical;
    ``None`` on the system's axis, where they are not defined: its distance from the axis
    at most :data:`AXIS_RTOL` times its distance from the origin (the round-off of turning a
    point on the axis into the system)."""
    if np.hypot(x_l[0], x_l[1]) <= AXIS_RTOL * np.linalg.norm(x_l):
        return None
    if kind == 1:
        return float(np.arctan2(x_l[1], x_l[0])), 0.0
    return float(np.arctan2(np.hypot(x_l[0], x_l[1]), x_l[2])), \
        float(np.arctan2(x_l[1], x_l[0]))


def frame_axes(frame: UffFrame, angles: tuple[float, float]) -> np.ndarray:
    r"""The global unit vectors of the direction codes 1, 2, 3 (rows) of a system at a point
    of the given angles (:func:`angles_of`, radians; ignored for a cartesian system)."""
    if frame.kind == 1:
        t = angles[0]
        local = np.array([[np.cos(t), np.sin(t), 0.0], [-np.sin(t), np.cos(t), 0.0],
                          [0.0, 0.0, 1.0]])
    elif frame.kind == 2:
        t, p = angles
        st, ct, sp, cp = np.sin(t), np.cos(t), np.sin(p), np.cos(p)
        local = np.array([[st * cp, st * sp, ct], [ct * cp, ct * sp, -st], [-sp, cp, 0.0]])
    else:
        return frame.A
    return local @ frame.A
