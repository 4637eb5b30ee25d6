r"""Eigenvalue derivatives with respect to a parameter, from the formulation.

A root :math:`s` of the constrained quadratic problem :math:`(s^2 M + s C + K)\,\phi = 0`,
:math:`A \phi = 0` (``A`` independent of the parameter ``p``), with ``M``, ``C``, ``K``
symmetric: in the null-space coordinates :math:`\phi = N y` the reduced matrices are symmetric
too, so the left eigenvector is :math:`y^T` and differentiating :math:`y^T (s^2 \bar M + s \bar
C + \bar K) y = 0` gives

.. math::  \frac{ds}{dp} = -\frac{\phi^T (s^2 M' + s C' + K')\, \phi}
                               {\phi^T (2 s M + C)\, \phi}

(transposes, not conjugates; any scaling of :math:`\phi` cancels).  Undamped,
:math:`s = i\omega`, :math:`\lambda = \omega^2` and this is the classical
:math:`d\lambda/dp = \phi^T (K' - \lambda M')\, \phi` for :math:`\phi^T M \phi = 1`.  The
natural frequency :math:`\omega = |s|` has :math:`d\omega/dp = \mathrm{Re}(\bar s\, ds/dp) /
|s|`.  A simple root is assumed: at a repeated root (an exact crossing) the derivative depends
on the direction the pair splits, and is not this.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["root_derivatives", "frequency_derivatives"]


def _quad(X: object, phi: np.ndarray) -> np.ndarray:
    """``phi_j^T X phi_j`` for each column (``X`` dense, sparse or ``None`` for 0)."""
    if X is None:
        return np.zeros(phi.shape[1], dtype=complex)
    Xp = (X @ phi) if sp.issparse(X) else np.asarray(X) @ phi
    return np.sum(phi * Xp, axis=0)


def root_derivatives(s: np.ndarray, phi: np.ndarray, M: object, C: object,
                     dM: object, dC: object, dK: object) -> np.ndarray:
    r""":math:`ds_j/dp` of the roots ``s`` (``k``) with shapes ``phi`` (``n x k``) of
    :math:`s^2 M + s C + K`, given :math:`M' , C', K'` (module docstring; ``None`` for a
    matrix that does not change).

    Raises:
        ValueError: shapes that do not match.
    """
    s = np.asarray(s, dtype=complex)
    phi = np.asarray(phi, dtype=complex)
    if phi.ndim != 2 or phi.shape[1] != s.size:
        raise ValueError(f"{s.size} roots need n x {s.size} shapes, got {phi.shape}")
    top = s ** 2 * _quad(dM, phi) + s * _quad(dC, phi) + _quad(dK, phi)
    bottom = 2 * s * _quad(M, phi) + _quad(C, phi)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(bottom != 0, -top / bottom, np.nan)


def frequency_derivatives(s: np.ndarray, ds: np.ndarray) -> np.ndarray:
    r""":math:`d|s|/dp = \mathrm{Re}(\bar s\, ds/dp) / |s|` (NaN at a zero root)."""
    s = np.asarray(s, dtype=complex)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(np.abs(s) > 0, np.real(np.conj(s) * ds) / np.abs(s), np.nan)
