r"""Singular-vector interface reduction: the interface of a coupling reduced to the dominant
singular vectors of its interface receptance over the frequency band.

The LM-FBS coupling (:mod:`substruct.analysis.frf.vp_coupling`) inverts the interface
receptance :math:`Z(\omega) = B_u Y(\omega) B_f^T` (rows scaled by :math:`S_u`, :math:`S_f` so
that translations and rotations compare, :math:`Z_s = S_u Z S_f`).  Noise in the directions of
:math:`Z_s` that carry little motion (the rotations of a virtual point seen over a small
adapter) is amplified by the inversion.  The reduction keeps the interface motion and the
interface loads in the span of real bases :math:`U_r` (``n_u x r``) and :math:`V_r` (``n_f x
r``) found once for the whole band, from the SVD of the frequency blocks side by side, each
normalised to unit Frobenius norm so that every frequency counts alike:

.. math::

    [\,\mathrm{Re}\,\hat Z_1,\ \mathrm{Im}\,\hat Z_1,\ \dots,\ \mathrm{Re}\,\hat Z_k,\
    \mathrm{Im}\,\hat Z_k\,] = U \Sigma W^T, \qquad \hat Z_j = Z_s(\omega_j) / \|Z_s(\omega_j)\|_F

(and the same for :math:`\hat Z_j^T` for :math:`V`); :math:`U_r`, :math:`V_r` are the first
:math:`r` columns, ``keep`` of them or those with :math:`\sigma_i > t\,\sigma_1` (``tolerance``
:math:`t`).  The reduced compatibility and equilibrium rows are

.. math::  \tilde B_u = U_r^T S_u B_u, \qquad \tilde B_f = V_r^T S_f B_f,

and the coupling is :math:`Y - Y \tilde B_f^T (\tilde B_u Y \tilde B_f^T)^{-1} \tilde B_u Y`,
an ``r x r`` inversion.  With every vector kept :math:`U_r`, :math:`V_r` are orthogonal and
square, :math:`(\tilde B_u Y \tilde B_f^T)^{-1} = V^T S_f^{-1} Z^{-1} S_u^{-1} U` and the
coupling is the plain one (to round-off).  Dropping vectors is a weakening in the directions
the interface barely responds in over the band, decided from the data instead of by name.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["InterfaceReduction", "band_bases", "reduce_rows"]


@dataclass(frozen=True)
class InterfaceReduction:
    """How many singular vectors of the interface the coupling keeps (module docstring).

    Attributes:
        keep: keep this many (at most the number of interface rows).
        tolerance: or keep those with singular value above ``tolerance`` times the largest
            (``0 <= tolerance < 1``).
    """

    keep: int | None = None
    tolerance: float | None = None

    def __post_init__(self) -> None:
        if (self.keep is None) == (self.tolerance is None):
            raise ValueError("interface reduction takes exactly one of keep or tolerance")
        if self.keep is not None and (isinstance(self.keep, bool) or self.keep < 1):
            raise ValueError(f"keep must be a positive integer, got {self.keep!r}")
        if self.tolerance is not None and not (np.isfinite(self.tolerance)
                                               and 0 <= self.tolerance < 1):
            raise ValueError(f"tolerance must be in [0, 1), got {self.tolerance!r}")


def _band_stack(Z: np.ndarray) -> np.ndarray:
    """``[Re Z_1/|Z_1|, Im Z_1/|Z_1|, ...]`` of ``(k, m, p)`` blocks: ``(m, 2 k p)``."""
    norm = np.linalg.norm(Z, axis=(1, 2))
    Zn = Z / np.where(norm > 0, norm, 1.0)[:, None, None]
    both = np.concatenate([Zn.real, Zn.imag], axis=2)          # (k, m, 2p)
    return np.transpose(both, (1, 0, 2)).reshape(Z.shape[1], -1)


def band_bases(Z: np.ndarray, reduction: InterfaceReduction
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""The real bases :math:`U_r` (``m x r``), :math:`V_r` (``p x r``) of the band and the
    singular values :math:`\sigma` of the band-stacked :math:`Z` (module docstring), for
    interface receptances ``Z`` of shape ``(k, m, p)``.

    Raises:
        ValueError: ``keep`` above ``min(m, p)``.
    """
    Z = np.asarray(Z)
    m, p = Z.shape[1], Z.shape[2]
    U, s, _ = np.linalg.svd(_band_stack(Z), full_matrices=False)
    V, s_f, _ = np.linalg.svd(_band_stack(np.swapaxes(Z, 1, 2)), full_matrices=False)
    most = min(m, p)
    if reduction.keep is not None:
        if reduction.keep > most:
            raise ValueError(f"interface reduction keeps {reduction.keep} singular vectors of "
                             f"an interface of {most}")
        r = reduction.keep
    else:
        tol = float(reduction.tolerance or 0.0)
        r = max(1, min(int(np.sum(s > tol * s[0])), int(np.sum(s_f > tol * s_f[0])), most))
    return U[:, :r], V[:, :r], s


def reduce_rows(Bu: np.ndarray, Bf: np.ndarray, Z: np.ndarray, su: np.ndarray,
                sf: np.ndarray, reduction: InterfaceReduction) -> tuple[np.ndarray, np.ndarray]:
    r"""The reduced rows :math:`\tilde B_u = U_r^T S_u B_u`, :math:`\tilde B_f = V_r^T S_f B_f`
    from the unscaled interface receptance ``Z = B_u Y B_f^T`` (``(k, n_u, n_f)``) and the
    row scales ``su``, ``sf`` (module docstring)."""
    Zs = su[None, :, None] * Z * sf[None, None, :]
    Ur, Vr, _ = band_bases(Zs, reduction)
    return Ur.T @ (su[:, None] * Bu), Vr.T @ (sf[:, None] * Bf)
