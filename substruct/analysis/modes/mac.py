r"""The modal assurance criterion: how alike two sets of mode shapes are.

.. math::  \mathrm{MAC}_{jk} = \frac{|u_j^H v_k|^2}{(u_j^H u_j)(v_k^H v_k)}

1 for shapes that are multiples of each other, 0 for orthogonal ones; complex shapes are
compared as they are (a phase does not change it).  :func:`pair_modes` pairs each mode of the
first set with the mode of the second of largest MAC.
"""

from __future__ import annotations

import numpy as np

__all__ = ["mac_matrix", "pair_modes"]


def mac_matrix(U: np.ndarray, V: np.ndarray) -> np.ndarray:
    r"""``MAC[j, k]`` between the columns of ``U`` (``n x p``) and ``V`` (``n x q``).

    Raises:
        ValueError: different numbers of rows.
    """
    U = np.asarray(U, dtype=complex)
    V = np.asarray(V, dtype=complex)
    if U.shape[0] != V.shape[0]:
        raise ValueError(f"shapes of {U.shape[0]} and {V.shape[0]} coordinates cannot be "
                         "compared")
    cross = np.abs(U.conj().T @ V) ** 2
    nu = np.einsum("ij,ij->j", U.conj(), U).real
    nv = np.einsum("ij,ij->j", V.conj(), V).real
    return cross / np.maximum(np.outer(nu, nv), 1e-300)


def pair_modes(mac: np.ndarray) -> np.ndarray:
    """For each row (mode of the first set), the column of largest MAC (``-1`` if none)."""
    if mac.shape[1] == 0:
        return -np.ones(mac.shape[0], dtype=int)
    return np.argmax(mac, axis=1)
