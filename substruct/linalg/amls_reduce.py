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

Every block is one task (:mod:`substruct.linalg.amls_block`) of a
:class:`~substruct.linalg.task_runner.TaskRunner`, submitted in post-order: a separator's task
takes its children's condensations as handles of their tasks, so that on a Dask cluster they
pass from worker to worker (a block starts as soon as its children are done, not level by
level) and only what the reduced model keeps comes back here, as each block is done.  In this
process each task runs at once, depth first, so that only the condensations still waiting for
their parent are held (at most two per level).  The tasks are pure functions of their data and
the numbering of the reduced coordinates is made here afterwards, so the reduced model does
not depend on where the tasks ran.  The separators' constraint modes, the largest part of
what is kept (:math:`\sum n_s n_B` entries) and used once by the expansion, are written to
disk as they arrive when large (:data:`SPILL_BYTES`) and read back by the expansion; in this
process so is a large condensation, until its parent has read it.  On a cluster whose workers
have a memory limit, a block whose task would hold more than :data:`LOCAL_FRACTION` of it
(:func:`~substruct.linalg.amls_block.task_bytes`: the top separators of a large compact
solid) is reduced in this process instead, with every block above it (:func:`reduced_here`),
after every task is done: a worker would be stopped by its limit where this process, with the
machine's memory, is not, and on one machine the two would not fit side by side.
"""

from __future__ import annotations

import operator
import time
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np
import scipy.sparse as sp

from substruct.linalg.amls_block import (
    BlockModes,
    Condensation,
    LeafExpansion,
    LeafJob,
    SeparatorJob,
    expand_leaf,
    reduce_leaf,
    reduce_separator,
    task_bytes,
)
from substruct.linalg.amls_tree import DissectionNode
from substruct.linalg.scratch_arrays import ScratchArrays, read_whole
from substruct.linalg.task_runner import IN_PROCESS, TaskRunner

__all__ = ["ReducedModel", "SPILL_BYTES", "LOCAL_FRACTION", "amls_reduce", "reduced_here"]

#: A separator's constraint modes (and, in this process, a condensation's stiffness or mass)
#: from this many bytes up are kept on disk until the expansion (its parent) reads them (:class:`~substruct.linalg.scratch_arrays.ScratchArrays`): they sum
#: to 0.56 GB at 98,400 coordinates of the solid box of docs/amls.md, 2.5 GB at 297,714 and
#: about 13 GB at 10^6 (``sum ns nb``, growing as ``n^1.36``), more than the rest of the
#: reduced model; the largest at 98,400 is 47 MB, so that a model of that size keeps every
#: one in memory.
SPILL_BYTES = 64 * 2**20

#: On a cluster, a block whose task would hold more than this fraction of a worker's memory
#: limit is reduced in this process (with every block above it), as it would be without the
#: cluster: a LocalCluster's worker may use the machine's memory over the number of workers,
#: and the largest separators of a 10^6-coordinate solid hold about 14 GB (docs/amls.md).
LOCAL_FRACTION = 0.5

#: The subdomains' expansions go to the tasks in batches whose inputs and results (their
#: boundary's and their own rows of the expanded vectors) are about this many bytes: all at
#: once they were 3.4 GB for the 1,012 vectors of a 297,714-coordinate solid, beside the 2.4 GB
#: result.
EXPAND_BATCH = 256 * 2**20


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
        scratch: where the large constraint modes are kept on disk (:data:`SPILL_BYTES`),
            removed with the model.
        blocks_here: how many blocks were too large for a worker of the cluster and were
            reduced in this process (:func:`reduced_here`).
    """

    lam: np.ndarray
    M: sp.csr_array
    level: np.ndarray
    n: int
    blocks: list[_Block] = field(repr=False)
    factorization: str = "auto"
    scratch: ScratchArrays | None = field(default=None, repr=False)
    blocks_here: int = 0

    @property
    def size(self) -> int:
        """Number of reduced coordinates."""
        return int(self.lam.size)

    def expand(self, Y: np.ndarray, tasks: TaskRunner | None = None,
               out: np.ndarray | None = None) -> np.ndarray:
        r"""Physical coordinates :math:`X = Z Y` of reduced ones (``size x k``), top-down:
        :math:`x_b = \Phi_b y_b + \Psi_b x_B` for the separators, root first, then every
        subdomain as one task of a map of ``tasks``
        (:func:`substruct.linalg.amls_block.expand_leaf`), in batches of about
        :data:`EXPAND_BATCH` bytes; written into ``out`` if given (``n x k``, zero)."""
        Y = np.asarray(Y, dtype=float).reshape(self.size, -1)
        X = np.zeros((self.n, Y.shape[1])) if out is None else out
        leaves = []
        for b in self.blocks:
            if b.Psi is None:
                leaves.append(b)
                continue
            xb = b.Phi @ Y[b.modes]
            if b.boundary.size:   # a constraint mode kept on disk is read, not mapped
                xb += read_whole(b.Psi) @ X[b.boundary]
            X[b.dofs] = xb
        start = 0
        while start < len(leaves):   # batches: the inputs and results of all at once are
            stop, size = start, 0    # about the n x k result again, and more
            while stop < len(leaves) and (stop == start or size < EXPAND_BATCH):
                b = leaves[stop]
                size += 8 * (b.boundary.size + b.dofs.size) * Y.shape[1]
                stop += 1
            jobs = []
            for b in leaves[start:stop]:
                assert b.K is not None and b.K_dB is not None
                jobs.append(LeafExpansion(b.K, b.K_dB, b.Phi, Y[b.modes], X[b.boundary],
                                          self.factorization))
            for b, xb in zip(leaves[start:stop], (tasks or IN_PROCESS).map(expand_leaf, jobs)):
                X[b.dofs] = xb
            start = stop
        return X


