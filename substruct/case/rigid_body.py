r"""Rigid-body motion of a model given at grid points: the six rigid-body vectors, the
rigid-body mass matrix, the total mass, the centre of gravity and the inertia.

A boundary grid at :math:`x_g` moved rigidly by a translation :math:`t` and a small rotation
:math:`\theta` about the reference point :math:`P` has

.. math::  u_g = t + \theta \times r_g = t - S(r_g)\,\theta, \qquad \varphi_g = \theta,
           \qquad r_g = x_g - P,

with :math:`S(r)` the cross-product matrix (:math:`S(r) v = r \times v`).  Stacking the rows of
the components a model has gives :math:`D` (``n x 6``), zero on modal (fixed-interface)
coordinates, which do not move in a rigid-body motion of a Craig-Bampton model.  Then

.. math::

    M_{rb} = D^T M D = \begin{bmatrix} m I & -m S(c) \\ m S(c) & I_P \end{bmatrix},

with :math:`m` the total mass, :math:`c = x_{cg} - P` and :math:`I_P` the inertia tensor about
:math:`P`; the inertia about the centre of gravity is :math:`I_P - m (c^T c I - c c^T)`.
A free model's stiffness annihilates :math:`D`: the "frequencies" of the rigid-body vectors are
compared with the first elastic frequency (:func:`rigid_body_frequency_ratio`).
"""

from __future__ import annotations

from typing import Any, Mapping, Sequence

import numpy as np

__all__ = ["rigid_body_vectors", "rigid_body_properties", "rigid_body_frequency_ratio"]


def _skew(r: np.ndarray) -> np.ndarray:
    """:math:`S(r)` with :math:`S(r) v = r \\times v`."""
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


def rigid_body_vectors(dofs: Sequence[tuple[int, int]], grids: Mapping[int, Sequence[float]],
                       reference: Sequence[float]) -> np.ndarray:
    """``D`` (``n x 6``): the coordinates of a rigid-body translation ``x, y, z`` and rotation
    about ``x, y, z`` through ``reference``, for coordinates ``(grid, component)`` (components
    1-6 of a grid at ``grids[grid]``; component 0, a modal coordinate, stays 0)."""
    P = np.asarray(reference, dtype=float)
    D = np.zeros((len(dofs), 6))
    for k, (grid, c) in enumerate(dofs):
        if c == 0:
            continue
        if c <= 3:
            D[k, c - 1] = 1.0
            D[k, 3:] = -_skew(np.asarray(grids[grid], dtype=float) - P)[c - 1]
        else:
            D[k, c - 1] = 1.0
    return D


def rigid_body_properties(M: np.ndarray, D: np.ndarray, reference: Sequence[float]
                          ) -> dict[str, Any]:
    """``M_rb`` (6 x 6), the total mass (mean of the three translational masses), the
    translational masses, the centre of gravity and the inertia about it (see the module).

    Raises:
        ValueError: a total mass that is not positive.
    """
    Mrb = D.T @ (M @ D)
    Mrb = (Mrb + Mrb.T) / 2
    masses = np.diag(Mrb)[:3].copy()
    m = float(masses.mean())
    if not m > 0:
        raise ValueError(f"the rigid-body mass D^T M D has a total mass of {m:.6g}, not > 0")
    A = Mrb[:3, 3:] / m  # -S(c)
    c = np.array([A[1, 2], A[2, 0], A[0, 1]])
    inertia = Mrb[3:, 3:] - m * (float(c @ c) * np.eye(3) - np.outer(c, c))
    return {"mass": m, "masses_xyz": masses, "cg": np.asarray(reference, dtype=float) + c,
            "inertia_cg": (inertia + inertia.T) / 2, "M_rb": Mrb,
            "reference": np.asarray(reference, dtype=float)}


def rigid_body_frequency_ratio(K: np.ndarray, M: np.ndarray, D: np.ndarray,
                               modal: np.ndarray, dense_limit: int) -> float | None:
    r"""How far a model is from free: :math:`\sqrt{\mu_{max} / \lambda_{ref}}`, the largest
    "frequency" of the rigid-body vectors over the first elastic frequency.

    :math:`\mu` are the eigenvalues of the 6 x 6 pencil :math:`(D^T K D, D^T M D)`; for a
    positive semidefinite ``K``, :math:`D^T K D = 0` exactly when :math:`K D = 0`, and a
    rigid-body motion held by a spring of stiffness ``k`` shows as :math:`\mu \approx k / m`.
    :math:`\lambda_{ref}` is the seventh eigenvalue of :math:`(K, M)` (dense, up to
    ``dense_limit`` coordinates), else the smallest :math:`K_{qq} / M_{qq}` of the modal rows
    ``modal`` (the fixed-interface :math:`\omega^2` of a Craig-Bampton model).  ``None`` when
    neither is known (no reference to compare with).
    """
    import scipy.linalg as sla

    Kr, Mr = D.T @ K @ D, D.T @ M @ D
    try:
        mu = sla.eigh((Kr + Kr.T) / 2, (Mr + Mr.T) / 2, eigvals_only=True)
    except (np.linalg.LinAlgError, ValueError):
        return None
    ref = None
    n = K.shape[0]
    if n > 6 and n <= dense_limit:
        try:
            lam = sla.eigh(K, M, eigvals_only=True, subset_by_index=[6, 6])
            ref = float(lam[0])
        except (np.linalg.LinAlgError, ValueError):
            ref = None
    if (ref is None or ref <= 0) and modal.size:
        ratios = np.diag(K)[modal] / np.where(np.diag(M)[modal] > 0, np.diag(M)[modal], np.inf)
        ref = float(ratios.min())
    if ref is None or ref <= 0:
        return None
    return float(np.sqrt(max(float(np.abs(mu).max()), 0.0) / ref))
