r"""The nested-dissection tree of automated multilevel substructuring (AMLS).

The graph of a sparse symmetric matrix (the stiffness) is cut recursively in two by METIS
(``pymetis.part_graph``, two parts), and each edge cut is turned into a *vertex separator*: a
minimum vertex cover of the bipartite graph of the cut edges (Koenig's theorem: from a maximum
matching :math:`\mathcal M`, with :math:`Z` the vertices reachable from the unmatched left
vertices by alternating paths, the cover is :math:`(L \setminus Z) \cup (R \cap Z)`, of size
:math:`|\mathcal M|`).  Removing the separator leaves two parts with no edge between them, so
in the order *subdomains first, then their separator* (post-order) the matrix has

.. math::  K_{ij} = 0 \quad \text{unless } i = j \text{ or one of } i, j
           \text{ is an ancestor of the other},

the structure AMLS reduces bottom-up (:mod:`substruct.linalg.amls`).

Rows with one sparsity pattern are merged into one graph vertex first (supervariables), so
METIS works on a smaller graph; any merging keeps the structure above, the patterns decide
only how many rows merge.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import maximum_bipartite_matching

__all__ = ["DissectionNode", "dissection_tree", "supervariables", "vertex_separator"]


@dataclass
class DissectionNode:
    """One block of the tree: a subdomain (leaf, no children) or a separator.

    Attributes:
        dofs: the matrix rows of this block, ascending.
        children: the two subtrees a separator separates (empty for a leaf).
        level: depth from the root (0).
    """

    dofs: np.ndarray
    children: list["DissectionNode"] = field(default_factory=list)
    level: int = 0

    @property
    def is_leaf(self) -> bool:
        """Whether the block is a subdomain (no children)."""
        return not self.children

    def postorder(self) -> list["DissectionNode"]:
        """The blocks of the subtree, every block after its descendants."""
        out: list[DissectionNode] = []
        for c in self.children:
            out.extend(c.postorder())
        out.append(self)
        return out


def supervariables(K: sp.sparray | sp.spmatrix) -> tuple[np.ndarray, sp.csr_array]:
    r"""Rows with identical sparsity patterns merged: ``(group, G)`` with ``group[i]`` the
    vertex of row ``i`` and ``G`` the vertex graph (symmetric, no self loops, unit weights),
    :math:`G = S^T |K| S` off its diagonal for the assignment matrix ``S``."""
    P = sp.csr_array(abs(sp.csr_array(K)))
    P = sp.csr_array(P + P.T)
    P.setdiag(1.0)
    P.sort_indices()
    keys: dict[bytes, int] = {}
    n = P.shape[0]
    group = np.empty(n, dtype=np.int64)
    for i in range(n):
        group[i] = keys.setdefault(P.indices[P.indptr[i]:P.indptr[i + 1]].tobytes(), len(keys))
    S = sp.csr_array((np.ones(n), (np.arange(n), group)), shape=(n, len(keys)))
    G = sp.csr_array(S.T @ P @ S)
    G.setdiag(0)
    G.eliminate_zeros()
    G.data[:] = 1.0
    G.sort_indices()
    return group, G


def vertex_separator(G: sp.csr_array, parts: np.ndarray) -> np.ndarray:
    r"""A minimum vertex cover of the edges of ``G`` between part 0 and part 1 (Koenig), as a
    boolean mask over the vertices: removing it disconnects the two parts."""
    coo = sp.coo_array(sp.triu(G))
    cut = parts[coo.row] != parts[coo.col]
    a = np.where(parts[coo.row[cut]] == 0, coo.row[cut], coo.col[cut])
    b = np.where(parts[coo.row[cut]] == 0, coo.col[cut], coo.row[cut])
    sep = np.zeros(G.shape[0], dtype=bool)
    if a.size == 0:
        return sep
    left, ia = np.unique(a, return_inverse=True)
    right, ib = np.unique(b, return_inverse=True)
    B = sp.csr_array((np.ones(a.size), (ia, ib)), shape=(left.size, right.size))
    match = maximum_bipartite_matching(B, perm_type="column")  # left -> right or -1
    matched_right = np.full(right.size, -1)
    matched_right[match[match >= 0]] = np.nonzero(match >= 0)[0]
    # alternating breadth-first search from the unmatched left vertices
    zl = match < 0
    zr = np.zeros(right.size, dtype=bool)
    frontier = np.nonzero(zl)[0]
    while frontier.size:
        sub = B[frontier]
        reach = np.unique(sub.indices)
        reach = reach[~zr[reach]]
        zr[reach] = True
        nxt = matched_right[reach]
        nxt = nxt[(nxt >= 0)]
        nxt = nxt[~zl[nxt]]
        zl[nxt] = True
        frontier = nxt
    sep[left[~zl]] = True
    sep[right[zr]] = True
    return sep


def _bisect(G: sp.csr_array) -> np.ndarray:
    """Two-way METIS partition of ``G`` (0/1 per vertex)."""
    import pymetis  # a dependency of the package

    adjacency = pymetis.CSRAdjacency(G.indptr.astype(np.int64), G.indices.astype(np.int64))
    _, parts = pymetis.part_graph(2, adjacency=adjacency)
    return np.asarray(parts, dtype=np.int64)


def dissection_tree(K: sp.sparray | sp.spmatrix, leaf_size: int, max_levels: int = 30,
                    M: sp.sparray | sp.spmatrix | None = None) -> DissectionNode:
    """The nested-dissection tree of the graph of ``K`` (of ``|K| + |M|`` when the mass ``M``
    is given): a block is split (two subdomains and their vertex separator) while it has
    more than ``leaf_size`` rows and is less than ``max_levels`` deep.

    Every row of ``K`` is in exactly one block; no entry of ``K`` (nor of ``M``, if given)
    couples two blocks of which neither is an ancestor of the other.  AMLS reduces the pencil
    ``(K, M)``, so its tree must be made with ``M``: a mass entry outside the stiffness's
    pattern (a point mass's inertia coupling two nodes, an eliminated rigid link) would
    otherwise couple two subdomains.
    """
    if leaf_size < 1:
        raise ValueError(f"leaf_size must be positive, got {leaf_size}")
    if M is not None:
        K = sp.csr_array(abs(sp.csr_array(K)) + abs(sp.csr_array(M)))
    group, G = supervariables(K)
    members = sp.csr_array((np.ones(group.size), (group, np.arange(group.size))),
                           shape=(G.shape[0], group.size))

    def rows(vertices: np.ndarray) -> np.ndarray:
        return np.sort(members[vertices].indices)

    def build(vertices: np.ndarray, level: int) -> DissectionNode:
        dofs = rows(vertices)
        if dofs.size <= leaf_size or level >= max_levels or vertices.size < 3:
            return DissectionNode(dofs, level=level)
        sub = sp.csr_array(G[vertices][:, vertices])
        parts = _bisect(sub)
        sep = vertex_separator(sub, parts)
        halves = [vertices[(parts == p) & ~sep] for p in (0, 1)]
        if sep.all() or min(h.size for h in halves) == 0:
            return DissectionNode(dofs, level=level)
        children = [build(h, level + 1) for h in halves]
        return DissectionNode(rows(vertices[sep]), children, level)

    return build(np.arange(G.shape[0]), 0)