def _boundaries(P: sp.csr_array, order: list[DissectionNode]) -> list[np.ndarray]:
    """Each block's boundary (post-order): the coordinates of later blocks (its ancestors'
    separators) coupled to its own rows or passed up by its children.  A child's boundary
    outside its parent's rows and boundary (an entry of ``P`` coupling two blocks neither of
    which is an ancestor of the other: a tree not made from the pattern ``P``) is refused."""
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
        if np.any(pos[B] < i):
            raise ValueError("the dissection tree does not separate the pencil: make it from "
                             "the pattern of both matrices (dissection_tree(K, ..., M=M))")
        out.append(B[pos[B] > i])
    return out


def _leaf_job(K: sp.csr_array, M: sp.csr_array, d: np.ndarray, B: np.ndarray, lam_cut: float,
              factorization: str, free_shift: float) -> LeafJob:
    """The task of the subdomain ``d`` with boundary ``B``: its sparse rows."""
    Kd, Md = K[d], M[d]
    return LeafJob(sp.csr_array(Kd[:, d]), sp.csr_array(Md[:, d]), sp.csr_array(Kd[:, B]),
                   sp.csr_array(Md[:, B]), lam_cut, factorization, free_shift)


def _separator_job(K: sp.csr_array, M: sp.csr_array, d: np.ndarray, B: np.ndarray,
                   lam_cut: float, child_bounds: list[np.ndarray], free_shift: float
                   ) -> SeparatorJob:
    r"""The task of the separator ``d`` with boundary ``B``: its rows on :math:`d \cup B` and
    where each child's boundary sits there."""
    I = np.concatenate([d, B])
    order = np.argsort(I)
    positions = [order[np.searchsorted(I, Bc, sorter=order)] for Bc in child_bounds]
    return SeparatorJob(sp.csr_array(K[d][:, I]), sp.csr_array(M[d][:, I]), d.size, positions,
                        lam_cut, free_shift)


