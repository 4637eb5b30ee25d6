r"""Rates and limits of a convergence study: the fitted order of an error series
(:func:`fit_order`), the order observed from three levels with no assumed limit
(:func:`observed_order`), and Richardson's estimate of the limit (:func:`richardson`)."""

from __future__ import annotations

import numpy as np

__all__ = ["fit_order", "observed_order", "richardson"]


def fit_order(dofs: np.ndarray, err: np.ndarray, floor: float, fit_points: int
              ) -> tuple[float, np.ndarray]:
    r"""Order ``p`` of ``err ~ C dofs^-p`` over the finest ``fit_points`` levels above ``floor``:

    .. math::  \log e_l = \log C - p \log N_l \quad \text{(least squares)}

    Returns:
        ``(p, mask)``: the order (NaN if fewer than ``max(fit_points, 2)`` levels lie above
        ``floor``) and the levels used.
    """
    ok = np.isfinite(err) & (err > floor)
    idx = np.nonzero(ok)[0][-fit_points:]
    mask = np.zeros(err.shape, dtype=bool)
    if idx.size < max(fit_points, 2) or np.unique(dofs[idx]).size < 2:
        return np.nan, mask
    mask[idx] = True
    slope = np.polyfit(np.log(dofs[idx]), np.log(err[idx]), 1)[0]
    return float(-slope), mask


def observed_order(lam: np.ndarray, n_el: np.ndarray, floor: float) -> np.ndarray:
    r"""Order from three levels without any assumed limit, per mode:
    :math:`p = \log(|\lambda_2 - \lambda_1| / |\lambda_3 - \lambda_2|) / \log r`, over the
    finest triple whose last difference is above ``floor`` (relative); NaN if there is none."""
    k = lam.shape[1] if lam.ndim == 2 else 0
    out = np.full(k, np.nan)
    for j in range(k):
        for i in range(lam.shape[0] - 1, 1, -1):
            l1, l2, l3 = lam[i - 2, j], lam[i - 1, j], lam[i, j]
            if not np.all(np.isfinite([l1, l2, l3])) or abs(l3 - l2) <= floor * abs(l3):
                continue
            out[j] = np.log(abs(l2 - l1) / abs(l3 - l2)) / np.log(n_el[i] / n_el[i - 1])
            break
    return out


def richardson(lf: np.ndarray, lc: np.ndarray, ratio: float, order: float) -> np.ndarray:
    r"""Richardson estimate of the limit from a fine and a coarse level:

    .. math::  \lambda_R = \lambda_f + \frac{\lambda_f - \lambda_c}{r^p - 1}

    with ``r = ratio`` the refinement ratio and ``p = order`` the order of the error."""
    return lf + (lf - lc) / (ratio**order - 1.0)
