"""Reduction of a substructure to its lowest undamped modes (paper eqs 21-22).

.. math::

    q = \\Phi_r y_r, \\qquad \\Phi_r^T M \\Phi_r = I_r, \\qquad
    \\Phi_r^T K \\Phi_r = \\Lambda_r = \\operatorname{diag}(\\omega_j^2), \\qquad
    \\Phi_r^T C \\Phi_r = \\Psi_r                                         \\qquad (21, 22)

Small problems (``n <= dense_limit``) are solved densely (``scipy.linalg.eigh``); large sparse ones
by shift-invert Lanczos (``scipy.sparse.linalg.eigsh``) with an explicit ``OPinv`` built from a
factorization of the registry (:func:`substruct.linalg.factorize.factorizer`: CHOLMOD when
installed, else SuperLU in symmetric mode; or the callable given), never one that ``eigsh``
makes for itself (SuperLU with partial pivoting; the registry's choice, measured, is in
docs/performance.md, "The factorization: measured, and the default").
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any, Mapping, Sequence

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from substruct.linalg.factorize import Factorize, factorizer
from substruct.linalg.lanczos import rayleigh_ritz, shift_invert_lanczos_deflated
from substruct.linalg.massless import massless_count
from substruct.linalg.scaling import rigid_modes
from substruct.substructure import Substructure, as_csr

__all__ = ["modal_truncation", "undamped_modes"]


def _check_count(sub: Substructure, n_modes: Any, what: str) -> int:
    n = sub.n_dof
    try:
        g = int(n_modes)
    except (TypeError, ValueError):
        raise ValueError(f"{sub.name}: {what} must be an integer, got {n_modes!r}") from None
    if g != n_modes or not 1 <= g <= n:
        raise ValueError(f"{sub.name}: {what} = {n_modes!r} modes requested, but the "
                         f"substructure has {n} coordinates (need 1 <= {what} <= {n})")
    return g


def _check_mass(sub: Substructure) -> None:
    massless = sub.massless
    if massless.any():
        labels = [sub.dof_labels[i] for i in np.nonzero(massless)[0][:5]]
        raise ValueError(f"{sub.name}: modal truncation needs M positive definite, but "
                         f"{int(massless.sum())} coordinate(s) are massless, e.g. {labels}")
    hidden = massless_count(as_csr(sub.M))  # combinations of coordinates without mass
    if hidden:
        raise ValueError(f"{sub.name}: modal truncation needs M positive definite, but "
                         f"{hidden} combination(s) of its coordinates carry no mass (e.g. a "
                         f"point mass off its node without rotary inertia)")


def _mass_normalized_sorted(lam: np.ndarray, Phi: np.ndarray, M: sp.csr_array
                            ) -> tuple[np.ndarray, np.ndarray]:
    """Sort by eigenvalue, scale to unit modal mass, first significant entry positive."""
    idx = np.argsort(lam)
    lam, Phi = lam[idx], Phi[:, idx]
    Phi = Phi / np.sqrt(np.einsum("ij,ij->j", Phi, M @ Phi))
    first = np.argmax(abs(Phi) > 1e-8 * abs(Phi).max(axis=0), axis=0)
    return lam, Phi * np.sign(Phi[first, np.arange(Phi.shape[1])])


def undamped_modes(sub: Substructure, n_modes: int, *, dense_limit: int = 2000,
                   sigma: float | None = None, factorization: str | Factorize = "auto"
                   ) -> tuple[np.ndarray, np.ndarray]:
    """The ``n_modes`` lowest undamped modes :math:`K \\phi = \\omega^2 M \\phi`, mass-normalized.

    .. math::  \\Phi^T M \\Phi = I, \\qquad \\Phi^T K \\Phi = \\operatorname{diag}(\\omega_j^2)

    Eigenvectors are sorted by frequency and signed so that their first entry larger than
    ``1e-8`` times their largest is positive.  For ``n > dense_limit`` the modes come from
    shift-invert Lanczos about ``sigma``
    (default a small negative shift, :math:`-10^{-9}\\,\\mathrm{tr}K/\\mathrm{tr}M`, so that
    ``K - sigma M`` is positive definite even with rigid-body modes), followed by a Rayleigh-Ritz
    step on the converged vectors which makes them M-orthonormal within repeated eigenvalues.

    Args:
        sub: the substructure; its ``M`` must be positive definite.
        n_modes: number ``g`` of modes, ``1 <= g <= n``.
        dense_limit: largest ``n`` solved densely.
        sigma: shift of the sparse solve.
        factorization: of the shifted matrix ``K - sigma M`` (symmetric positive definite):
            a name of :func:`substruct.linalg.factorize.factorizer` (``"auto"``,
            ``"superlu"``, ``"cholmod"``) or a callable ``A -> (b -> A^{-1} b)``.

    Returns:
        ``(omega, Phi)``: circular frequencies ``(g,)`` (rad/s; the round-off eigenvalues of
        rigid-body modes, :func:`substruct.linalg.scaling.rigid_modes`, of either sign, are
        set to zero) and the ``n x g`` modal matrix.

    Raises:
        ValueError: bad ``n_modes``, massless coordinates, ``M`` not positive definite, or ``K``
            with a clearly negative eigenvalue.
    """
    g = _check_count(sub, n_modes, "n_modes")
    _check_mass(sub)
    M, K = as_csr(sub.M), as_csr(sub.K)
    n = sub.n_dof
    scale = max(abs(K.diagonal()).sum() / abs(M.diagonal()).sum(), np.finfo(float).tiny)
    if n <= dense_limit or g >= n - 1:
        try:
            lam, Phi = sla.eigh(K.toarray(), M.toarray(), subset_by_index=[0, g - 1])
        except np.linalg.LinAlgError as err:
            raise ValueError(f"{sub.name}: modal truncation needs M positive definite "
                             f"({err})") from None
    else:
        shift = -1e-9 * scale if sigma is None else float(sigma)
        solve = factorizer(factorization, spd=True)(sp.csc_array(K - shift * M))
        # rigid-body modes (a free part) deflated: the elastic modes to round-off
        _, vecs = shift_invert_lanczos_deflated(K, M, g, shift, solve, 1e-12 * scale)
        lam, Phi = rayleigh_ritz(K, M, vecs)
    if lam[0] < -1e-8 * scale:
        raise ValueError(f"{sub.name}: K has a negative eigenvalue {lam[0]:.6g} "
                         f"(relative to {scale:.6g}); it must be positive semidefinite")
    # a rigid-body mode's computed eigenvalue is round-off of either sign (2.7e-5 or -5.5e-5
    # for a free steel plate, as the BLAS's threads fall): exactly 0, or the coupled model
    # gets a soft spring in its place, and modal damping a dashpot on it
    lam = np.where(rigid_modes(lam, Phi, K, M) | (lam < 0), 0.0, lam)
    lam, Phi = _mass_normalized_sorted(lam, Phi, M)
    return np.sqrt(lam), Phi


def _modal_damping(sub: Substructure, damping: Any, omega: np.ndarray
                   ) -> tuple[np.ndarray | None, dict[str, Any]]:
    """Diagonal of ``Psi`` (or ``None`` to project ``C``) and a description for ``meta``."""
    if damping is None:
        return None, {"damping": "projected"}
    if isinstance(damping, Mapping):
        if set(damping) == {"rayleigh"}:
            alpha, beta = (float(v) for v in damping["rayleigh"])
            if not (np.isfinite(alpha) and np.isfinite(beta) and alpha >= 0 and beta >= 0):
                raise ValueError(f"{sub.name}: Rayleigh damping needs finite alpha, beta >= 0, "
                                 f"got ({alpha!r}, {beta!r})")
            return alpha + beta * omega**2, {"damping": "rayleigh", "rayleigh": [alpha, beta]}
        if set(damping) != {"zeta"}:
            raise ValueError(f"{sub.name}: damping must be {{'zeta': ...}} or "
                             f"{{'rayleigh': (alpha, beta)}}, got keys {sorted(damping)}")
        damping = damping["zeta"]
    zeta = np.atleast_1d(np.asarray(damping, dtype=float))
    if zeta.ndim != 1 or len(zeta) not in (1, len(omega)):
        raise ValueError(f"{sub.name}: {len(zeta)} modal damping ratios for "
                         f"{len(omega)} kept modes")
    if not np.all(np.isfinite(zeta)) or np.any(zeta < 0):
        raise ValueError(f"{sub.name}: modal damping ratios must be finite and >= 0, "
                         f"got {zeta.tolist()}")
    zeta = np.broadcast_to(zeta, omega.shape)
    return 2 * zeta * omega, {"damping": "modal", "zeta": zeta.tolist()}


def modal_truncation(sub: Substructure, n_keep: int,
                     damping: float | Sequence[float] | Mapping[str, Any] | None = None,
                     *, dense_limit: int = 2000, sigma: float | None = None,
                     factorization: str | Factorize = "auto") -> Substructure:
    """Reduce ``sub`` to its ``n_keep`` lowest undamped modes (eqs 21-22).

    .. math::

        q = \\Phi_r y_r, \\qquad \\ddot y_r + \\Psi_r \\dot y_r + \\Lambda_r y_r = \\Phi_r^T f,
        \\qquad \\Lambda_r = \\operatorname{diag}(\\omega_j^2)                   \\qquad (21, 22)

    The reduced mass and stiffness are exactly :math:`I` and :math:`\\Lambda_r`.  Damping:

    * ``None``: :math:`\\Psi_r = \\Phi_r^T C \\Phi_r` (diagonal only if ``C`` is classical);
    * a ratio ``zeta`` or a list of ``n_keep`` ratios (or ``{"zeta": ...}``):
      :math:`\\Psi_r = \\operatorname{diag}(2 \\zeta_j \\omega_j)`, replacing ``sub.C``;
    * ``{"rayleigh": (alpha, beta)}``: :math:`C = \\alpha M + \\beta K`, i.e.
      :math:`\\Psi_r = \\alpha I + \\beta \\Lambda_r`, replacing ``sub.C``.

    Points and drawing follow the modal coordinates: ``row_new(x) = row(x) @ Phi``.

    Returns:
        The reduced :class:`Substructure`, labels ``y1 .. yg``, kind ``"modal"``,
        ``meta["omega"]`` the kept circular frequencies (rad/s), ``meta["reduced_from"]`` the
        original number of coordinates, ``meta["damping"]`` how ``Psi`` was made.

    Raises:
        ValueError: ``n_keep`` not in ``1 .. n``, massless coordinates, bad damping data.
    """
    g = _check_count(sub, n_keep, "n_keep")
    omega, Phi = undamped_modes(sub, g, dense_limit=dense_limit, sigma=sigma,
                                factorization=factorization)
    psi, damping_meta = _modal_damping(sub, damping, omega)
    reduced = sub.transformed(Phi, tuple(f"y{j}" for j in range(1, g + 1)), kind="modal",
                              omega=omega, n_keep=g, reduced_from=sub.n_dof,
                              reduced_kind=sub.kind, **damping_meta)
    C = reduced.C if psi is None else as_csr(sp.diags_array(psi))
    return replace(reduced, M=as_csr(sp.eye_array(g)), K=as_csr(sp.diags_array(omega**2)), C=C)
