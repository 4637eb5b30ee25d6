r"""Automated multilevel substructuring (AMLS): all eigenpairs of :math:`K u = \lambda M u`
below a wanted frequency, for many modes of large sparse models.

1. Nested dissection of the graph of ``|K| + |M|`` into subdomains and separators
   (:func:`substruct.linalg.amls_tree.dissection_tree`, METIS bisections and minimum vertex
   covers of the cuts).
2. Bottom-up reduction (:func:`substruct.linalg.amls_reduce.amls_reduce`): in every block the
   fixed-interface modes with eigenvalue up to the cut-off
   :math:`\lambda_c = (r\,\omega_{max})^2` (``r`` = ``cutoff``, a multiple of the highest
   wanted circular frequency) and the exact static (constraint-mode) coupling onto its
   ancestors' separators; the reduced pencil :math:`(\operatorname{diag}\Lambda, M_r)`.
3. The reduced eigenproblem, dense, for every eigenvalue up to :math:`\omega_{max}^2` (or, to be
   improved, up to :math:`(s\,\omega_{max})^2`, ``s`` = ``ritz_ratio``), expanded to physical
   coordinates :math:`U = Z Y`.
4. Optionally ``iterations`` steps of subspace iteration with the full factorization,
   :math:`W = (K - \sigma M)^{-1} M U`, then Rayleigh-Ritz on :math:`W`
   (:func:`substruct.linalg.amls_improve.subspace_iteration`, in blocks); one step
   multiplies the error of
   :math:`\lambda_j` by about :math:`((\lambda_j - \sigma)/(\lambda_{p+1} - \sigma))^2`,
   :math:`\lambda_{p+1}` the first Ritz value left out.  Two or more steps are
   Chebyshev-shifted on the eigenvalues beyond
   :math:`\lambda_u = \sqrt{\lambda_b \lambda_c}`, the geometric mean of the Ritz bound
   :math:`\lambda_b = (s\,\omega_{max})^2` and the cut-off: the span's error lies in the
   components near and above the cut-off, which the reduction truncated, while those between
   the bound and the cut-off are Ritz vectors left out, which the Rayleigh-Ritz keeps apart
   (measured on a 29,400-coordinate box, 500 modes, two steps: largest frequency error
   7.6e-5 with this :math:`\lambda_u`, 1.9e-4 with :math:`\lambda_b`, 2.1e-4 plain).

Accuracy: AMLS is a Rayleigh-Ritz method on nested subspaces, so every computed
:math:`\lambda_j` is an upper bound of the exact one and decreases monotonically as the
cut-off grows, reaching it (to round-off) when every mode is kept.  Every returned mode has
its relative residual :math:`\|K u - \lambda M u\| / \|K u\|` in the full space.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from substruct.linalg.amls_improve import (
    SOLVE_COLUMNS,
    Vectors,
    chebyshev_shifts,
    filter_steps,
    ritz_pairs,
)
from substruct.linalg.column_file import ColumnFile
from substruct.linalg.amls_reduce import ReducedModel, amls_reduce
from substruct.linalg.amls_tree import DissectionNode, dissection_tree
from substruct.linalg.definite import definite_factorization
from substruct.linalg.factorize import factorizer
from substruct.linalg.scaling import rigid_eigenvalue, rigid_modes, stiffness_over_mass
from substruct.linalg.scratch_arrays import ScratchArrays
from substruct.linalg.task_runner import TaskRunner
from substruct.machine import available_memory

__all__ = ["AMLSModes", "RITZ_ON_DISK", "amls_modes", "expand_modes", "free_shift",
           "iterated_vectors", "reduced_eigenpairs", "relative_residuals"]

#: The shift of the subspace iteration and of the blocks with no boundary, as a fraction of
#: the wanted eigenvalue :math:`\omega_{max}^2` (negative: ``K - sigma M`` is positive
#: definite for a free body, whatever the rank of ``M``).
SHIFT_FRACTION = -1e-3

#: ... and at least this fraction of the stiffness's scale :math:`\operatorname{tr} K /
#: \operatorname{tr} M` (a wanted frequency far below a stiff body's first flexible one would
#: otherwise leave ``K - sigma M`` singular to working precision on its rigid-body modes).
SHIFT_FLOOR = 1e-5

#: ... and at most this fraction of it: the eigenvalues come out as :math:`\sigma + 1/\mu`,
#: to about :math:`\epsilon |\sigma|` absolutely, so a wanted frequency far above the model's
#: highest mode (``band: {max: 1e12}`` on a rod whose modes end at 1.8e5 rad/s) made the
#: lowest modes wrong (8.6e-4 with every block's modes kept) with :math:`\sigma` following it.
SHIFT_CEILING = 1.0


def free_shift(K: sp.sparray, M: sp.sparray, lam_w: float) -> float:
    r"""The shift :math:`\sigma` of the blocks with no boundary, the reduced pencil of a free body
    and the subspace iteration: :math:`\sigma = f \min(\max(\omega_{max}^2, 10^{-5} s), s)`,
    :math:`s = \operatorname{tr} K / \operatorname{tr} M`, :math:`f` = :data:`SHIFT_FRACTION`,
    so that :math:`K - \sigma M` is positive definite to working precision for a free body at
    any wanted frequency (its rigid-body modes' eigenvalue :math:`-\sigma` is at least
    :math:`10^{-8}` of the stiffness's scale), and no larger than the stiffness's scale makes
    it (:data:`SHIFT_CEILING`: an eigenvalue :math:`\lambda` comes out to about
    :math:`\epsilon \max(|\sigma|, \lambda^2 / |\sigma|)`)."""
    scale = stiffness_over_mass(K, M)
    return SHIFT_FRACTION * min(max(lam_w, SHIFT_FLOOR * scale), SHIFT_CEILING * scale)


@dataclass
class AMLSModes:
    r"""Eigenpairs by AMLS, ascending.

    Attributes:
        lam: eigenvalues :math:`\omega^2` up to the wanted one.
        U: ``n x k`` mode shapes, ``M``-orthonormal.
        residual: relative residual :math:`\|K u - \lambda M u\| / \|K u\|` of each mode.
        n_reduced: number of reduced coordinates (modes kept over all blocks).
        kept_per_level: number of modes kept at each tree level (0: the root separator).
        n_blocks: number of blocks (subdomains and separators) of the tree.
        iterations: subspace iterations done.
        times: seconds spent in each stage (``tree``, ``reduce``, ``reduced``, ``expand``,
            ``improve``, ``residual``).
    """

    lam: np.ndarray
    U: np.ndarray
    residual: np.ndarray
    n_reduced: int
    kept_per_level: np.ndarray
    n_blocks: int
    iterations: int
    times: dict[str, float] = field(default_factory=dict)

    @property
    def omega(self) -> np.ndarray:
        """Circular frequencies :math:`\\sqrt{\\max(\\lambda, 0)}`."""
        return np.sqrt(np.maximum(self.lam, 0.0))


def relative_residuals(K: sp.sparray, M: sp.sparray, lam: np.ndarray, U: np.ndarray
                       ) -> np.ndarray:
    r""":math:`\|K u_j - \lambda_j M u_j\| / \|K u_j\|` per column; for a rigid-body mode
    (:math:`\lambda_j = 0`, where :math:`K u_j` is round-off and the ratio 0/0)
    :math:`\|K u_j\| / \|\,|K|\,|u_j|\,\|`, the force left against the largest one its
    entries could make (``inf`` where the denominator is 0)."""
    out = np.empty(U.shape[1])
    absK = abs(K) if np.any(lam == 0.0) else None
    for j in range(0, U.shape[1], SOLVE_COLUMNS):
        Uj = np.ascontiguousarray(U[:, j:j + SOLVE_COLUMNS])
        KU = K @ Uj
        num = np.linalg.norm(KU - (M @ Uj) * lam[j:j + SOLVE_COLUMNS], axis=0)
        den = np.linalg.norm(KU, axis=0)
        rigid = lam[j:j + SOLVE_COLUMNS] == 0.0
        if absK is not None and rigid.any():
            den[rigid] = np.linalg.norm(absK @ np.abs(Uj[:, rigid]), axis=0)
        with np.errstate(divide="ignore", invalid="ignore"):
            out[j:j + SOLVE_COLUMNS] = np.where(den > 0, num / np.where(den > 0, den, 1.0), np.inf)
    return out


#: The factorization of the subdomains and of the full matrix: the registry's choice
#: (:mod:`substruct.linalg.factorize`), the fastest backend installed.
AUTO = "auto"

#: Reduced pencils up to this size are solved by a dense ``eigh``; larger ones by Lanczos
#: unless many of their eigenpairs are wanted (:data:`LANCZOS_FRACTION`).
DENSE_REDUCED = 3000

#: Lanczos on a reduced pencil only while the pairs it asks for (twice the blocks'
#: eigenvalues below the bound) are fewer than this fraction of its size.  Measured on the
#: reduced pencils of a 29,400-coordinate box (CPU s, dense against Lanczos): 2,626 pairs of
#: 4,481 coordinates 14.8 against 214.5; 290 of 2,668 1.90 against 1.99; 290 of 6,900 9.13
#: against 9.09.  Cut-off 2 asks for about 0.6 of the size: thousands of modes are dense.
LANCZOS_FRACTION = 0.1


def reduced_eigenpairs(red: ReducedModel, lam_max: float, shift: float | None = None
                       ) -> tuple[np.ndarray, np.ndarray]:
    r"""Every eigenpair of :math:`\operatorname{diag}(\Lambda) y = \lambda M_r y` with
    :math:`\lambda \le` ``lam_max``, ``M_r``-normalized.

    A singular :math:`\Lambda` (a free body's rigid modes): dense, in the inverse form
    :math:`M_r y = \mu (\Lambda - \sigma M_r) y`, :math:`\lambda = \sigma + 1/\mu`,
    :math:`\sigma` = ``shift`` (:func:`free_shift`; by default :data:`SHIFT_FRACTION`
    ``lam_max``; positive definite on the right whatever the rank of :math:`M_r`).  Otherwise, with :math:`\Lambda > 0` diagonal, the
    pencil is the standard symmetric problem

    .. math::  \hat M z = \mu z, \qquad \hat M = \Lambda^{-1/2} M_r \Lambda^{-1/2}, \qquad
               \mu = 1/\lambda, \quad y = \Lambda^{-1/2} z / \sqrt{\mu},

    solved by a dense ``eigh`` (MRRR, subset by value; the generalized solver would first
    factorize :math:`M_r` and reduce the pencil) up to :data:`DENSE_REDUCED` coordinates or
    when many pairs are wanted (:data:`LANCZOS_FRACTION`); else its largest eigenvalues by
    Lanczos (``eigsh``, ``which="LA"``) with sparse products only (the
    inverse iteration is free: :math:`K_r` is diagonal), the number asked for growing until one
    found is beyond ``lam_max``.
    """
    if red.size == 0:
        return np.zeros(0), np.zeros((0, 0))
    if red.lam.min() <= 0:
        sigma = SHIFT_FRACTION * lam_max if shift is None else shift
        Mr = red.M.toarray(order="F")
        Ks = -sigma * Mr
        Ks[np.diag_indices(red.size)] += red.lam
        mu, Y = sla.eigh(Mr, Ks, subset_by_value=(1.0 / (lam_max - sigma), np.inf),
                         driver="gvx", overwrite_b=True)
        return sigma + 1.0 / mu[::-1], Y[:, ::-1] / np.sqrt(mu[::-1])
    d = 1.0 / np.sqrt(red.lam)
    D = sp.diags_array(d)
    Mh = sp.csr_array(D @ red.M @ D)
    k = min(max(32, 2 * int(np.sum(red.lam <= lam_max))), red.size - 2)
    if red.size <= DENSE_REDUCED or k >= LANCZOS_FRACTION * red.size:
        # Fortran order: LAPACK then works in this array (a C-ordered one is copied first,
        # 1 GB more for the 11,225 reduced coordinates of 2,000 modes)
        mu, Z = sla.eigh(Mh.toarray(order="F"), subset_by_value=(1.0 / lam_max, np.inf),
                         driver="evr", overwrite_a=True)
        lam = 1.0 / mu[::-1]
        return lam, Z[:, ::-1] * d[:, None] * np.sqrt(lam)
    v0 = np.random.default_rng(0).standard_normal(red.size)
    while True:
        mu, Z = spla.eigsh(Mh, k=k, which="LA", v0=v0)
        if mu.min() < 1.0 / lam_max or k >= red.size - 2:
            break
        k = min(int(1.5 * k) + 1, red.size - 2)
    lam = 1.0 / mu
    order = np.argsort(lam)
    order = order[lam[order] <= lam_max]
    return lam[order], Z[:, order] * d[:, None] * np.sqrt(lam[order])


#: Mode shapes are made in a file (:class:`~substruct.linalg.scratch_arrays.ScratchArrays`)
#: when the ``n x k`` array would take more than this fraction of the memory available.
MODES_ON_DISK = 0.4

#: The fraction of the memory available that the temporaries of one block of columns of an
#: expansion to disk may take (about ``16 n`` bytes a column: the subdomains' parts and their
#: boundaries' values).
EXPAND_MEMORY = 0.1


def expand_modes(red: ReducedModel, Y: np.ndarray, tasks: TaskRunner | None,
                 scratch: ScratchArrays) -> np.ndarray:
    r"""The mode shapes :math:`U = Z Y` (:meth:`ReducedModel.expand`), in memory, or, when
    ``n x k`` doubles would exceed :data:`MODES_ON_DISK` of the memory available, in a
    column-major file of ``scratch`` expanded a block of columns at a time (each block's
    temporaries within :data:`EXPAND_MEMORY` of it; the subdomains are factorized again for
    each block).  The same numbers either way, each column's expansion being independent (up to
the rounding of the dense products over blocks of other widths)."""
    n, k = red.n, Y.shape[1]
    have = available_memory()
    if not k or have is None or 8.0 * n * k <= MODES_ON_DISK * have:
        return red.expand(Y, tasks) if k else np.zeros((n, 0))
    U = scratch.empty((n, k))
    columns = int(min(k, max(16, EXPAND_MEMORY * have // (16 * n))))
    for j in range(0, k, columns):
        red.expand(Y[:, j:j + columns], tasks, out=U[:, j:j + columns])
    return U


#: Ritz vectors of this many bytes or more are iterated from a file
#: (:class:`~substruct.linalg.column_file.ColumnFile`), not from memory: the subspace
#: iteration then holds the full factorization and a few blocks of columns, not the ``n x p``
#: vectors beside it (2.4 GB of 1,012 vectors of 297,714 coordinates, as much as the
#: Lanczos basis of the same 500 modes).
RITZ_ON_DISK = 64 * 2**20


def iterated_vectors(U: np.ndarray, scratch: ScratchArrays) -> Vectors:
    """The Ritz vectors ``U`` as the subspace iteration takes them: ``U`` itself when of less
    than :data:`RITZ_ON_DISK` bytes and in memory, else a new column file of ``scratch``
    (blocks of ``SOLVE_COLUMNS`` columns) written a block at a time, the file of ``U`` (mode
    shapes larger than the memory, :func:`expand_modes`) removed then.  The caller drops ``U``
    then."""
    if U.nbytes < RITZ_ON_DISK and not isinstance(U, np.memmap):
        return U
    W = scratch.columns(U.shape, SOLVE_COLUMNS)
    for j in range(0, U.shape[1], SOLVE_COLUMNS):
        W.write(j, U[:, j:j + SOLVE_COLUMNS])
    scratch.discard(U)
    return W


def amls_modes(K: sp.sparray | sp.spmatrix, M: sp.sparray | sp.spmatrix, omega_max: float,
               cutoff: float = 5.0, leaf_size: int = 1000, iterations: int = 0,
               ritz_ratio: float = 1.5, progress: Callable[[str], None] | None = None,
               tasks: TaskRunner | None = None, tree: DissectionNode | None = None
               ) -> AMLSModes:
    r"""The eigenpairs of :math:`K u = \omega^2 M u` with :math:`\omega \le` ``omega_max`` by
    AMLS (module docstring).

    Args:
        K, M: ``n x n`` sparse symmetric stiffness (positive semi-definite; positive definite on
            every subdomain the dissection makes that has a boundary) and mass (positive
            semi-definite: massless coordinates held by a stiffness have no finite eigenvalue
            in any block, and none is kept).
        omega_max: the highest wanted circular frequency.
        cutoff: ``r``: every block keeps its modes up to ``r * omega_max``.
        leaf_size: subdomains are split until they have at most this many coordinates.
        iterations: subspace iterations with the full factorization after the reduction.
        ritz_ratio: with iterations, the Ritz vectors iterated are those up to
            ``ritz_ratio * omega_max`` (capped by the cut-off).
        progress: receives one line per stage and tree level.
        tasks: where the blocks of the reduction and the subdomains' expansions run
            (:class:`~substruct.linalg.task_runner.TaskRunner`, e.g. a Dask session);
            default: in this process.  The results do not depend on it.
        tree: the dissection of the pencil
            (:func:`~substruct.linalg.amls_tree.dissection_tree` of ``K`` with ``leaf_size``
            and ``M=M``), if already made (another wanted frequency of the same model).

    A free body's rigid-body modes (:func:`~substruct.linalg.scaling.rigid_modes`: strain
    energy at round-off) come back at 0, their
    residual measured by :func:`relative_residuals` against :math:`|K|\,|u|`.
    """
    if not (np.isfinite(omega_max) and omega_max > 0):
        raise ValueError(f"omega_max must be positive and finite, got {omega_max!r}")
    if not (np.isfinite(cutoff) and cutoff >= 1):
        raise ValueError(f"cutoff must be at least 1, got {cutoff!r}")
    if iterations < 0:
        raise ValueError(f"iterations must be non-negative, got {iterations!r}")
    say = progress or (lambda line: None)
    K = sp.csr_array(K, dtype=float)
    M = sp.csr_array(M, dtype=float)
    lam_w = float(omega_max) ** 2
    # rigid-body modes come out at round-off of the stiffness's scale, of either sign: every
    # stage keeps the eigenvalues up to that level too (a free body wanted below 1e-6 of its
    # first flexible frequency lost some of them), and the last keeps the rigid ones
    lam_0 = rigid_eigenvalue(K, M)
    lam_c = max((cutoff * omega_max) ** 2, lam_0)
    times: dict[str, float] = {}
    t = time.perf_counter()
    root = dissection_tree(K, leaf_size, M=M) if tree is None else tree
    n_blocks = len(root.postorder())
    times["tree"] = time.perf_counter() - t
    say(f"AMLS tree: {n_blocks} blocks, {max(b.level for b in root.postorder()) + 1} levels")
    t = time.perf_counter()
    shift = free_shift(K, M, lam_w)
    red = amls_reduce(K, M, root, lam_c, AUTO, say, tasks, shift)
    times["reduce"] = time.perf_counter() - t
    say(f"AMLS reduced: {red.size} coordinates from {red.n}")
    t = time.perf_counter()
    bound = max(min(ritz_ratio ** 2, cutoff ** 2) * lam_w if iterations else lam_w, lam_0)
    lam, Y = reduced_eigenpairs(red, bound, shift)
    times["reduced"] = time.perf_counter() - t
    t = time.perf_counter()
    scratch = ScratchArrays("substruct-modes-")
    U = expand_modes(red, Y, tasks, scratch)
    times["expand"] = time.perf_counter() - t
    n_reduced = red.size
    levels = np.bincount(red.level, minlength=int(red.level.max(initial=0)) + 1)
    del red, Y   # the blocks' modes and constraint modes: not held through the iteration
    t = time.perf_counter()
    if iterations and U.shape[1]:
        huge = isinstance(U, np.memmap)
        W = iterated_vectors(U, scratch)
        del U        # on disk now, or W itself
        sigma = shift
        solve = definite_factorization(factorizer(AUTO), sp.csc_array(K - sigma * M))
        filter_steps(M, W, solve, chebyshev_shifts(iterations, sigma, np.sqrt(bound * lam_c)),
                     say)
        del solve    # freed before the n x k modes are made: the peak is one of the two
        lam, U = ritz_pairs(K, M, W, max(lam_w, lam_0), scratch.empty if huge else np.empty)
        if isinstance(W, ColumnFile):
            W.close()
            scratch.discard(W)
        del W
    times["improve"] = time.perf_counter() - t
    found = int(np.searchsorted(lam, max(lam_w, lam_0), side="right"))   # lam ascending
    lam, U = lam[:found], U[:, :found]
    rigid = rigid_modes(lam, U, K, M)
    keep = np.flatnonzero(rigid | (lam <= lam_w))
    if keep.size < found:
        lam, U, rigid = lam[keep], U[:, keep], rigid[keep]
    lam = np.where(rigid, 0.0, lam)
    t = time.perf_counter()
    res = relative_residuals(K, M, lam, U)
    times["residual"] = time.perf_counter() - t
    return AMLSModes(lam, U, res, n_reduced, levels, n_blocks, iterations, times)
