r"""Base-driven frequency response by modal superposition: the transmissibility of
:mod:`substruct.analysis.frf.base_drive` in relative coordinates, with the receptance of the
held structure summed over its modes (:func:`substruct.analysis.frf.modal.modal_receptance_sweep`,
any of its eigensolvers, the AMLS basis included).

With the influence vectors ``r`` (:math:`K r + A^T \mu = 0`, :math:`A r = E`,
:func:`substruct.analysis.transient.base.influence`) and :math:`q = r G + w`, :math:`A w = 0`,

.. math::  T(\omega) = \hat q / G = r + \omega^2 H_0(\omega) M r - i \omega H_0(\omega) C r ,

:math:`H_0` the receptance under :math:`A w = 0` (no constraint tied to the force).  The
modal sum gives :math:`O H_0 [M r, C r]` with its residual flexibility and its direct check
at a few frequencies; per base acceleration :math:`\hat q / \ddot G = -T / \omega^2`.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Sequence

import numpy as np
import scipy.sparse as sp

from substruct.analysis.frf.base_drive import base_frequencies
from substruct.analysis.frf.modal import modal_receptance_sweep
from substruct.analysis.results import Receptance
from substruct.analysis.system import SweepOptions
from substruct.analysis.transient.base import influence
from substruct.linalg.system import ConstrainedSystem, Matrix

__all__ = ["modal_base_drive_sweep"]


def modal_base_drive_sweep(K: Matrix, M: Matrix, C: Matrix | None, A: Matrix,
                           omegas: Sequence[float] | np.ndarray, E: np.ndarray,
                           outputs: Matrix, *, per: str = "displacement",
                           options: SweepOptions | None = None) -> Receptance:
    r"""Output displacement per base motion :math:`G_j` (or per base acceleration,
    ``per="acceleration"``) by the modal sum in relative coordinates (module docstring):

    .. math::  T[k] = O r + \omega_k^2\, O H_0(\omega_k) M r - i \omega_k\, O H_0(\omega_k) C r

    Args:
        E: ``m x p``: column ``j`` the coefficients of base input ``j`` in the rows of ``A``.
        options: the checks (direct formulations at ``options.modal.n_check`` frequencies,
            ``kkt`` if none), tolerance, names and, in ``options.modal``, the modal sum
            (:class:`~substruct.analysis.frf.modal.ModalOptions`).

    Raises:
        CheckError: the direct check of :math:`H_0` disagrees by more than the tolerance.
        AnalysisInputError: a mechanism with the supports held, ``omega <= 0`` per base
            acceleration, a damped model with rigid-body modes.
        ValueError: an unknown ``per`` (a programming error).
    """
    opts = options if options is not None else SweepOptions(method="modal")
    w = base_frequencies(omegas, per)
    Ks, Ms, As = (sp.csr_array(X, dtype=float) for X in (K, M, A))
    n = Ks.shape[0]
    Cs = sp.csr_array(C if C is not None else (n, n), dtype=float)
    E = np.asarray(E, dtype=float).reshape(As.shape[0], -1)
    p = E.shape[1]
    r = np.column_stack([influence(Ks, As, E[:, j]) for j in range(p)])
    out = sp.csr_array(outputs, dtype=float)
    system = ConstrainedSystem.of(Ms, Cs, Ks, As)
    h0 = modal_receptance_sweep(system, w, np.column_stack([Ms @ r, Cs @ r]), out,
                                options=replace(opts, input_names=None))
    T = (out @ r)[None] + (w ** 2)[:, None, None] * h0.H[:, :, :p] \
        - 1j * w[:, None, None] * h0.H[:, :, p:]
    H = T if per == "displacement" else T / (-(w ** 2))[:, None, None]
    names = list(opts.input_names) if opts.input_names is not None else \
        [f"base{j + 1}" for j in range(p)]
    return replace(h0, H=H, inputs=names, method=f"{h0.method}, relative coordinates")
