r"""The massless directions of a constrained model: :math:`\operatorname{null}(M) \cap
\operatorname{null}(A)`, each of which carries an infinite root instead of a mode.

A zero row of ``M`` (a massless coordinate, the paper's eq 6) is one such direction, but not
the only kind: a point mass off its node without rotary inertia gives the node's six
coordinates a mass of rank three with no zero row, and a pinned beam end in skew axes with a
coupled mass a rank-deficient block.  The directions are found on the mass scaled to a unit
diagonal (:func:`substruct.linalg.scaling.mass_column_scale`), so the decision does not
depend on the units nor on a heavy part beside a light one:

.. math::  \tilde M = \frac{C M C}{\bar m}, \qquad u = C v, \qquad
           v \in \operatorname{null}(A C) = \operatorname{span} N, \qquad
           N^T \tilde M N\, w = \mu\, w, \quad \mu \le \text{MASSLESS\_TOL}.

:func:`massless_directions` does this densely (the dense eigensolvers' root counts);
:func:`massless_split` finds them in a large sparse mass block by block and makes each one a
coordinate (the reduced mass of the sparse eigensolvers, whose Krylov basis must fit in the
space that has mass and whose Lanczos iteration needs the massless directions as zero rows).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from substruct.linalg.dense import dense
from substruct.linalg.nullspace import null_space_basis
from substruct.linalg.scaling import mass_column_scale

__all__ = ["MASSLESS_BLOCK", "MASSLESS_TOL", "MasslessSplit", "massless_count",
           "massless_directions", "massless_split"]

#: Smallest eigenvalue of the mass scaled to a unit diagonal (coordinates with mass) below
#: which a direction carries no mass.  Measured on the worked cases: 4.5e-4 (shells,
#: quadratic solids) to 1 (lumped); a direction without mass is at round-off (-4e-16 for a
#: pinned CBAR end in skew axes with coupled mass, 1e-16 for a point mass off its node).
MASSLESS_TOL = 1e-10
#: Largest block of a sparse mass (a connected component of its graph) whose massless
#: directions :func:`massless_count` finds by a dense eigensolve; a larger block (a consistent
#: mass over a whole mesh) is counted by its zero rows only.
MASSLESS_BLOCK = 200


def massless_directions(M: sp.sparray | sp.spmatrix | np.ndarray,
                        A: sp.sparray | sp.spmatrix | np.ndarray | None = None) -> np.ndarray:
    r"""Orthonormal ``n x z`` basis of the motions with no mass that satisfy ``A u = 0``
    (every coordinate free when ``A`` is ``None`` or has no row), dense; see the module
    docstring.  ``M`` symmetric positive semidefinite.

    Examples
    --------
    A unit mass at ``x = 1`` on a node with a translation and a rotation: ``M`` has rank one
    and no zero row; its massless motion is the rotation about the mass,
    ``(u, theta) ~ (1, -1)``.

    >>> import numpy as np
    >>> T = np.array([[1.0, 1.0]])            # u_mass = u + 1 * theta
    >>> Z = massless_directions(T.T @ T)
    >>> np.round(Z[:, 0] * np.sign(Z[0, 0]) * np.sqrt(2), 12)
    array([ 1., -1.])
    """
    Md = np.asarray(dense(sp.csr_array(M, dtype=float)), dtype=float)
    n = Md.shape[0]
    if n == 0:
        return np.zeros((0, 0))
    c = mass_column_scale(Md)
    scaled = c[:, None] * Md * c[None, :]
    mean = float(np.mean(np.abs(np.diag(scaled))[np.diag(scaled) != 0])) \
        if np.any(np.diag(scaled)) else 1.0
    scaled = (scaled + scaled.T) / (2 * mean)
    Ad = np.zeros((0, n)) if A is None else np.asarray(dense(sp.csr_array(A, dtype=float)))
    N = null_space_basis(Ad * c[None, :]) if Ad.shape[0] else np.eye(n)
    if not N.shape[1]:
        return np.zeros((n, 0))
    mu, W = np.linalg.eigh(N.T @ scaled @ N)
    V = c[:, None] * (N @ W[:, mu <= MASSLESS_TOL])
    if not V.shape[1]:
        return V
    Q, _ = np.linalg.qr(V)
    return Q


@dataclass(frozen=True)
class MasslessSplit:
    r"""The massless directions of a sparse mass, made coordinates (:func:`massless_split`).

    Attributes:
        Q: sparse ``n x n``, block diagonal: on each block with a massless direction that is a
            combination of its coordinates, :math:`\operatorname{diag}(c) W` (``c`` the unit
            diagonal scaling, ``W`` the eigenvectors of the scaled block), the identity
            elsewhere; ``u = Q p``.
        zero: the new coordinates ``p`` without mass (the zero rows of ``M`` among them).
        rotated: whether ``Q`` is not the identity.
    """

    Q: sp.csr_array
    zero: np.ndarray
    rotated: bool

    @property
    def count(self) -> int:
        """The number of massless directions."""
        return int(np.count_nonzero(self.zero))

    def mass(self, M: sp.sparray) -> sp.csr_array:
        r""":math:`Q^T M Q` with the rows and columns of :attr:`zero` set to exact zeros (they
        are round-off of the mass), symmetric."""
        if not self.rotated:
            return sp.csr_array(M)
        keep = sp.diags_array((~self.zero).astype(float))
        Mq = keep @ (self.Q.T @ (sp.csr_array(M) @ self.Q)) @ keep
        return sp.csr_array((Mq + Mq.T) / 2)


def massless_split(M: sp.sparray | sp.spmatrix | np.ndarray) -> MasslessSplit:
    r"""The massless directions of the symmetric positive semidefinite ``M``, decided as
    :func:`massless_directions` decides them, one block (connected component of the graph of
    ``M``) at a time, and a change of coordinates that makes each one a coordinate.

    A zero row is one direction; a block of at most :data:`MASSLESS_BLOCK` coordinates (a point
    mass on its node, an offset mass with the rotations of its node, lumped masses with their
    couplings) gives the eigenvalues of its mass scaled to a unit diagonal at or below
    :data:`MASSLESS_TOL`; a larger block only its zero rows (its dense eigensolve would cost
    more than the eigensolver the split serves).  With ``Q`` the sparse eigensolvers see the
    massless directions as zero rows of :math:`Q^T M Q` (:meth:`MasslessSplit.mass`), which
    they handle; a combination of coordinates without mass would leave the Lanczos iteration
    in the semi-inner product of ``M`` with components of any size in it.

    Examples
    --------
    Two offset masses without rotary inertia (rank one on two coordinates each) and a massless
    coordinate: three directions without mass.

    >>> import numpy as np, scipy.sparse as sp
    >>> T = np.array([[1.0, 2.0]])
    >>> split = massless_split(sp.block_diag([T.T @ T, 5 * T.T @ T, sp.csr_array((1, 1))]))
    >>> split.count, split.rotated
    (3, True)
    >>> bool(abs(split.mass(sp.block_diag([T.T @ T, 5 * T.T @ T, sp.csr_array((1, 1))]))
    ...           @ split.zero.astype(float)).max() == 0)
    True
    """
    Ms = sp.csr_array(M, dtype=float)
    Ms.eliminate_zeros()
    n = Ms.shape[0]
    zero = np.asarray(abs(Ms).sum(axis=1)).ravel() == 0.0
    rows: list[np.ndarray] = []
    cols: list[np.ndarray] = []
    vals: list[np.ndarray] = []
    if n:
        nblocks, label = connected_components(Ms, directed=False)
        sizes = np.bincount(label, minlength=nblocks)
        order = np.argsort(label, kind="stable")
        starts = np.concatenate([[0], np.cumsum(sizes)])
        pos = np.empty(n, dtype=np.int64)  # each coordinate's place in its block
        pos[order] = np.arange(n) - np.repeat(starts[:-1], sizes)
        coo = Ms.tocoo()
        for size in np.unique(sizes[(sizes > 1) & (sizes <= MASSLESS_BLOCK)]):
            blocks = np.flatnonzero(sizes == size)
            slot = np.full(nblocks, -1)
            slot[blocks] = np.arange(blocks.size)
            e = sizes[label[coo.row]] == size
            D = np.zeros((blocks.size, size, size))
            np.add.at(D, (slot[label[coo.row[e]]], pos[coo.row[e]], pos[coo.col[e]]),
                      coo.data[e])
            d = np.abs(np.diagonal(D, axis1=1, axis2=2))
            c = 1.0 / np.sqrt(np.where(d > 0, d, 1.0))
            S = c[:, :, None] * D * c[:, None, :]
            mu, W = np.linalg.eigh((S + np.swapaxes(S, 1, 2)) / 2)
            hit = np.any(mu <= MASSLESS_TOL, axis=1)
            if not hit.any():
                continue
            members = np.stack([order[starts[b]:starts[b + 1]] for b in blocks[hit]])
            Qb = c[hit][:, :, None] * W[hit]  # (blocks, size, size): u = diag(c) W p
            rows.append(np.repeat(members, size, axis=1).ravel())
            cols.append(np.tile(members, (1, size)).ravel())
            vals.append(Qb.ravel())
            zero[members.ravel()] = (mu[hit] <= MASSLESS_TOL).ravel()
    if not rows:
        return MasslessSplit(Q=sp.csr_array(sp.eye_array(n)), zero=zero, rotated=False)
    rotated = np.concatenate(rows)
    untouched = np.setdiff1d(np.arange(n), rotated)
    Q = sp.csr_array(sp.coo_array(
        (np.concatenate(vals + [np.ones(untouched.size)]),
         (np.concatenate(rows + [untouched]), np.concatenate(cols + [untouched]))),
        shape=(n, n)))
    return MasslessSplit(Q=Q, zero=zero, rotated=True)


def massless_count(M: sp.sparray | sp.spmatrix | np.ndarray) -> int:
    """The number of massless directions of ``M`` (:func:`massless_split`)."""
    return massless_split(M).count
