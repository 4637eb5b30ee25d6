r"""One block of the AMLS reduction as a task: a pure function of picklable data, so that the
blocks run anywhere (in this process, or as Dask tasks on other workers,
:mod:`substruct.linalg.task_runner`) and give the same numbers bit for bit.  A subdomain's
task (:func:`reduce_leaf`) needs only its own rows; a separator's (:func:`reduce_separator`)
its own rows and its children's condensations, taken from their tasks' handles, so that on a
cluster they go from worker to worker, and it builds its dense local pencil itself
(:func:`separator_pencil`).  Each task returns what the reduced model keeps
(:class:`BlockModes`) apart from what its parent needs (:class:`Condensation`).

A block ``b`` with boundary :math:`B` (the separators above it that its subtree touches) is one
Craig-Bampton step on the local pencil :math:`(\hat K, \hat M)` of the coordinates
:math:`b \cup B` (:mod:`substruct.linalg.amls_reduce` for the whole method):

.. math::

    \Psi_b = -\hat K_{bb}^{-1} \hat K_{bB}, \qquad
    \hat K_{bb} \Phi_b = \hat M_{bb} \Phi_b \Lambda_b \ (\lambda \le \lambda_c), \qquad
    \tilde K_{BB} = \hat K_{BB} + \hat K_{Bb} \Psi_b, \\
    \tilde M_{BB} = \hat M_{BB} + \hat M_{Bb}\Psi_b + \Psi_b^T (\hat M_{bB} + \hat M_{bb}\Psi_b),
    \qquad G_b = \Phi_b^T (\hat M_{bB} + \hat M_{bb} \Psi_b),

and for every child ``c`` of a separator, whose subtree's modes couple to :math:`b \cup B` by
the mass :math:`G_c = [G_{cb}, G_{cB}]`: the reduced mass block :math:`G_{cb} \Phi_b` and the
coupling :math:`G_{cb} \Psi_b + G_{cB}` passed up.

A subdomain's task factorizes its sparse :math:`K_{bb}` itself (the factorization never leaves
the task); its constraint modes are applied again at the expansion by
:func:`expand_leaf`, which factorizes once more (a subdomain's factorization costs a fraction
of its eigen solve).  Peak memory of a task: its subdomain's factor, its modes and the dense
:math:`b \times B` constraint modes; a separator's: its dense local pencil.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Sequence

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from scipy.linalg import blas

from substruct.linalg.definite import definite_factorization
from substruct.linalg.factorize import Solve, factorizer
from substruct.linalg.lanczos import shift_invert_lanczos

__all__ = ["DENSE_LEAF", "LeafJob", "SeparatorJob", "Condensation", "BlockModes",
           "LeafExpansion", "block_modes", "separator_condensation", "separator_pencil",
           "reduce_leaf", "reduce_separator", "expand_leaf", "task_bytes"]

#: Subdomains up to this many coordinates get their fixed-interface modes by a dense ``eigh``;
#: larger ones by shift-invert Lanczos on their sparse factorization.
DENSE_LEAF = 2000


@dataclass
class LeafJob:
    """The data of a subdomain's task: its sparse ``K_bb``, ``M_bb`` and their coupling
    ``K_bB``, ``M_bB`` to its boundary, the cut-off eigenvalue, a factorization's registry
    name (:mod:`substruct.linalg.factorize`) and the shift of a block with no boundary
    (:func:`block_modes`: negative, so that a free part's pencil is definite)."""

    K: sp.csr_array
    M: sp.csr_array
    K_bB: sp.csr_array
    M_bB: sp.csr_array
    lam_cut: float
    factorization: str = "auto"
    free_shift: float = 0.0


@dataclass
class SeparatorJob:
    r"""The data of a separator's task, without its children's condensations (which come
    from their own tasks): the separator's rows of ``K``, ``M`` on :math:`I = b \cup B`
    (sparse, ``b`` first), the number ``ns`` of its own coordinates, each child's boundary as
    positions in :math:`I`, the cut-off eigenvalue and the shift of a block with no boundary
    (the root separator)."""

    K_rows: sp.csr_array
    M_rows: sp.csr_array
    ns: int
    positions: list[np.ndarray]
    lam_cut: float
    free_shift: float = 0.0


@dataclass
class Condensation:
    """What a block passes up to its parent.

    Attributes:
        CK, CM: the static condensation onto its boundary (symmetric, ``|B| x |B|``).
        G: the mass coupling of its subtree's modes onto its boundary: its own modes first,
            then each child's subtree in order.
    """

    CK: np.ndarray
    CM: np.ndarray
    G: np.ndarray


@dataclass
class BlockModes:
    """What a block keeps for the reduced model.

    Attributes:
        lam, Phi: its fixed-interface eigenpairs up to the cut-off, ``M``-normalized.
        Psi: a separator's constraint modes (``ns x |B|``); ``None`` for a subdomain.
        cross: per child, the reduced mass block of the child's subtree's modes against this
            block's modes.
        seconds: the task's time.
    """

    lam: np.ndarray
    Phi: np.ndarray
    Psi: np.ndarray | None
    cross: list[np.ndarray]
    seconds: float = 0.0


def task_bytes(own: int, boundary: int, children: Sequence[int], leaf: bool) -> int:
    r"""The bytes a block's task holds at its peak, before LAPACK's workspaces and a
    subdomain's sparse factor: for a separator with :math:`n_s` own coordinates, boundary
    :math:`n_B` and children's boundaries :math:`n_{B_c}`, its dense local pencil, the
    children's condensations, its own condensation and constraint-mode products,

    .. math::  8\,\bigl(2 (n_s + n_B)^2 + 2 \textstyle\sum_c n_{B_c}^2 + 2 n_B^2
               + 4 n_s n_B\bigr);

    for a subdomain its dense coupling, constraint modes and their mass product and its
    condensation, :math:`8 (3 n_s n_B + 2 n_B^2)`."""
    if leaf:
        return 8 * (3 * own * boundary + 2 * boundary ** 2)
    return 8 * (2 * (own + boundary) ** 2 + 2 * sum(c * c for c in children)
                + 2 * boundary ** 2 + 4 * own * boundary)


def block_modes(Kb: np.ndarray | sp.sparray, Mb: np.ndarray | sp.sparray, lam_cut: float,
                solve: Solve | None = None, shift: float = 0.0
                ) -> tuple[np.ndarray, np.ndarray]:
    r"""The eigenpairs :math:`K_b \phi = \lambda M_b \phi` with :math:`\lambda \le` ``lam_cut``,
    ``M``-normalized, for :math:`K_b - \sigma M_b` positive definite (:math:`\sigma` =
    ``shift``); :math:`M_b` may be singular (massless rotations of lumped-mass shells and
    beams, a mass with an offset): its infinite eigenvalues are never kept.

    Dense blocks are solved in the inverse form, positive definite on the right whatever the
    mass,

    .. math::  M_b \phi = \mu\, (K_b - \sigma M_b)\, \phi, \qquad
               \lambda = \sigma + 1/\mu, \qquad \phi \leftarrow \phi / \sqrt{\mu},

    by ``eigh`` (subset by value, :math:`\mu \ge 1/(\lambda_c - \sigma)`: the largest
    :math:`\mu` are the lowest :math:`\lambda`, to a relative accuracy that does not depend on
    how ill-conditioned :math:`M_b` is).  Large sparse blocks with a factorization ``solve``
    of :math:`K_b - \sigma M_b`: shift-invert Lanczos (ARPACK's mode 3, valid for a singular
    :math:`M_b`), doubling the number of pairs until one exceeds the cut-off (or the block is
    small enough for the dense form)."""
    n = Kb.shape[0]
    if n == 0:
        return np.zeros(0), np.zeros((0, 0))
    if sp.issparse(Kb) and n > DENSE_LEAF and solve is not None:
        k = min(32, n // 4)
        v0 = np.asarray(np.random.default_rng(0).standard_normal(n))
        while k < n // 4:
            lam, V = shift_invert_lanczos(sp.csr_array(Kb), sp.csr_array(Mb), k, shift, solve,
                                          v0=v0)
            if lam.max() > lam_cut:
                order = np.argsort(lam)
                keep = order[lam[order] <= lam_cut]
                return lam[keep], V[:, keep]
            k *= 2
    Kd = sp.csr_array(Kb).toarray() if sp.issparse(Kb) else np.asarray(Kb)
    Md = sp.csr_array(Mb).toarray() if sp.issparse(Mb) else np.asarray(Mb)
    if shift:
        Kd = Kd - shift * Md
    mu, V = sla.eigh(Md, Kd, subset_by_value=(1.0 / (lam_cut - shift), np.inf), driver="gvx")
    mu, V = mu[::-1], V[:, ::-1]
    return shift + 1.0 / mu, V / np.sqrt(mu)


def _sym(A: np.ndarray) -> np.ndarray:
    return (A + A.T) / 2


#: Rows of a symmetric matrix's triangle mirrored at once.
MIRROR_ROWS = 512


def _mirror_upper(C: np.ndarray) -> np.ndarray:
    """``C`` made symmetric from its upper triangle, in place, by blocks of rows."""
    n = C.shape[0]
    for i in range(0, n, MIRROR_ROWS):
        e = min(i + MIRROR_ROWS, n)
        D = C[i:e, i:e]
        D[:] = np.triu(D) + np.triu(D, 1).T
        C[e:, i:e] = C[i:e, e:].T
    return C


def separator_condensation(Kl: np.ndarray, Ml: np.ndarray, ns: int
                           ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    r"""The constraint modes and static condensation of a separator's dense local pencil
    (its ``ns`` own coordinates first, then its boundary :math:`B`), by the Cholesky factor
    :math:`\hat K_{bb} = L L^T` and symmetric rank updates:

    .. math::  X = L^{-1} \hat K_{bB}, \quad \Psi_b = -L^{-T} X, \quad
               \tilde K_{BB} = \hat K_{BB} - X^T X, \\
               T = \hat M_{bB} + \tfrac12 \hat M_{bb} \Psi_b, \quad
               \tilde M_{BB} = \hat M_{BB} + \Psi_b^T T + T^T \Psi_b,

    (the last is the module's :math:`\tilde M_{BB}`: :math:`\Psi^T T + T^T \Psi` holds both
    cross terms and :math:`\Psi^T \hat M_{bb} \Psi`), the triangles by BLAS ``syrk`` and
    ``syr2k``, half the products of the general form, symmetric by construction.

    Returns:
        ``(Psi, CK, CM, MsBt)`` with ``MsBt`` :math:`= \hat M_{bB} + \hat M_{bb} \Psi_b`.
    """
    L = sla.cholesky(Kl[:ns, :ns], lower=True)
    X = sla.solve_triangular(L, Kl[:ns, ns:], lower=True)
    # the operands' transposes are Fortran-ordered views, passed to BLAS without a copy; the
    # output starts as a row-by-row copy of the boundary block, whose transpose (the same
    # symmetric matrix) is Fortran-ordered too
    CK = blas.dsyrk(-1.0, X.T, beta=1.0, c=np.array(Kl[ns:, ns:]).T, overwrite_c=1)
    Psi = -sla.solve_triangular(L, X, lower=True, trans="T")
    del X
    MP = Ml[:ns, :ns] @ Psi
    T = Ml[:ns, ns:] + 0.5 * MP
    CM = blas.dsyr2k(1.0, Psi.T, T.T, beta=1.0, c=np.array(Ml[ns:, ns:]).T, overwrite_c=1)
    T += 0.5 * MP
    return Psi, _mirror_upper(np.asarray(CK)), _mirror_upper(np.asarray(CM)), T


def reduce_leaf(job: LeafJob) -> tuple[BlockModes, Condensation]:
    """The reduction of a subdomain (module docstring); a pure function of ``job``."""
    t = time.perf_counter()
    Kdd, Mdd = job.K, job.M
    nd, nb = Kdd.shape[0], job.K_bB.shape[1]
    # with no boundary (a whole disconnected part, perhaps free) no constraint modes: the
    # eigenproblem is shifted instead
    shift = 0.0 if nb else job.free_shift
    solve = definite_factorization(factorizer(job.factorization),
                                   sp.csc_array(Kdd - shift * Mdd if shift else Kdd))
    Psi = -np.asarray(solve(job.K_bB.toarray())).reshape(nd, nb)
    lam, Phi = block_modes(Kdd, Mdd, job.lam_cut, solve, shift)
    MdBt = job.M_bB.toarray() + Mdd @ Psi
    CK = job.K_bB.T @ Psi
    CM = job.M_bB.T @ Psi + Psi.T @ MdBt
    up = Condensation(_sym(CK), _sym(CM), Phi.T @ MdBt)
    return BlockModes(lam, Phi, None, [], time.perf_counter() - t), up


def separator_pencil(job: SeparatorJob, children: Sequence[Condensation]
                     ) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
    r"""A separator's dense local pencil :math:`(\hat K, \hat M)` on :math:`b \cup B`: its
    own rows (mirrored onto its columns) plus every child's condensation :math:`\tilde K_{BB}`,
    :math:`\tilde M_{BB}` added at the child's boundary; and each child's mass coupling
    :math:`G_c` scattered onto the columns of :math:`b \cup B`."""
    ns = job.ns
    Ks, Ms = job.K_rows.toarray(), job.M_rows.toarray()
    nI = Ks.shape[1]
    Kl = np.zeros((nI, nI))
    Ml = np.zeros((nI, nI))
    Kl[:ns], Ml[:ns] = Ks, Ms
    Kl[ns:, :ns], Ml[ns:, :ns] = Ks[:, ns:].T, Ms[:, ns:].T
    Gfs = []
    for p, c in zip(job.positions, children):
        for r, row in enumerate(p):      # row by row: 16x faster than Kl[np.ix_(p, p)] +=
            Kl[row, p] += c.CK[r]
            Ml[row, p] += c.CM[r]
        Gf = np.zeros((c.G.shape[0], nI))
        Gf[:, p] = c.G
        Gfs.append(Gf)
    return Kl, Ml, Gfs


def reduce_separator(job: SeparatorJob, *children: Condensation
                     ) -> tuple[BlockModes, Condensation]:
    """The reduction of a separator (module docstring), given its children's condensations in
    the order of ``job.positions``; a pure function of its arguments."""
    t = time.perf_counter()
    Kl, Ml, Gfs = separator_pencil(job, children)
    ns = job.ns
    nb = Kl.shape[0] - ns
    lam, Phi = block_modes(Kl[:ns, :ns], Ml[:ns, :ns], job.lam_cut,
                           shift=0.0 if nb else job.free_shift)
    if nb and ns:
        Psi, CK, CM, MsBt = separator_condensation(Kl, Ml, ns)
    else:
        Psi, MsBt = np.zeros((ns, nb)), Ml[:ns, ns:]
        CK, CM = Kl[ns:, ns:].copy(), Ml[ns:, ns:].copy()
    del Kl, Ml
    G = [Phi.T @ MsBt]
    cross = []
    for Gf in Gfs:
        cross.append(Gf[:, :ns] @ Phi)
        G.append(Gf[:, :ns] @ Psi + Gf[:, ns:])
    up = Condensation(CK, CM, np.vstack(G))
    return BlockModes(lam, Phi, Psi, cross, time.perf_counter() - t), up


@dataclass
class LeafExpansion:
    r"""A subdomain's part of the expansion :math:`x_b = \Phi_b y_b - K_{bb}^{-1} K_{bB} x_B`."""

    K: sp.csr_array
    K_bB: sp.csr_array
    Phi: np.ndarray
    y: np.ndarray
    xB: np.ndarray
    factorization: str = "auto"


def expand_leaf(job: LeafExpansion) -> np.ndarray:
    r""":math:`x_b = \Phi_b y_b - K_{bb}^{-1} (K_{bB} x_B)` (the subdomain factorized again)."""
    xb = job.Phi @ job.y
    if job.xB.shape[0]:
        solve = factorizer(job.factorization)(sp.csc_array(job.K))
        xb -= np.asarray(solve(job.K_bB @ job.xB)).reshape(xb.shape)
    return xb
