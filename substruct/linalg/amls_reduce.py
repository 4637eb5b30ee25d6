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
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from substruct.linalg.amls_tree import Node
from substruct.linalg.factorize import Solve, factorizer
from substruct.linalg.lanczos import shift_invert_lanczos

__all__ = ["DENSE_LEAF", "ReducedModel", "amls_reduce", "block_modes"]

#: Subdomains up to this many coordinates get their fixed-interface modes by a dense ``eigh``;
#: larger ones by shift-invert Lanczos on their sparse factorization.
DENSE_LEAF = 2000


@dataclass
class _Block:
    """What the expansion to physical coordinates needs of one block."""

    dofs: np.ndarray
    boundary: np.ndarray
    modes: np.ndarray          # indices of the block's modes among the reduced coordinates
    Phi: np.ndarray
    Psi: np.ndarray | None = None          # separators: dense constraint modes
    K_dB: sp.csr_array | None = None       # subdomains: -solve(K_dB x_B) instead
    solve: Solve | None = None


@dataclass
class ReducedModel:
    r"""The AMLS reduced pencil :math:`(K_r, M_r) = (\operatorname{diag}\Lambda, Z^T M Z)`.

    Attributes:
        lam: the diagonal of :math:`K_r` (the blocks' fixed-interface eigenvalues).
        M: :math:`M_r`, sparse symmetric with identity diagonal blocks.
        level: the tree level (0: root) of each reduced coordinate.
        n: number of physical coordinates.
        blocks: the data of :meth:`expand`, root first.
    """

    lam: np.ndarray
    M: sp.csr_array
    level: np.ndarray
    n: int
    blocks: list[_Block] = field(repr=False)

    @property
    def size(self) -> int:
        """Number of reduced coordinates."""
        return int(self.lam.size)

    def expand(self, Y: np.ndarray) -> np.ndarray:
        r"""Physical coordinates :math:`X = Z Y` of reduced ones (``size x k``), top-down:
        :math:`x_b = \Phi_b y_b + \Psi_b x_B` (subdomains: :math:`\Psi_b x_B` by a solve)."""
        Y = np.asarray(Y, dtype=float).reshape(self.size, -1)
        X = np.zeros((self.n, Y.shape[1]))
        for b in self.blocks:
            xb = b.Phi @ Y[b.modes]
            if b.boundary.size:
                xB = X[b.boundary]
                if b.Psi is not None:
                    xb += b.Psi @ xB
                else:
                    assert b.K_dB is not None and b.solve is not None
                    xb -= np.asarray(b.solve(b.K_dB @ xB)).reshape(xb.shape)
            X[b.dofs] = xb
        return X


