r"""The reduction of automated multilevel substructuring (AMLS; Bennighof and Lehoucq, SIAM J.
Sci. Comput. 25 (2004) 2084-2106), bottom-up over a nested-dissection tree
(:mod:`substruct.linalg.amls_tree`).

Every block ``b`` of the tree (a subdomain or a separator) sees its *boundary* :math:`B_b`: the
coordinates of its ancestors' separators coupled to its subtree.  In post-order, each block is
one Craig-Bampton step on the coordinates :math:`I = b \cup B_b`, where the local stiffness and
mass are the block's own rows of ``K``, ``M`` plus what its children passed up (their static
condensation onto :math:`B_c \subset I`):

.. math::

    x_b = \Phi_b\, q_b + \Psi_b\, x_B, \qquad \Psi_b = -\hat K_{bb}^{-1} \hat K_{bB},
    \qquad \hat K_{bb} \Phi_b = \hat M_{bb} \Phi_b \Lambda_b,
    \quad \Phi_b^T \hat M_{bb} \Phi_b = I,

with :math:`\Phi_b` the fixed-interface modes whose eigenvalue is at most the cut-off
:math:`\lambda_c`.  What the block passes up to its parent is the exact static condensation

.. math::

    \tilde K_{BB} = \hat K_{BB} + \hat K_{Bb} \Psi_b, \qquad
    \tilde M_{BB} = \hat M_{BB} + \hat M_{Bb}\Psi_b + \Psi_b^T (\hat M_{bB} + \hat M_{bb}\Psi_b),

and the mass coupling of every mode of its subtree onto :math:`B_b`; a child's coupling
:math:`G_c = [G_{cb}, G_{cB}]` becomes the reduced mass block :math:`G_{cb}\Phi_b` (modes of
the child's subtree against the block's modes) and :math:`G_{cb}\Psi_b + G_{cB}` on the new
boundary.  Because the static transformations are exact, the reduced pencil is the exact
Rayleigh-Ritz projection of ``(K, M)`` on the span of the columns :math:`Z` it stands for:

.. math::  K_r = Z^T K Z = \operatorname{diag}(\Lambda_b), \qquad M_r = Z^T M Z,

sparse in blocks (modes of two blocks couple only if one is an ancestor of the other).  Keeping
every mode of every block, :math:`Z` is invertible and the reduced eigenvalues are the exact
ones; truncating, they are upper bounds that decrease as :math:`\lambda_c` grows (the subspaces
are nested).  Subdomains (sparse) use a factorization from :mod:`substruct.linalg.factorize`
for their constraint modes; separators (dense after their children's condensation) a dense
Cholesky.

The blocks of one tree level are independent once the level below is reduced: each is one task
(:func:`substruct.linalg.amls_block.reduce_block`) of a ``map`` given by the caller (a Dask
client's map runs them on its workers), the levels bottom-up.  In this process (no ``map``)
the blocks run one at a time in post-order instead, so that only the condensations still
waiting for their parent are held (at most two per level), not a whole level's.  The
tasks are pure functions of their data and the numbering of the reduced coordinates is made
here afterwards, so the reduced model does not depend on where the tasks ran.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import scipy.sparse as sp

from substruct.linalg.amls_block import (
    BlockJob,
    BlockResult,
    LeafExpansion,
    TaskMap,
    expand_leaf,
    reduce_block,
    serial_map,
)
from substruct.linalg.amls_tree import DissectionNode

__all__ = ["ReducedModel", "amls_reduce"]


@dataclass
class _Block:
    """What the expansion to physical coordinates needs of one block."""

    dofs: np.ndarray
    boundary: np.ndarray
    modes: np.ndarray          # indices of the block's modes among the reduced coordinates
    Phi: np.ndarray
    Psi: np.ndarray | None = None          # separators: dense constraint modes
    K: sp.csr_array | None = None          # subdomains: K_bb and K_bB, factorized again
    K_dB: sp.csr_array | None = None


@dataclass
class ReducedModel:
    r"""The AMLS reduced pencil :math:`(K_r, M_r) = (\operatorname{diag}\Lambda, Z^T M Z)`.

    Attributes:
        lam: the diagonal of :math:`K_r` (the blocks' fixed-interface eigenvalues).
        M: :math:`M_r`, sparse symmetric with identity diagonal blocks.
        level: the tree level (0: root) of each reduced coordinate.
        n: number of physical coordinates.
        blocks: the data of :meth:`expand`, root first.
        factorization: the registry name the subdomains are factorized with.
    """

    lam: np.ndarray
    M: sp.csr_array
    level: np.ndarray
    n: int
    blocks: list[_Block] = field(repr=False)
    factorization: str = "auto"

    @property
    def size(self) -> int:
        """Number of reduced coordinates."""
        return int(self.lam.size)

    def expand(self, Y: np.ndarray, map: TaskMap | None = None) -> np.ndarray:
        r"""Physical coordinates :math:`X = Z Y` of reduced ones (``size x k``), top-down:
        :math:`x_b = \Phi_b y_b + \Psi_b x_B` for the separators, root first, then every
        subdomain as one task of ``map`` (:func:`substruct.linalg.amls_block.expand_leaf`)."""
        Y = np.asarray(Y, dtype=float).reshape(self.size, -1)
        X = np.zeros((self.n, Y.shape[1]))
        leaves = []
        for b in self.blocks:
            if b.Psi is None:
                leaves.append(b)
                continue
            xb = b.Phi @ Y[b.modes]
            if b.boundary.size:
                xb += b.Psi @ X[b.boundary]
            X[b.dofs] = xb
        jobs = []
        for b in leaves:
            assert b.K is not None and b.K_dB is not None
            jobs.append(LeafExpansion(b.K, b.K_dB, b.Phi, Y[b.modes], X[b.boundary],
                                      self.factorization))
        for b, xb in zip(leaves, (map or serial_map)(expand_leaf, jobs)):
            X[b.dofs] = xb
        return X


def _positions(I: np.ndarray, sub: np.ndarray) -> np.ndarray:
    """Where the entries of ``sub`` sit in ``I`` (every one is there)."""
    order = np.argsort(I)
    return order[np.searchsorted(I, sub, sorter=order)]


def _boundaries(P: sp.csr_array, order: list[DissectionNode]) -> list[np.ndarray]:
    """Each block's boundary (post-order): the coordinates of later blocks (its ancestors'
    separators) coupled to its own rows or passed up by its children."""
    n = P.shape[0]
    pos = np.empty(n, dtype=np.int64)
    for i, b in enumerate(order):
        pos[b.dofs] = i
    index = {id(b): i for i, b in enumerate(order)}
    out: list[np.ndarray] = []
    for i, b in enumerate(order):
        own = np.unique(P[b.dofs].indices) if b.dofs.size else np.zeros(0, dtype=np.int64)
        B = own[pos[own] > i]
        for c in b.children:
            B = np.union1d(B, out[index[id(c)]])
        out.append(B[pos[B] > i])
    return out


def _job(K: sp.csr_array, M: sp.csr_array, b: DissectionNode, B: np.ndarray, lam_cut: float,
         factorization: str, below: list[tuple[np.ndarray, BlockResult]]) -> BlockJob:
    r"""The task of block ``b``: a subdomain's sparse rows, or a separator's dense local pencil
    on :math:`b \cup B` with its children's condensations added (``below``: each child's
    boundary and result)."""
    d = b.dofs
    if b.is_leaf:
        Kd, Md = K[d], M[d]
        return BlockJob(True, Kd[:, d], Md[:, d], d.size, lam_cut, factorization,
                        K_bB=sp.csr_array(Kd[:, B]), M_bB=sp.csr_array(Md[:, B]))
    ns = d.size
    I = np.concatenate([d, B])
    Kl = np.zeros((I.size, I.size))
    Ml = np.zeros((I.size, I.size))
    Ks, Ms = K[d][:, I].toarray(), M[d][:, I].toarray()
    Kl[:ns], Ml[:ns] = Ks, Ms
    Kl[ns:, :ns], Ml[ns:, :ns] = Ks[:, ns:].T, Ms[:, ns:].T
    children = []
    for Bc, rc in below:
        p = _positions(I, Bc)
        for r, row in enumerate(p):      # row by row: 16x faster than Kl[np.ix_(p, p)] +=
            Kl[row, p] += rc.CK[r]
            Ml[row, p] += rc.CM[r]
        Gf = np.zeros((rc.G.shape[0], I.size))
        Gf[:, p] = rc.G
        children.append(Gf)
    return BlockJob(False, Kl, Ml, ns, lam_cut, factorization, children=children)


def amls_reduce(K: sp.sparray | sp.spmatrix, M: sp.sparray | sp.spmatrix, root: DissectionNode,
                lam_cut: float, factorization: str = "auto",
                progress: Callable[[str], None] | None = None,
                map: TaskMap | None = None) -> ReducedModel:
    r"""The AMLS reduction of the symmetric pencil ``(K, M)`` over the tree ``root``, keeping in
    every block the fixed-interface modes with eigenvalue at most ``lam_cut`` (see the module
    docstring).  ``K`` restricted to every subdomain must be positive definite (true when the
    subdomains are held by separators, or ``K`` is); the root separator may be singular
    (a free body's rigid modes).

    The blocks of each level, deepest first, are the tasks of one call of ``map``
    (:data:`~substruct.linalg.amls_block.TaskMap`); without it they run in this process, one
    at a time in post-order (the same numbers); ``progress`` receives one line as each level
    is done."""
    K = sp.csr_array(K, dtype=float)
    M = sp.csr_array(M, dtype=float)
    run = map or serial_map
    n = K.shape[0]
    order = root.postorder()
    bounds = _boundaries(sp.csr_array(abs(K) + abs(M)), order)
    index = {id(b): i for i, b in enumerate(order)}
    depth = max(b.level for b in order)
    results: list[BlockResult | None] = [None] * len(order)

    def job(i: int) -> BlockJob:
        below = []
        for c in order[i].children:
            j = index[id(c)]
            rc = results[j]
            assert rc is not None
            below.append((bounds[j], rc))
        return _job(K, M, order[i], bounds[i], lam_cut, factorization, below)

    def report(lev: int, here: list[int], seconds: float) -> None:
        if progress is not None:
            kept = sum(int(r.lam.size) for r in (results[i] for i in here) if r is not None)
            coords = sum(int(order[i].dofs.size) for i in here)
            progress(f"AMLS level {lev} ({depth - lev + 1} of {depth + 1}): {len(here)} "
                     f"block(s) of {coords} coordinates, {kept} modes kept ({seconds:.1f} s)")

    levels = {lev: [i for i, b in enumerate(order) if b.level == lev]
              for lev in range(depth, -1, -1)}
    if map is None:
        # in this process: one block at a time in post-order, each child's condensation
        # freed once its parent is reduced, so at most two per level are alive (level by
        # level, a whole level's would be)
        left = {lev: len(here) for lev, here in levels.items()}
        spent = dict.fromkeys(levels, 0.0)
        for i, b in enumerate(order):
            t = time.perf_counter()
            results[i] = reduce_block(job(i))
            _release(results, b, index)
            spent[b.level] += time.perf_counter() - t
            left[b.level] -= 1
            if not left[b.level]:
                report(b.level, levels[b.level], spent[b.level])
    else:
        for lev, here in levels.items():
            t = time.perf_counter()
            out = list(run(reduce_block, [job(i) for i in here]))
            for i, r in zip(here, out):
                results[i] = r
                _release(results, order[i], index)
            report(lev, here, time.perf_counter() - t)
    return _assemble(K, order, bounds, results, n, factorization)


def _release(results: list[BlockResult | None], b: DissectionNode, index: dict[int, int]
             ) -> None:
    """Once block ``b`` is reduced, its children's condensation and boundary coupling are no
    longer needed (their modes, constraint modes and cross blocks are)."""
    for c in b.children:
        rc = results[index[id(c)]]
        assert rc is not None
        rc.G = np.zeros((0, rc.G.shape[1]))   # new arrays: a view would keep the data
        rc.CK = np.zeros((0, 0))
        rc.CM = np.zeros((0, 0))


def _assemble(K: sp.csr_array, order: list[DissectionNode], bounds: list[np.ndarray],
              results: list[BlockResult | None], n: int, factorization: str) -> ReducedModel:
    """The reduced pencil: the reduced coordinates numbered block by block in post-order,
    :math:`M_r` from the identity blocks and every separator's cross blocks."""
    index = {id(b): i for i, b in enumerate(order)}
    subtree: list[np.ndarray] = []   # the reduced coordinates of each block's subtree
    blocks: list[_Block] = []
    rows: list[np.ndarray] = []
    cols: list[np.ndarray] = []
    vals: list[np.ndarray] = []
    offset = 0
    for i, b in enumerate(order):
        r = results[i]
        assert r is not None
        mine = np.arange(offset, offset + r.lam.size)
        offset += r.lam.size
        Qs = [subtree[index[id(c)]] for c in b.children]
        for Qc, cross in zip(Qs, r.cross):
            rr, cc = np.meshgrid(Qc, mine, indexing="ij")
            rows += [rr.ravel(), cc.ravel()]
            cols += [cc.ravel(), rr.ravel()]
            vals += [cross.ravel(), cross.ravel()]
        subtree.append(np.concatenate([mine] + Qs))
        d = b.dofs
        if b.is_leaf:
            Kd = K[d]
            blocks.append(_Block(d, bounds[i], mine, r.Phi, K=sp.csr_array(Kd[:, d]),
                                 K_dB=sp.csr_array(Kd[:, bounds[i]])))
        else:
            blocks.append(_Block(d, bounds[i], mine, r.Phi, Psi=r.Psi))
    lam_all = np.concatenate([r.lam for r in results if r is not None])
    level = np.concatenate([np.full(r.lam.size, b.level) for b, r in zip(order, results)
                            if r is not None])
    N = lam_all.size
    diag = np.arange(N)
    Mr = sp.csr_array((np.concatenate(vals + [np.ones(N)]),
                       (np.concatenate(rows + [diag]), np.concatenate(cols + [diag]))),
                      shape=(N, N))
    return ReducedModel(lam_all, Mr, level, n, blocks[::-1], factorization)
