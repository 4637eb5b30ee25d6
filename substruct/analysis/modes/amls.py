r"""Coupled modes by automated multilevel substructuring (AMLS): the ``solver: amls`` strategy.

The constraints are eliminated first (:func:`substruct.analysis.modes.krylov.eliminate`,
``u = T p``, ``A T = 0``), and AMLS (:func:`substruct.linalg.amls.amls_modes`) computes the
eigenpairs of the eliminated pencil

.. math::  T^T K T\, y = \lambda\, T^T M T\, y, \qquad u = T y,

every one below the wanted frequency :math:`\omega_{max}`.  With a ``count`` and no
:math:`\omega_{max}`, :math:`\omega_{max}` grows from :math:`10^{-3}\sqrt{\operatorname{tr} K /
\operatorname{tr} M}` (a scale of the model's own, so the decision does not depend on its units)
by at least a factor 2 per pass (:math:`1.2\,(k/m)^{1/3}` when ``m`` of the ``k`` modes were
found: the count of a solid grows as :math:`\omega^3`) until ``count`` modes are below it, and
the lowest ``count`` are kept.

The cross-check of each mode is its relative residual in the eliminated equations,

.. math::  r_j = \|K_T y_j - \lambda_j M_T y_j\| / \|K_T y_j\|,

reported as ``agreement["amls-residual"]`` (the largest) and held to the tolerance.  A Ritz
value's relative error is of the order of :math:`r_j^2`, so a tolerance on :math:`r_j` of
``t`` holds the frequencies to about :math:`t^2/2`.  The check formulations, if any, are the
shift-invert Lanczos solution of the lowest :data:`CHECKED_MODES` modes
(:func:`substruct.analysis.modes.production.production_modes`), compared by
:func:`substruct.analysis.checks.modes_agreement`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
import scipy.sparse as sp

from substruct.analysis.checks import modes_agreement
from substruct.analysis.errors import AnalysisInputError, singular_model
from substruct.linalg.definite import SingularPencil
from substruct.analysis.events import Phase
from substruct.analysis.modes.krylov import (
    check_inputs,
    constraint_residuals,
    eliminate,
    stiffness_over_mass,
)
from substruct.analysis.modes.pencil import quadratic_forms, rayleigh_root
from substruct.analysis.modes.production import production_modes
from substruct.analysis.modes.roots import normalize_shapes
from substruct.analysis.modes.sparse import has_damping
from substruct.analysis.results import Modes
from substruct.linalg.amls import AMLSModes, amls_modes
from substruct.linalg.task_runner import TaskRunner
from substruct.linalg.amls_tree import dissection_tree
from substruct.linalg.massless import massless_count
from substruct.linalg.system import Matrix

__all__ = ["AMLS_CHECK", "AmlsOptions", "CHECKED_MODES", "amls_coupled_modes",
           "amls_damped_basis", "REAL_ROOT"]

#: A root of the projected damped pencil whose imaginary part is below this fraction of its
#: modulus is real (an over-damped root, an entry of its own).
REAL_ROOT = 1e-10

#: The name of the residual cross-check in ``Modes.agreement``.
AMLS_CHECK = "amls-residual"
#: The lowest modes that a ``check:`` formulation recomputes by shift-invert Lanczos.
CHECKED_MODES = 6
#: The first wanted frequency tried when only a count is given, times
#: :math:`\sqrt{\operatorname{tr} K / \operatorname{tr} M}`.
FIRST_GUESS = 1e-3
#: The Ritz vectors iterated by default: those up to this multiple of the wanted frequency
#: (capped by the cut-off).  Fewer cost less: docs/amls.md measures 1.2 to 2 on a
#: 29,400-coordinate box.
RITZ_RATIO = 2.0
#: Passes of the growing wanted frequency before giving up.
MAX_PASSES = 40


@dataclass(frozen=True)
class AmlsOptions:
    """How AMLS reduces (:func:`substruct.linalg.amls.amls_modes`).

    Attributes:
        cutoff: every block keeps its modes up to ``cutoff`` times the wanted frequency (> 1).
        leaf_size: subdomains are split until at most this many coordinates.
        iterations: subspace iterations with the full factorization after the reduction.
        ritz_ratio: with iterations, the Ritz vectors iterated: those up to ``ritz_ratio``
            times the wanted frequency (capped by ``cutoff``); ``None``:
            :data:`RITZ_RATIO`.
        omega_max: the wanted circular frequency (every mode below it); ``None``: found from
            the count.
        tasks: where the blocks of the reduction run as tasks
            (:class:`~substruct.linalg.task_runner.TaskRunner`: the Dask session of
            ``substruct run --workers N``); ``None``: in this process.  The modes are the
            same bit for bit.
    """

    cutoff: float = 5.0
    leaf_size: int = 1000
    iterations: int = 0
    ritz_ratio: float | None = None
    omega_max: float | None = None
    tasks: TaskRunner | None = field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:
        if not (np.isfinite(self.cutoff) and self.cutoff > 1):
            raise ValueError(f"cutoff must be > 1, got {self.cutoff!r}")
        if self.ritz_ratio is not None and not self.ritz_ratio >= 1:
            raise ValueError(f"ritz_ratio must be >= 1, got {self.ritz_ratio!r}")
        if self.leaf_size < 1 or self.iterations < 0:
            raise ValueError(f"leaf_size >= 1 and iterations >= 0, got {self.leaf_size!r}, "
                             f"{self.iterations!r}")
        if self.omega_max is not None and not (np.isfinite(self.omega_max)
                                               and self.omega_max > 0):
            raise ValueError(f"omega_max must be positive, got {self.omega_max!r}")


def _solve(K: sp.csr_array, M: sp.csr_array, count: int | None, opts: AmlsOptions,
           say: Phase | None) -> tuple[AMLSModes, float]:
    """AMLS at ``opts.omega_max``, or at a growing wanted frequency until ``count`` modes."""
    def line(text: str) -> None:
        if say is not None:
            say("amls", f"modes: {text}", K.shape[0])

    tree = dissection_tree(K, opts.leaf_size, M=M)     # one dissection for every pass

    ritz = min(opts.cutoff, RITZ_RATIO if opts.ritz_ratio is None else opts.ritz_ratio)

    def run(w: float) -> AMLSModes:
        if say is not None:
            say("sparse-eigen", f"modes: AMLS up to {w:.4g} rad/s (cut-off {opts.cutoff:g})", K.shape[0])
        return amls_modes(K, M, w, cutoff=opts.cutoff, leaf_size=opts.leaf_size,
                          iterations=opts.iterations, ritz_ratio=ritz,
                          progress=line, tasks=opts.tasks, tree=tree)

    if opts.omega_max is not None:
        return run(opts.omega_max), opts.omega_max
    assert count is not None
    w = FIRST_GUESS * np.sqrt(stiffness_over_mass(K, M))
    # every block kept every one of its modes (the basis spans every finite mode) and every
    # reduced eigenpair is below the wanted frequency: a model with fewer than ``count`` finite
    # modes has given them all (as the other solvers report it).  The finite modes are the
    # coordinates less the massless directions, combinations of coordinates included
    # (:func:`~substruct.linalg.massless.massless_count`); beyond 1/eps of the stiffness's
    # scale an eigenvalue is a mass at round-off of the stiffness's, an infinite one
    finite = K.shape[0] - massless_count(M)
    infinite = stiffness_over_mass(K, M) / np.finfo(float).eps
    for _ in range(MAX_PASSES):
        r = run(w)
        m = r.lam.size
        if m >= count or m == r.n_reduced >= finite or w * w >= infinite:
            return r, w
        w *= max(2.0, 1.2 * (count / m) ** (1 / 3)) if m else 4.0
    raise AnalysisInputError(f"AMLS found fewer than {count} modes below {w:.3g} rad/s")


def amls_coupled_modes(M: Matrix, C: Matrix | None, K: Matrix, A: Matrix | None,
                       count: int | None, opts: AmlsOptions, checks: Sequence[str] = (),
                       events: Phase | None = None) -> tuple[Modes, dict[str, float], str]:
    r"""The lowest modes of ``K u = lambda M u`` under ``A u = 0`` by AMLS on the null-space
    eliminated pencil (module docstring).

    Args:
        M, C, K, A: the system; ``C`` must be zero (AMLS computes undamped modes).
        count: at most this many modes (the lowest); ``None`` with ``opts.omega_max``: every
            mode below it.
        opts: the reduction (:class:`AmlsOptions`).
        checks: if not empty, the lowest :data:`CHECKED_MODES` modes are recomputed by
            shift-invert Lanczos and compared (``agreement["null-space/sparse"]``).
        events: told as each AMLS pass starts.

    Returns:
        ``(modes, agreement, label)``: the modes (``method`` ``"null-space/amls"``, roots
        :math:`i\omega_j`, shapes :math:`M`-orthonormal, ``residual``
        the constraint residual :math:`|A u| / (|A| |u|)`), the figures
        (``"amls-residual"``: the largest :math:`r_j`), and the strategy's label (cut-off,
        reduced coordinates, iterations).

    Raises:
        AnalysisInputError: a damped model, a motion with neither mass nor stiffness (a
            singular pencil), no count and no wanted frequency.
    """
    if has_damping(C):
        raise AnalysisInputError("solver amls computes undamped modes; the model has damping "
                                 "(use solver: sparse)")
    if count is None and opts.omega_max is None:
        raise AnalysisInputError("solver amls needs a count or a band with a max")
    Ms, Ks, As, _ = check_inputs(M, K, A, count or 1)
    el = eliminate(Ms, As)
    T = sp.csr_array(el.T)
    Kt = sp.csr_array(T.T @ Ks @ T)
    Mt = sp.csr_array(T.T @ Ms @ T)
    try:
        r, w = _solve(Kt, Mt, count, opts, events)
    except (RuntimeError, np.linalg.LinAlgError, SingularPencil) as exc:   # not definite
        raise singular_model("a block's pencil is not definite") from exc
    k = r.lam.size if count is None else min(count, r.lam.size)
    U = T @ r.U[:, :k]
    agreement = {AMLS_CHECK: float(r.residual[:k].max(initial=0.0))}
    main = Modes(eigenvalues=1j * r.omega[:k], omega=r.omega[:k],
                 damping_ratio=np.zeros(k), shapes=U.astype(complex),
                 residual=constraint_residuals(As, U), method="null-space/amls")
    if checks and k:
        few = min(k, CHECKED_MODES)
        ref, _, _ = production_modes(Ms, Ks, As, few, elimination=el)
        agreement["null-space/sparse"] = modes_agreement(main.lowest(few), ref)
    label = (f"amls (cut-off {opts.cutoff:g} x {w:.4g} rad/s, {r.n_reduced} reduced "
             f"coordinates of {Kt.shape[0]}, {r.n_blocks} blocks, {r.iterations} "
             f"iteration(s); largest residual {agreement[AMLS_CHECK]:.1e})")
    return main, agreement, label


#: Roots closer than this fraction of their modulus are one repeated root.
REPEATED_ROOT = 1e-8
#: A repeated root's vectors whose :math:`Z_c^T (2\lambda I + C_r) Z_c` departs from a multiple
#: of the identity by at most this fraction are left as they are (bi-orthogonal to it).
BIORTHOGONAL = 1e-12


def _biorthogonal(lam: np.ndarray, Z: np.ndarray, Cr: np.ndarray) -> np.ndarray:
    r"""The vectors of each repeated root recombined so that
    :math:`z_r^T (2\lambda I + C_r) z_s = 0` for :math:`r \ne s`: with
    :math:`G = Z_c^T (2\lambda I + C_r) Z_c` (complex symmetric) and its eigenvectors
    :math:`V` (complex-orthogonal, :math:`v_i^T v_j = 0`), :math:`Z_c \leftarrow Z_c V`.
    Distinct roots are bi-orthogonal already (:math:`(\lambda_r + \lambda_s) z_r^T z_s +
    z_r^T C_r z_s = 0`)."""
    Z = Z.copy()
    k = 0
    while k < lam.size:
        j = k + 1
        while j < lam.size and abs(lam[j] - lam[k]) <= REPEATED_ROOT * abs(lam[k]):
            j += 1
        if j - k > 1:
            Zc = Z[:, k:j]
            B = 2 * lam[k:j].mean() * Zc + Cr @ Zc
            G = Zc.T @ B
            # the same eigenvectors as G's, computed from its departure from a multiple of
            # the identity (a nearly scalar G, Rayleigh damping, would give eig's vectors to
            # eps |G| / gap, which is no accuracy at all); none left: bi-orthogonal already
            D = G - np.trace(G) / G.shape[0] * np.eye(G.shape[0])
            if np.abs(D).max() > BIORTHOGONAL * np.abs(G).max():
                _, V = np.linalg.eig(D)
                Z[:, k:j] = Zc @ V
        k = j
    return Z


def amls_damped_basis(M: Matrix, C: Matrix | None, K: Matrix, A: Matrix | None,
                      count: int | None, opts: AmlsOptions, events: Phase | None = None
                      ) -> tuple[Modes, str]:
    r"""The roots of :math:`(\lambda^2 M + \lambda C + K) u = 0`, :math:`A u = 0` on the AMLS
    basis: the undamped modes :math:`\Phi` (:func:`amls_coupled_modes`, ``C`` left out, every
    mode below ``opts.omega_max`` or the lowest ``count``), then the damping projected on them,

    .. math::  \big(\lambda^2 I + \lambda\, \Phi^T C \Phi + \Omega^2\big) z = 0,
               \qquad u = \Phi z,

    solved densely in first-order form (``2N`` roots); one root of each conjugate pair is kept
    (``Im > 0``), and each real (over-damped) root, with ``u^H M u = 1``.  The vectors of a
    repeated root (the two bending modes of a square section) are made bi-orthogonal
    (:func:`_biorthogonal`), as the modal sum :math:`\sum_r u_r u_r^T / a_r` needs.  For damping that the
    modes diagonalize (Rayleigh, :math:`C = \alpha M + \beta K`) the roots are those of each
    mode, :math:`\lambda = -\zeta\omega \pm i\omega\sqrt{1 - \zeta^2}`,
    :math:`2\zeta\omega = \alpha + \beta\omega^2`; otherwise they are the Rayleigh-Ritz
    roots of the projected pencil.  Without damping: the undamped modes.

    Returns:
        ``(modes, label)``: the roots (method ``"null-space/amls"``) and the AMLS label.
    """
    main, agreement, label = amls_coupled_modes(M, None, K, A, count, opts, (), events)
    if not has_damping(C) or not len(main):
        return main, label
    assert C is not None
    Phi = main.shapes.real
    n = len(main)
    Cr = Phi.T @ (sp.csr_array(C) @ Phi)
    Cr = (Cr + Cr.T) / 2
    first = np.block([[np.zeros((n, n)), np.eye(n)], [-np.diag(main.omega ** 2), -Cr]])
    lam, V = np.linalg.eig(first)
    real = np.abs(lam.imag) <= REAL_ROOT * np.abs(lam)
    lam = np.where(real, lam.real, lam)
    keep = real | (lam.imag > 0)
    lam, Z = lam[keep], V[:n, keep]
    order = np.lexsort((lam.real, np.abs(lam)))
    lam, Z = lam[order], Z[:, order]
    Z = _biorthogonal(lam, Z, Cr)
    # QR of the first-order matrix is accurate to eps |lambda|_max: a slow decay beside a fast
    # one (C = 1000 M: -0.001 beside -1000) would lose seven digits, which the residual moments
    # of the modal receptance (1 / lambda^3) multiply; the Rayleigh functional of each vector
    # on the projected quadratic gives it to rounding again
    a, b, c = quadratic_forms(Z, np.eye(n), Cr, np.diag(main.omega ** 2))
    refined = np.array([rayleigh_root(lam[j], a[j], b[j], c[j])[0] for j in range(lam.size)],
                       dtype=complex)
    lam = np.where(lam.imag == 0, refined.real, refined)  # a real root stays real
    U = normalize_shapes(Phi @ Z, sp.csr_array(M))
    omega = np.abs(lam)
    zeta = np.where(omega > 0, -lam.real / np.where(omega > 0, omega, 1.0), 0.0)
    As = sp.csr_array(A) if A is not None else sp.csr_array((0, U.shape[0]))
    damped = Modes(eigenvalues=lam, omega=omega, damping_ratio=zeta, shapes=U,
                   residual=constraint_residuals(As, U),
                   method="null-space/amls")
    return damped, f"{label}; damping projected on its {n} modes"
