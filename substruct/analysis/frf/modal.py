r"""Receptances by modal superposition of the coupled modes, with a residual flexibility.

The receptance of a system under ``A q = 0`` is a sum over the roots :math:`\lambda_r` of
``(lambda^2 M + lambda C + K) u = A^T mu``, ``A u = 0`` (eqs 23-34), in the first-order
(state-space) form, which holds for any damping (proportional or not):

.. math::  H(\omega) = \sum_r \frac{u_r u_r^T}{a_r (i\omega - \lambda_r)}, \qquad
           a_r = u_r^T (2 \lambda_r M + C)\, u_r ,

each complex root standing beside its conjugate.  For an undamped model
(:math:`\lambda_r = i \omega_r`, ``u_r^T M u_r = 1``) a pair is the classical
:math:`u_r u_r^T / (\omega_r^2 - \omega^2)`, and for a proportionally damped one
:math:`u_r u_r^T / (\omega_r^2 - \omega^2 + 2 i \zeta_r \omega_r \omega)`.

Only the roots up to a cut-off are computed (:func:`substruct.analysis.api.modes`, dense or
sparse); the truncated ones are replaced by their static part, taken from one static solve of
the constrained system (a Lagrange-multiplier solve with the independent rows of ``A``):

.. math::  H(\omega) \approx \sum_{r \le N} T_r(\omega)
           + \Big( G_{static} - \sum_{r \le N} T_r(0) \Big),
           \qquad G_{static} = H(0) ,

so that the low-frequency limit is exact.  Rigid-body modes (``K u = 0``, ``A u = 0``, found
as zero roots) of an undamped model are handled by inertia relief: their terms
:math:`-\Phi_0 \Phi_0^T / \omega^2` are kept apart and ``G_static`` is the flexibility of the
elastic part,

.. math::  \begin{bmatrix} K & A^T & M \Phi_0 \\ A & 0 & 0 \\ \Phi_0^T M & 0 & 0
           \end{bmatrix} \begin{bmatrix} q \\ \mu \\ \nu \end{bmatrix} =
           \begin{bmatrix} (I - M \Phi_0 \Phi_0^T) F \\ 0 \\ 0 \end{bmatrix} .

A damped model with rigid-body modes, and constraints tied to the force (``R != 0``), are
refused with a one-line ``ValueError``.  The sweep itself costs one small matrix product per
frequency; the direct solve (:func:`substruct.analysis.formulations.coupling.receptance`) at a few check
frequencies is its cross-check.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Callable, Sequence

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from substruct.analysis.checks import (
    check_methods,
    receptance_difference,
    require_agreement,
)
from substruct.analysis.formulations.coupling import receptance
from substruct.analysis.frf.clusters import (
    Cluster,
    cluster_moment,
    cluster_terms,
    root_accuracy,
    root_clusters,
)
from substruct.analysis.modes.amls import AmlsOptions, amls_damped_basis
from substruct.analysis.modes.eigen import modes
from substruct.analysis.errors import AnalysisInputError
from substruct.analysis.system import ConstrainedSystem, SweepOptions
from substruct.analysis.results import Modes, Receptance
from substruct.analysis.modes.sparse import has_damping
from substruct.linalg.constraints import independent_rows
from substruct.linalg.factorize import factorizer
from substruct.vocabulary import GENERALIZED_INVERSE, KKT

__all__ = ["MODAL_ABOVE", "ModalOptions", "frf_method", "DEFAULT_CUTOFF", "MODAL_CHECK_FREQUENCIES", "ModalBasis", "modal_basis",
           "static_solver", "static_moments", "modal_terms", "modal_moment", "RESIDUAL_ORDER", "modal_receptance_sweep", "check_indices"]

#: ``method: auto`` takes the modal sweep above this many coordinates.
MODAL_ABOVE = 2000
#: Default cut-off: the modes up to this multiple of the highest frequency of the grid.
DEFAULT_CUTOFF = 10.0
#: Frequencies of the grid at which the direct solve checks the modal sweep.
MODAL_CHECK_FREQUENCIES = 3
#: Residual terms: none, the static flexibility (``G - sum_r T_r(0)``), or the Taylor terms
#: up to ``s^2`` (:func:`static_moments`; error of the truncation then ``O((w / w_c)^3)``).
RESIDUAL_ORDER = {"none": -1, "static": 0, "second-order": 2}
#: A root below this fraction of the frequency scale is a rigid-body mode.
RIGID_ROOT_FRACTION = 1e-6


@dataclass(frozen=True)
class ModalOptions:
    """How the modal sweep is made (``analysis.frf.modal`` in a case file).

    Attributes:
        count: the number of roots kept (``None``: those up to ``cutoff`` times the highest
            frequency of the grid).
        cutoff: the cut-off as a multiple of the highest frequency.
        residual: one of :data:`RESIDUAL_ORDER`.
        n_check: how many frequencies of the grid the direct solve checks.
        solver: the eigensolver strategy (:func:`substruct.analysis.api.choose_solver`), or
            ``"amls"``: every root below the cut-off on the AMLS basis
            (:func:`substruct.analysis.modes.amls.amls_damped_basis`).
        amls: with ``solver="amls"``, the reduction
            (:class:`~substruct.analysis.modes.amls.AmlsOptions`; its defaults if ``None``).
    """

    count: int | None = None
    cutoff: float = DEFAULT_CUTOFF
    residual: str = "second-order"
    n_check: int = MODAL_CHECK_FREQUENCIES
    solver: str = "auto"
    amls: Any = None


def frf_method(method: str, n: int, R: sp.sparray | np.ndarray | None) -> str:
    """``method`` with ``"auto"`` resolved: ``"modal"`` above :data:`MODAL_ABOVE` coordinates
    (unless a constraint is tied to the force), ``generalized-inverse`` otherwise."""
    if method != "auto":
        return method
    tied = R is not None and bool(np.any(sp.csr_array(R).data != 0))
    return "modal" if n > MODAL_ABOVE and not tied else GENERALIZED_INVERSE


@dataclass(frozen=True)
class ModalBasis:
    """The retained roots of the coupled system, as the modal sum needs them.

    Attributes:
        eigenvalues: elastic roots ``lambda_r`` (``Im >= 0``; one per conjugate pair).
        shapes: ``n x N`` complex shapes ``u_r``.
        norms: ``a_r = u_r^T (2 lambda_r M + C) u_r``.
        paired: whether a root stands for a conjugate pair (``Im lambda_r > 0``).
        rigid: ``n x r0`` rigid-body shapes, ``Phi_0^T M Phi_0 = I`` (undamped models only).
        highest: the largest ``|lambda_r|`` computed (rad/s).
        clusters: the repeated roots, summed through their projected pencils
            (:mod:`substruct.analysis.frf.clusters`) instead of ``1 / a_r``.
    """

    eigenvalues: np.ndarray
    shapes: np.ndarray
    norms: np.ndarray
    paired: np.ndarray
    rigid: np.ndarray
    highest: float
    clusters: tuple[Cluster, ...] = ()

    @property
    def count(self) -> int:
        """Number of retained elastic roots."""
        return int(self.eigenvalues.size)


def _modes(M: sp.csr_array, C: sp.csr_array | None, K: sp.csr_array, A: sp.csr_array,
           count: int | None, solver: str) -> Modes:
    return modes(M, C, K, A, count, solver=solver, what="frf (modal)")


def modal_basis(M: sp.csr_array, C: sp.csr_array | None, K: sp.csr_array, A: sp.csr_array,
                omega_max: float, *, count: int | None = None,
                cutoff: float = DEFAULT_CUTOFF, solver: str = "auto",
                amls: Any = None) -> ModalBasis:
    r"""The roots of the coupled system up to ``cutoff * omega_max`` (or the lowest ``count``).

    .. math::  |\lambda_r| \le c\, \omega_{max}

    With ``count`` ``None`` the sparse solvers are asked for 20, 40, 80, ... roots until one
    passes the cut-off (the dense solver computes all and keeps those below it).  With
    ``solver="amls"`` one AMLS reduction gives every undamped mode below the cut-off (or the
    lowest ``count``) and the damping is projected on them
    (:func:`substruct.analysis.modes.amls.amls_damped_basis`, options ``amls``).  Repeated
    roots are grouped (:func:`substruct.analysis.frf.clusters.root_clusters`), whatever basis
    of their eigenspace the eigensolver gave.

    Raises:
        ValueError: a damped model with rigid-body modes.
    """
    n = K.shape[0]
    damped = has_damping(C)
    Cm = C if damped else None
    limit = cutoff * omega_max
    if solver == "amls":
        opts = amls if amls is not None else AmlsOptions()
        opts = replace(opts, omega_max=None if count is not None else limit)
        md, _ = amls_damped_basis(M, Cm, K, A, None if count is None else min(int(count), n),
                                  opts)
    elif count is not None:
        md = _modes(M, Cm, K, A, min(int(count), n), solver)
    else:
        k = min(20, n)
        while True:
            md = _modes(M, Cm, K, A, k, solver)
            if len(md) < k or md.omega.max(initial=0.0) > limit or k >= n:
                break
            k = min(2 * k, n)
        md = md.lowest(int(np.sum(md.omega <= limit)) + (1 if np.any(md.omega > limit) else 0))
    lam = np.asarray(md.eigenvalues, dtype=complex)
    U = np.asarray(md.shapes, dtype=complex)
    highest = float(np.abs(lam).max(initial=0.0))
    scale = max(omega_max, highest, 1e-300)
    rigid = np.abs(lam) <= RIGID_ROOT_FRACTION * scale
    if np.any(rigid) and damped:
        raise AnalysisInputError("modal receptance of a damped model with rigid-body modes is not "
                         "supported; use method: generalized-inverse")
    Phi = U[:, rigid].real
    if Phi.shape[1]:
        L = np.linalg.cholesky(Phi.T @ (M @ Phi))
        Phi = np.linalg.solve(L, Phi.T).T  # Phi_0^T M Phi_0 = I
    lam, U = lam[~rigid], U[:, ~rigid]
    MU = M @ U
    CU = C @ U if damped and C is not None else np.zeros_like(U)
    norms = np.einsum("ir,ir->r", U, 2 * lam[None, :] * MU + CU)
    Cd = C if damped else None
    accuracy = root_accuracy(M, Cd, K, A, lam, U, norms)
    clusters = root_clusters(M, Cd, K, lam, U, lam.imag > 0, accuracy)
    return ModalBasis(lam, U, norms, lam.imag > 0, Phi, highest, clusters)


def _singles(basis: ModalBasis) -> np.ndarray:
    """Whether each root is summed on its own (in no cluster)."""
    single = np.ones(basis.count, dtype=bool)
    for c in basis.clusters:
        single[c.index] = False
    return single


def static_solver(K: sp.csr_array, M: sp.csr_array, A: sp.csr_array,
                  rigid: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    r"""``F -> G_static F``: the static response of the constrained system, by one
    factorization of the saddle-point matrix (inertia relief against the rigid shapes
    ``Phi_0``, M-orthonormal).

    .. math::  \begin{bmatrix} K & \beta A_k^T & M \Phi_0 \\ \beta A_k & 0 & 0 \\
               \Phi_0^T M & 0 & 0 \end{bmatrix} x =
               \begin{bmatrix} (I - M \Phi_0 \Phi_0^T) F \\ 0 \\ 0 \end{bmatrix}

    ``A_k`` are the independent rows of ``A``, ``beta = |K| / |A_k|`` balances the blocks.

    Raises:
        ValueError: the constrained stiffness is singular (a mechanism the modes missed).
    """
    n = K.shape[0]
    Ak = A[independent_rows(A).keep] if A.shape[0] else sp.csr_array((0, n))
    normA = max(float(spla.norm(Ak)), 1e-300) if Ak.shape[0] else 1.0
    beta = max(float(spla.norm(K)), 1e-300) / normA
    MPhi = M @ rigid
    r0, m = rigid.shape[1], Ak.shape[0]
    blocks: list[list[sp.sparray | None]] = [[K]]
    if m:
        blocks = [[K, beta * Ak.T], [beta * Ak, None]]
    if r0:
        Mp = sp.csr_array(MPhi)
        blocks = [row + [Mp if i == 0 else None] for i, row in enumerate(blocks)]
        blocks.append([sp.csr_array(MPhi.T)] + [None] * len(blocks))
    big = sp.csc_array(sp.block_array(blocks, format="csc"))
    try:
        solve = factorizer("saddle")(big)
    except RuntimeError:
        raise AnalysisInputError("the constrained stiffness is singular (a mechanism with no mass?); "
                         "the modal receptance needs a static solve") from None

    def flexibility(F: np.ndarray) -> np.ndarray:
        F = np.asarray(F).reshape(n, -1)
        if r0:
            F = F - MPhi @ (rigid.T @ F)
        rhs = np.vstack([F, np.zeros((big.shape[0] - n, F.shape[1]), dtype=F.dtype)])
        x = solve(rhs)
        x = x + solve(rhs - big @ x)  # one step of iterative refinement
        return np.asarray(x[:n])

    return flexibility


def static_moments(flexibility: Callable[[np.ndarray], np.ndarray], M: sp.csr_array,
                   C: sp.csr_array | None, E: np.ndarray, order: int) -> list[np.ndarray]:
    r"""``X_k = H_k E`` for ``k = 0 .. order``: the Taylor coefficients of the constrained
    receptance in :math:`s = i\omega` about ``s = 0``.

    .. math::  H(s) = (K + s C + s^2 M)^{-1}_{A} = G - s\, G C G
               + s^2 (G C G C G - G M G) + O(s^3)

    (``G`` the constrained static flexibility; one back-substitution per term.)
    """
    X0 = flexibility(E)
    out = [X0]
    if order >= 1:
        X1 = -flexibility(C @ X0) if C is not None else np.zeros_like(X0)
        out.append(X1)
    if order >= 2:
        rhs = M @ X0 + (C @ X1 if C is not None else 0)
        out.append(-flexibility(rhs))
    return out


def modal_terms(basis: ModalBasis, P: np.ndarray, Q: np.ndarray,
                omegas: np.ndarray) -> np.ndarray:
    r"""``sum_r T_r(omega_k)`` projected on outputs and inputs, ``(n_omega, q, p)``.

    .. math::  \sum_r \frac{(O u_r)(u_r^T E)}{a_r (i \omega - \lambda_r)}
               + \text{conjugates} - \frac{O \Phi_0 \Phi_0^T E}{\omega^2}

    ``P = O U`` (``q x N``), ``Q = U^T E`` (``N x p``); the rigid part needs ``omega > 0``.
    A cluster of repeated roots is summed through its projected pencil
    (:func:`substruct.analysis.frf.clusters.cluster_terms`).
    """
    lam, a, pair = basis.eigenvalues, basis.norms, basis.paired
    iw = 1j * np.asarray(omegas, dtype=float)[:, None]
    single = _singles(basis)
    f = np.where(single[None, :], 1.0 / (a[None, :] * (iw - lam[None, :])), 0)
    g = np.where(pair[None, :] & single[None, :],
                 1.0 / (np.conj(a)[None, :] * (iw - np.conj(lam)[None, :])), 0)
    out = np.einsum("qr,kr,rp->kqp", P, f, Q, optimize=True)
    if np.any(pair):
        out += np.einsum("qr,kr,rp->kqp", np.conj(P), g, np.conj(Q), optimize=True)
    if basis.clusters:
        out += cluster_terms(basis.clusters, pair, P, Q, np.asarray(omegas, dtype=float))
    return out


def modal_moment(basis: ModalBasis, P: np.ndarray, Q: np.ndarray, k: int) -> np.ndarray:
    r"""The coefficient of :math:`s^k` of the retained elastic terms about ``s = 0``:

    .. math::  \sum_r -\frac{(O u_r)(u_r^T E)}{a_r \lambda_r^{k+1}} + \text{conjugates}
    """
    lam, a, pair = basis.eigenvalues, basis.norms, basis.paired
    f = np.where(_singles(basis), -1.0 / (a * lam ** (k + 1)), 0)
    out = (P * f[None, :]) @ Q
    if np.any(pair):
        g = np.where(pair, np.conj(f), 0)
        out = out + (np.conj(P) * g[None, :]) @ np.conj(Q)
    if basis.clusters:
        out = out + cluster_moment(basis.clusters, pair, P, Q, k)
    return np.asarray(out)


def check_indices(count: int, k: int = MODAL_CHECK_FREQUENCIES) -> np.ndarray:
    """``k`` indices spread over a grid of ``count`` frequencies (first, last, between)."""
    return np.unique(np.round(np.linspace(0, count - 1, min(k, count))).astype(int))


def modal_receptance_sweep(system: ConstrainedSystem, omegas: Sequence[float] | np.ndarray,
                           inputs: sp.sparray | np.ndarray, outputs: sp.sparray | np.ndarray,
                           *, options: SweepOptions) -> Receptance:
    r"""Receptances at ``omegas`` by modal superposition plus residual flexibility, checked by
    the direct solve at ``n_check`` frequencies of the grid.

    .. math::  H[k] = O \Big[ \sum_{r \le N} T_r(\omega_k) + G_{static}
               - \sum_{r \le N} T_r(0) \Big] E

    Args:
        system: the assembled model (:class:`~substruct.linalg.system.ConstrainedSystem`); its
            ``R`` must be zero: a force-tied constraint is refused.
        omegas: circular frequencies (rad/s).
        inputs, outputs: ``n x p`` force patterns and ``q x n`` output rows.
        options: the checks, tolerance, names and ``what`` of the sweep
            (:class:`~substruct.analysis.system.SweepOptions`), and in ``options.modal`` the
            roots kept, the residual (:data:`RESIDUAL_ORDER`: ``"static"``, exact at
            ``omega = 0``; ``"second-order"``, also the ``s`` and ``s^2`` terms from two more
            back-substitutions; ``"none"`` only to show what the others are worth), the
            number of check frequencies, the eigensolver (:class:`ModalOptions`).
            ``options.checks`` are the direct formulations (``kkt`` if none) and
            ``options.tolerance`` the largest ``max |H_direct - H| / max |H|`` at the check
            frequencies.

    Returns:
        A :class:`~substruct.analysis.results.Receptance` with ``method`` naming the roots
        kept, ``agreement`` keyed ``"<check> (<n> frequencies)"`` and ``constraint_residual``
        the largest :math:`|A x|_\infty / (|A|_F |x|_\infty)` over the retained shapes and
        the static responses (everything the sum is made of).

    Raises:
        CheckError: a direct solve disagrees by more than ``tolerance``.
        ValueError: ``R != 0``; a damped model with rigid-body modes; a zero frequency with
            rigid-body modes.
    """
    Ks, Ms, Cs, As = system.K, system.M, system.C, system.A
    modal = options.modal if options.modal is not None else ModalOptions()
    checks, tolerance, what = options.checks, options.tolerance, options.what
    input_names, output_names = options.input_names, options.output_names
    if system.R is not None:
        raise AnalysisInputError("the modal receptance needs A q = 0; a constraint tied to the force "
                         "(R) needs method: generalized-inverse")
    w = np.atleast_1d(np.asarray(omegas, dtype=float))
    E = sp.csc_array(inputs, dtype=float).toarray()
    O = sp.csr_array(outputs, dtype=float)
    basis = modal_basis(Ms, Cs, Ks, As, float(w.max(initial=0.0)), count=modal.count,
                        cutoff=modal.cutoff, solver=modal.solver, amls=modal.amls)
    residual = modal.residual
    if basis.rigid.shape[1] and np.any(w <= 0):
        raise AnalysisInputError("the receptance of a model with rigid-body modes is infinite at "
                         "omega = 0")
    P = O @ basis.shapes
    Q = basis.shapes.T @ E
    H = modal_terms(basis, P, Q, w)
    if basis.rigid.shape[1]:
        OPhi, PhiE = O @ basis.rigid, basis.rigid.T @ E
        H -= (OPhi @ PhiE)[None] / w[:, None, None] ** 2
    if residual not in RESIDUAL_ORDER:
        raise ValueError(f"unknown residual {residual!r}; expected one of "
                         f"{', '.join(RESIDUAL_ORDER)}")
    order = RESIDUAL_ORDER[residual]
    if order >= 0:
        flex = static_solver(Ks, Ms, As, basis.rigid)
        X = static_moments(flex, Ms, Cs if has_damping(Cs) else None, E, order)
        s_k = 1j * w
        for k, Xk in enumerate(X):
            H += (s_k ** k)[:, None, None] * (O @ Xk - modal_moment(basis, P, Q, k))[None]
        vectors = np.hstack([basis.shapes, *X])
    else:
        vectors = basis.shapes
    norm_a = max(float(spla.norm(As)), 1e-300) if As.shape[0] else 1.0
    size = np.maximum(np.abs(vectors).max(axis=0, initial=0.0), 1e-300) * norm_a
    constraint_residual = float((np.abs(As @ vectors).max(axis=0, initial=0.0) / size).max(
        initial=0.0)) if As.shape[0] and vectors.shape[1] else 0.0
    idx = check_indices(len(w), modal.n_check)
    agreement = {}
    for check in check_methods("modal", list(checks) or [KKT]) if idx.size else []:
        Hd = receptance(Ks, Ms, Cs, As, w[idx], None, method=check, inputs=E, outputs=O)
        agreement[f"{check} ({len(idx)} frequencies)"] = receptance_difference(Hd, H[idx])
    what_modes = f"modal: {basis.count} root(s) up to {basis.highest:.4g} rad/s" + \
        (" (AMLS basis)" if modal.solver == "amls" else "") + \
        (f", {basis.rigid.shape[1]} rigid" if basis.rigid.shape[1] else "") + \
        (f" + {residual} residual" if order >= 0 else ", no residual")
    require_agreement(what, what_modes, agreement, tolerance)
    names_in = list(input_names) if input_names is not None else \
        [str(j + 1) for j in range(E.shape[1])]
    names_out = list(output_names) if output_names is not None else \
        [str(i + 1) for i in range(O.shape[0])]
    return Receptance(method=what_modes, omega=w, H=H, inputs=names_in, outputs=names_out,
                      agreement=agreement, constraint_residual=constraint_residual,
                      tolerance=float(tolerance))