def block_modes(Kb: np.ndarray | sp.sparray, Mb: np.ndarray | sp.sparray, lam_cut: float,
                solve: Solve | None = None) -> tuple[np.ndarray, np.ndarray]:
    r"""The eigenpairs :math:`K_b \phi = \lambda M_b \phi` with :math:`\lambda \le` ``lam_cut``,
    ``M``-normalized: dense ``eigh`` (subset by value) for small or dense blocks, else
    shift-invert Lanczos with ``solve`` (:math:`K_b^{-1}`), doubling the number of pairs until
    one exceeds the cut-off (or the block is small enough for ``eigh``)."""
    n = Kb.shape[0]
    if n == 0:
        return np.zeros(0), np.zeros((0, 0))
    if sp.issparse(Kb) and n > DENSE_LEAF and solve is not None:
        k = min(32, n // 4)
        v0 = np.asarray(np.random.default_rng(0).standard_normal(n))
        while k < n // 4:
            lam, V = shift_invert_lanczos(sp.csr_array(Kb), sp.csr_array(Mb), k, 0.0, solve,
                                          v0=v0)
            if lam.max() > lam_cut:
                order = np.argsort(lam)
                keep = order[lam[order] <= lam_cut]
                return lam[keep], V[:, keep]
            k *= 2
    Kd = sp.csr_array(Kb).toarray() if sp.issparse(Kb) else np.asarray(Kb)
    Md = sp.csr_array(Mb).toarray() if sp.issparse(Mb) else np.asarray(Mb)
    lam, V = sla.eigh(Kd, Md, subset_by_value=(-np.inf, lam_cut), driver="gvx")
    return lam, V


def _positions(I: np.ndarray, sub: np.ndarray) -> np.ndarray:
    """Where the entries of ``sub`` sit in ``I`` (every one is there)."""
    order = np.argsort(I)
    return order[np.searchsorted(I, sub, sorter=order)]


def amls_reduce(K: sp.sparray | sp.spmatrix, M: sp.sparray | sp.spmatrix, root: Node,
                lam_cut: float, factorization: str = "auto",
                progress: Callable[[str], None] | None = None) -> ReducedModel:
    r"""The AMLS reduction of the symmetric pencil ``(K, M)`` over the tree ``root``, keeping in
    every block the fixed-interface modes with eigenvalue at most ``lam_cut`` (see the module
    docstring).  ``K`` restricted to every subdomain must be positive definite (true when the
    subdomains are held by separators, or ``K`` is); the root separator may be singular
    (a free body's rigid modes).  ``progress`` receives one line per tree level."""
    K = sp.csr_array(K, dtype=float)
    M = sp.csr_array(M, dtype=float)
    n = K.shape[0]
    P = sp.csr_array(abs(K) + abs(M))
    order = root.postorder()
    pos = np.empty(n, dtype=np.int64)
    for i, b in enumerate(order):
        pos[b.dofs] = i
    factor = factorizer(factorization)
    passed: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = {}
    blocks: list[_Block] = []
    lams: list[np.ndarray] = []
    levels: list[np.ndarray] = []
    rows: list[np.ndarray] = []
    cols: list[np.ndarray] = []
    vals: list[np.ndarray] = []
    offset = 0
    depth = max(b.level for b in order)
    per_level = np.zeros(depth + 1, dtype=np.int64)
    for i, b in enumerate(order):
        d = b.dofs
        own = np.unique(P[d].indices) if d.size else np.zeros(0, dtype=np.int64)
        B = own[pos[own] > i]
        for c in b.children:
            B = np.union1d(B, passed[id(c)][0])
        B = B[pos[B] > i]
        if b.is_leaf:
            Kdd, Mdd = K[d][:, d], M[d][:, d]
            KdB, MdB = K[d][:, B], M[d][:, B]
            solve = factor(sp.csc_array(Kdd))
            Psi = -np.asarray(solve(KdB.toarray())).reshape(d.size, B.size)
            lam, Phi = block_modes(Kdd, Mdd, lam_cut, solve)
            MdBt = MdB.toarray() + Mdd @ Psi
            CK = KdB.T @ Psi
            CM = MdB.T @ Psi + Psi.T @ MdBt
            G_own = Phi.T @ MdBt
            Qs: list[np.ndarray] = []
            Gs: list[np.ndarray] = []
            blk = _Block(d, B, np.arange(0), Phi, K_dB=KdB, solve=solve)
        else:
            ns = d.size
            I = np.concatenate([d, B])
            Kl = np.zeros((I.size, I.size))
            Ml = np.zeros((I.size, I.size))
            Ks, Ms = K[d][:, I].toarray(), M[d][:, I].toarray()
            Kl[:ns], Ml[:ns] = Ks, Ms
            Kl[ns:, :ns], Ml[ns:, :ns] = Ks[:, ns:].T, Ms[:, ns:].T
            Qs, Gs = [], []
            for c in b.children:
                Bc, CKc, CMc, Qc, Gc = passed.pop(id(c))
                p = _positions(I, Bc)
                Kl[np.ix_(p, p)] += CKc
                Ml[np.ix_(p, p)] += CMc
                Gf = np.zeros((Qc.size, I.size))
                Gf[:, p] = Gc
                Qs.append(Qc)
                Gs.append(Gf)
            Kss, Mss = Kl[:ns, :ns], Ml[:ns, :ns]
            if B.size and ns:
                Psi = -sla.cho_solve(sla.cho_factor(Kss), Kl[:ns, ns:])
            else:
                Psi = np.zeros((ns, B.size))
            lam, Phi = block_modes(Kss, Mss, lam_cut)
            MsBt = Ml[:ns, ns:] + Mss @ Psi
            CK = Kl[ns:, ns:] + Kl[ns:, :ns] @ Psi
            CM = Ml[ns:, ns:] + Ml[ns:, :ns] @ Psi + Psi.T @ MsBt
            G_own = Phi.T @ MsBt
            blk = _Block(d, B, np.arange(0), Phi, Psi=Psi)
        mine = np.arange(offset, offset + lam.size)
        offset += lam.size
        blk.modes = mine
        blocks.append(blk)
        lams.append(lam)
        levels.append(np.full(lam.size, b.level))
        per_level[b.level] += lam.size
        Gnew = [G_own]
        for Qc, Gf in zip(Qs, Gs):
            cross = Gf[:, :d.size] @ Phi     # child-subtree modes against this block's modes
            r, c_ = np.meshgrid(Qc, mine, indexing="ij")
            rows += [r.ravel(), c_.ravel()]
            cols += [c_.ravel(), r.ravel()]
            vals += [cross.ravel(), cross.ravel()]
            Gnew.append(Gf[:, :d.size] @ Psi + Gf[:, d.size:])
        Q = np.concatenate([mine] + Qs)
        passed[id(b)] = (B, (CK + CK.T) / 2, (CM + CM.T) / 2, Q, np.vstack(Gnew))
    lam_all = np.concatenate(lams)
    N = lam_all.size
    diag = np.arange(N)
    Mr = sp.csr_array((np.concatenate(vals + [np.ones(N)]),
                       (np.concatenate(rows + [diag]), np.concatenate(cols + [diag]))),
                      shape=(N, N))
    if progress is not None:
        for lev in range(depth + 1):
            progress(f"AMLS level {lev}: {int(per_level[lev])} modes kept")
    return ReducedModel(lam_all, Mr, np.concatenate(levels), n, blocks[::-1])
