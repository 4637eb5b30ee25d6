r"""Transient response by superposition of the coupled modes, with a static correction for the
truncated ones: the modal check of :mod:`substruct.analysis.transient.response`.

With the undamped coupled modes :math:`\Phi` (``A \Phi = 0``, :math:`\Phi^T M \Phi = I`,
:math:`\Phi^T K \Phi = \Omega^2`; :func:`substruct.analysis.api.modes`),

.. math::  q(t) = q_p + \Phi \eta(t) + R f(t), \qquad
           \ddot \eta + \Phi^T C \Phi\, \dot \eta + \Omega^2 \eta = \Phi^T B f(t),

.. math::  R = G B - \Phi_e \Omega_e^{-2} \Phi_e^T B ,

where ``G`` is the constrained static flexibility
(:func:`substruct.analysis.frf.modal_static.static_solver`, inertia relief against rigid-body modes)
and :math:`\Phi_e` the elastic modes kept: the quasi-static response of the modes left out.
With every coupled mode kept, :math:`R = 0` to rounding and the superposition is the direct
integration in other coordinates (the integrators are linear and invariant under a change of
coordinates); with fewer, the difference is the dynamic part of the truncated modes.  A moving
ground adds :math:`r g(t)` and the effective loads :math:`-M r \ddot g - C r \dot g - K r g`
(:mod:`substruct.analysis.transient.base`).  The modal
equations are integrated by the same scheme and step as the direct forms.

With ``modal_solver="amls"`` the modes are those of an AMLS reduction
(:func:`substruct.analysis.modes.amls.amls_coupled_modes`), every one below
``modal_cutoff`` times the step's Nyquist frequency :math:`\pi / dt`: approximate (Ritz)
modes, still :math:`M`- and :math:`K`-orthogonal after the Rayleigh-Ritz of
:func:`coupled_basis`, so the modal equations stay uncoupled and ``R`` is still the exact
static flexibility minus the static part of the modes kept (the mode-acceleration method):
the answer converges to the direct integration as the cut-off grows, and with every mode of
every block kept it is the direct integration to rounding.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from dataclasses import replace

from substruct.analysis.modes.amls import AmlsOptions, amls_coupled_modes
from substruct.analysis.modes.eigen import SPARSE_ABOVE, modes
from substruct.analysis.transient.integrators import (
    Scheme,
    StepControl,
    StepState,
    effective_matrix,
    integrate,
)
from substruct.analysis.frf.modal_static import static_solver
from substruct.analysis.transient.fields import FieldStore
from substruct.analysis.transient.record import Physical, Recorder
from substruct.analysis.transient.options import MODAL_CUTOFF, TransientOptions
from substruct.linalg.scaling import rigid_modes

__all__ = ["MODAL_DEFAULT_COUNT", "coupled_basis", "modal_run"]

#: Modes kept by the modal form of a model too large for the dense eigensolver, unless told.
MODAL_DEFAULT_COUNT = 40


def coupled_basis(phys: Physical, count: int | None, solver: str, *,
                  omega_max: float | None = None, amls: AmlsOptions | None = None
                  ) -> tuple[np.ndarray, np.ndarray, str]:
    r"""``(Phi, omega, label)``: undamped coupled modes, :math:`\Phi^T M \Phi = I`,
    :math:`\Phi^T K \Phi = \operatorname{diag}(\omega^2)` (re-orthonormalized by a small
    Rayleigh-Ritz, so repeated frequencies are orthogonal too), and how they were found.

    ``solver="amls"``: the AMLS modes below ``omega_max`` (or the lowest ``count``), options
    ``amls``; the label names the reduction and its largest relative residual
    :math:`\|K u - \omega^2 M u\| / \|K u\|`.
    """
    n = phys.M.shape[0]
    if solver == "amls":
        opts = replace(amls if amls is not None else AmlsOptions(),
                       omega_max=None if count is not None else omega_max)
        md, _, label = amls_coupled_modes(phys.M, None, phys.K, phys.A, count, opts)
        label = f"{len(md)} modes by {label}"
    else:
        if count is None and n > SPARSE_ABOVE:
            count = MODAL_DEFAULT_COUNT
        md = modes(phys.M, None, phys.K, phys.A, count, solver=solver,
                   what="transient (modal)")
        label = f"{len(md)} modes"
    U = np.asarray(md.shapes).real
    Mr, Kr = U.T @ (phys.M @ U), U.T @ (phys.K @ U)
    w2, rot = sla.eigh((Kr + Kr.T) / 2, (Mr + Mr.T) / 2)
    Phi = U @ rot
    # rigid as the eigensolvers decide it, on the model's stiffness scale: against the modes
    # kept, a basis of rigid-body modes alone (a free body, modal_count 6) read its round-off
    # eigenvalues as elastic and divided the static correction by them
    w2 = np.where(rigid_modes(w2, Phi, phys.K, phys.M) | (w2 < 0), 0.0, w2)
    return Phi, np.sqrt(w2), label


def modal_run(phys: Physical, s: Scheme, h: float, n_steps: int, d0: np.ndarray,
              v0: np.ndarray, opts: TransientOptions, fields: FieldStore | None = None
              ) -> Recorder:
    """The modal form (module docstring), recorded like the direct forms (the fields of the
    steps ``fields`` names go to it)."""
    cutoff = MODAL_CUTOFF if opts.modal_cutoff is None else opts.modal_cutoff
    Phi, omega, label = coupled_basis(phys, opts.modal_count, opts.modal_solver,
                                      omega_max=cutoff * np.pi / h, amls=opts.modal_amls)
    M, K, B, f = phys.M, phys.K, phys.B, phys.f
    loads = phys.loads
    rigid = omega == 0.0
    Bd = np.asarray(sp.csr_array(B).toarray()) if sp.issparse(B) else np.asarray(B)
    mo = phys.motion
    if mo is not None:  # q = r g + w: the effective loads -M r g'' - K r g - C r g'
        extra = [X @ mo.r for X in (M, K, phys.C) if X is not None]
        Bd = np.hstack([Bd, -np.column_stack(extra)])
        loads = loads.widened(mo.load_columns(len(extra)))
        f = loads.f
        d0, v0 = d0 - mo.r * mo.g[0, 0], v0 - mo.r * mo.g[0, 1]
    qp = phys.qp if phys.qp is not None else np.zeros(M.shape[0])
    if phys.qp is not None:  # q = q_p + Phi eta + R f: the constant load -K q_p
        Bd = np.hstack([Bd, -(K @ qp)[:, None]])
        loads = loads.widened(np.ones((f.shape[0], 1)))
        f = loads.f
    if Bd.shape[1] and opts.modal_residual == "static":
        G = static_solver(sp.csr_array(K), sp.csr_array(M), phys.A, Phi[:, rigid])
        Pe, we = Phi[:, ~rigid], omega[~rigid]
        R = G(Bd) - Pe @ ((Pe.T @ Bd) / (we ** 2)[:, None])
    else:
        R = np.zeros((M.shape[0], Bd.shape[1]))
    k = Phi.shape[1]
    Me, Ke = np.eye(k), np.diag(omega ** 2)
    Ce = None if phys.C is None else Phi.T @ (phys.C @ Phi)
    Be = Phi.T @ Bd
    eta0 = Phi.T @ (M @ (d0 - qp - R @ f[0]))
    etav0 = Phi.T @ (M @ v0)
    r0 = Be @ f[0] - Ke @ eta0 - (Ce @ etav0 if Ce is not None else 0.0)
    S = effective_matrix(Me, Ce, Ke, s, h)
    inv = np.linalg.inv(S)
    mphys = Physical(M, phys.C, K, B, phys.f, phys.A, phys.b, phys.O, Phi, phys.qp, mo,
                     phys.pairs)

    def restart(step: int, eta: np.ndarray, etav: np.ndarray, fv: np.ndarray) -> np.ndarray:
        return np.asarray(Be @ fv - Ke @ eta - (Ce @ etav if Ce is not None else 0.0))

    rec = Recorder(mphys, Me, Ke, h, None, fields, offset=lambda step: R @ f[step],
                   basis=label)
    integrate(Me, Ce, Ke, Be, loads, StepState(eta0, etav0, r0), rec,
              StepControl(s, h, n_steps, lambda r: inv @ r, opts.every), restart=restart)
    return rec