def amls_reduce(K: sp.sparray | sp.spmatrix, M: sp.sparray | sp.spmatrix, root: DissectionNode,
                lam_cut: float, factorization: str = "auto",
                progress: Callable[[str], None] | None = None,
                tasks: TaskRunner | None = None, free_shift: float = 0.0) -> ReducedModel:
    r"""The AMLS reduction of the symmetric pencil ``(K, M)`` over the tree ``root``, keeping in
    every block the fixed-interface modes with eigenvalue at most ``lam_cut`` (see the module
    docstring).  ``K`` restricted to every block with a boundary must be positive definite
    (true when the subdomains are held by separators, or ``K`` is); a block with none (the
    root separator, a subdomain that is a whole disconnected part) solves its eigenproblem
    shifted by ``free_shift`` (negative, :func:`~substruct.linalg.amls_block.block_modes`),
    so that a free body's rigid modes and massless coordinates (a singular ``M``) are both
    allowed.

    Every block is a task of ``tasks`` (default: in this process, the same numbers);
    ``progress`` receives one line as each level is done, with the seconds its tasks took."""
    K = sp.csr_array(K, dtype=float)
    M = sp.csr_array(M, dtype=float)
    run = tasks or IN_PROCESS
    n = K.shape[0]
    order = root.postorder()
    bounds = _boundaries(sp.csr_array(abs(K) + abs(M)), order)
    index = {id(b): i for i, b in enumerate(order)}
    depth = max(b.level for b in order)
    levels = {lev: [i for i, b in enumerate(order) if b.level == lev]
              for lev in range(depth, -1, -1)}
    left = {lev: len(here) for lev, here in levels.items()}
    results: list[BlockModes | None] = [None] * len(order)
    scratch = ScratchArrays("substruct-amls-")
    up: dict[int, Any] = {}      # the condensation's handle of each block not yet used
    kept: dict[int, Any] = {}    # the kept part's handle of each block not yet brought here
    limit = run.task_memory()
    here = reduced_here(order, bounds, limit)
    if any(here) and progress is not None:
        progress(f"AMLS: {sum(here)} of {len(order)} blocks would hold more than "
                 f"{LOCAL_FRACTION:g} of a worker's memory ({(limit or 0) / 2**30:.1f} GB): "
                 f"reduced in this process")

    def keep(i: int, value: BlockModes) -> None:
        if value.Psi is not None and value.Psi.nbytes >= SPILL_BYTES:
            value.Psi = scratch.keep(value.Psi)
        results[i] = value
        lev = order[i].level
        left[lev] -= 1
        if not left[lev] and progress is not None:
            mine = levels[lev]
            modes = sum(int(r.lam.size) for r in (results[j] for j in mine) if r is not None)
            coords = sum(int(order[j].dofs.size) for j in mine)
            spent = sum(r.seconds for r in (results[j] for j in mine) if r is not None)
            progress(f"AMLS level {lev} ({depth - lev + 1} of {depth + 1}): {len(mine)} "
                     f"block(s) of {coords} coordinates, {modes} modes kept "
                     f"({spent:.1f} s)")

    parent = {index[id(c)]: i for i, b in enumerate(order) for c in b.children}

    def collect(positions: list[int]) -> None:
        for k, value in run.completed([kept[i] for i in positions]):
            i = positions[k]
            keep(i, value)
            del kept[i]
            if i in parent and here[parent[i]] and not here[i]:
                # its parent is reduced here: the condensation brought here at once, onto
                # disk when large, so that the workers do not hold it until then
                up[i] = _on_disk_if_large(next(iter(run.completed([up[i]])))[1], scratch)

    def reduce(i: int, b: DissectionNode, where: TaskRunner) -> None:
        if b.is_leaf:
            both = where.submit(reduce_leaf, _leaf_job(K, M, b.dofs, bounds[i], lam_cut,
                                                       factorization, free_shift))
        else:
            kids = [index[id(c)] for c in b.children]
            job = _separator_job(K, M, b.dofs, bounds[i], lam_cut, [bounds[j] for j in kids],
                                 free_shift)
            inputs = [up.pop(j) for j in kids]  # here: values (collect brought the tasks')
            both = where.submit(reduce_separator, job, *inputs)
            for c in inputs:            # in this process: read, no longer needed
                if isinstance(c, Condensation):
                    scratch.discard(c.CK)
                    scratch.discard(c.CM)
            del inputs
        if where is run:
            kept[i] = run.submit(operator.getitem, both, 0)
        else:
            keep(i, both[0])
        if b is not root:
            up[i] = _on_disk_if_large(where.submit(operator.getitem, both, 1), scratch)
        del both
        collect([j for j in kept if run.done(kept[j])])

    # the tasks first (none of them waits for a block reduced here); once every one is done,
    # the blocks too large for a worker, in post-order here: on one machine the workers'
    # peaks and this process's would otherwise add up (a 10^6-coordinate solid on two
    # workers: this process stopped by the system at 15.5 GB while both workers were busy);
    # meanwhile their children's condensations wait on this process's disk, not in the
    # workers (there they had a worker restarted at 10^6 coordinates)
    for i, b in enumerate(order):
        if not here[i]:
            reduce(i, b, run)
    collect(list(kept))
    for i, b in enumerate(order):
        if here[i]:
            reduce(i, b, IN_PROCESS)
    red = _assemble(K, order, bounds, results, n, factorization)
    red.scratch = scratch
    red.blocks_here = sum(here)
    return red


def reduced_here(order: list[DissectionNode], bounds: list[np.ndarray], limit: int | None
                 ) -> list[bool]:
    """Which blocks (post-order) are reduced in this process instead of as tasks: those whose
    task would hold more than :data:`LOCAL_FRACTION` of ``limit``, a worker's memory
    (:func:`~substruct.linalg.amls_block.task_bytes`), and every ancestor of one, so that no
    task waits for a block reduced here; none without a limit."""
    if limit is None:
        return [False] * len(order)
    index = {id(b): i for i, b in enumerate(order)}
    here: list[bool] = []
    for i, b in enumerate(order):
        kids = [index[id(c)] for c in b.children]
        size = task_bytes(b.dofs.size, bounds[i].size, [bounds[j].size for j in kids],
                          b.is_leaf)
        here.append(size > LOCAL_FRACTION * limit or any(here[j] for j in kids))
    return here


def _on_disk_if_large(up: Any, scratch: ScratchArrays) -> Any:
    """A condensation computed in this process (not a task's handle) with its dense blocks
    written to ``scratch`` when large, until its parent has read them: depth first, what waits
    for a parent is a condensation of every level above the block at work, ``2 nb^2`` entries
    each (a task's handle stays on its worker, which spills by Dask's own memory limits)."""
    if isinstance(up, Condensation) and up.CK.nbytes >= SPILL_BYTES:
        return Condensation(scratch.keep(up.CK), scratch.keep(up.CM), up.G)
    return up


def _assemble(K: sp.csr_array, order: list[DissectionNode], bounds: list[np.ndarray],
              results: list[BlockModes | None], n: int, factorization: str) -> ReducedModel:
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
