r"""Shells of a frame: flat plates between frame nodes, divided into elements of
:mod:`substruct.models.shell` that share nodes with the beams.

A :class:`Shell` is a triangle or a quadrilateral of frame nodes with a thickness and a
material.  ``divisions`` cuts it into equal elements: a quadrilateral into ``nx x ny``
quadrilaterals on its bilinear map (``x(s, r) = sum N_k(s, r) x_k``), a triangle into ``d^2``
triangles on its barycentric grid.  A node made this way that falls on an existing node (a
given one, one made along a beam by its ``divisions``, or one of an earlier shell) within
the frame's node tolerance *is* that node, so shells and beams meeting along a line share
their nodes when their divisions agree there.  New nodes are numbered after the largest id.

The material's Poisson ratio is :math:`\nu = E / (2G) - 1` (isotropic).  ``bending``:
``"kirchhoff"`` (DKQ / DKT, no transverse shear deformation) or ``"mindlin"`` (MITC4 /
MITC3, transverse shear stiffness :math:`\tfrac56 G t`, :mod:`substruct.models.mindlin_plate`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from substruct.models.beam import Material
from substruct.models.mindlin_plate import KAPPA_SHEAR
from substruct.models.shell import ShellTerms
from substruct.models.shell_batch import shell_matrices_batch

__all__ = ["Shell", "ShellMesh", "shell_mesh", "shell_divisions", "SHELL_BENDING"]

#: The plate theories of a shell's bending.
SHELL_BENDING = ("kirchhoff", "mindlin")


@dataclass(frozen=True)
class Shell:
    """A flat plate between three or four frame nodes (in order around it).

    Attributes:
        nodes: the corner node ids.
        thickness: its thickness.
        material: ``E``, ``G`` (so ``nu = E / 2G - 1``) and ``rho``.
        divisions: elements along sides 1-2 and 2-3 (a quadrilateral), or along each side (a
            triangle: ``d`` gives ``d^2`` elements; both numbers must then be equal).
        nsm: non-structural mass per area.
        name: for messages.
        bending: ``"kirchhoff"`` or ``"mindlin"`` (module docstring).
    """

    nodes: tuple[int, ...]
    thickness: float
    material: Material
    divisions: tuple[int, int] = (1, 1)
    nsm: float = 0.0
    name: str = ""
    bending: str = "kirchhoff"


@dataclass
class ShellMesh:
    """Element triplets and faces made from the shells: ``rows``, ``cols``, ``kv``, ``mv``
    (one array each per shell, its elements' ``(6n)^2`` entries one after another, 6
    coordinates per node), faces by kind (``"triangle"``,
    ``"quad"``: node indices) and the largest element size."""

    rows: list[np.ndarray] = field(default_factory=list)
    cols: list[np.ndarray] = field(default_factory=list)
    kv: list[np.ndarray] = field(default_factory=list)
    mv: list[np.ndarray] = field(default_factory=list)
    faces: dict[str, list[tuple[int, ...]]] = field(default_factory=dict)
    h_max: float = 0.0


def shell_divisions(shell: Shell) -> int:
    """The number of elements ``shell`` makes."""
    nx, ny = shell.divisions
    return nx * ny if len(shell.nodes) == 4 else nx * nx


def _grid(shell: Shell, X: np.ndarray) -> tuple[np.ndarray, list[tuple[int, ...]]]:
    """Local node positions of the divided shell and its elements (local node indices)."""
    nx, ny = shell.divisions
    if len(X) == 4:
        S, Rr = np.meshgrid(np.linspace(0, 1, nx + 1), np.linspace(0, 1, ny + 1), indexing="ij")
        s, r = S.ravel(), Rr.ravel()
        W = np.column_stack([(1 - s) * (1 - r), s * (1 - r), s * r, (1 - s) * r])

        def at(i: int, j: int) -> int:
            return i * (ny + 1) + j

        quads: list[tuple[int, ...]] = [(at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1))
                                        for i in range(nx) for j in range(ny)]
        return W @ X, quads
    d = nx
    pts: list[tuple[float, float, float]] = []
    index: dict[tuple[int, int], int] = {}
    for i in range(d + 1):
        for j in range(d + 1 - i):
            index[i, j] = len(pts)
            pts.append(((d - i - j) / d, i / d, j / d))
    tris: list[tuple[int, ...]] = []
    for i in range(d):
        for j in range(d - i):
            tris.append((index[i, j], index[i + 1, j], index[i, j + 1]))
            if i + j < d - 1:
                tris.append((index[i + 1, j], index[i + 1, j + 1], index[i, j + 1]))
    return np.asarray(pts) @ X, tris


def shell_mesh(shells: list[Shell], points: list[np.ndarray], ids: list[int],
               index: dict[int, int], tol: float, mass: str,
               label: Callable[[int], str]) -> ShellMesh:
    """Divide ``shells`` and make their element matrices (module docstring), all elements of a
    shell at once (:func:`substruct.models.shell_batch.shell_matrices_batch`).

    ``points``, ``ids`` and ``index`` (node id -> position in ``points``) are the frame's
    nodes so far; new nodes are appended to them.

    Raises:
        ValueError: unknown or repeated corner nodes, bad divisions or properties, a degenerate,
            non-convex or warped element (the message starts with ``label(k)``).
    """
    out = ShellMesh()
    for k, shell in enumerate(shells):
        where = label(k)
        n = len(shell.nodes)
        if n not in (3, 4) or len(set(shell.nodes)) != n or \
                any(c not in index for c in shell.nodes):
            raise ValueError(f"{where}: corners {list(shell.nodes)} must be 3 or 4 different "
                             f"nodes of the frame")
        nx, ny = shell.divisions
        if min(nx, ny) < 1 or (n == 3 and nx != ny):
            raise ValueError(f"{where}: divisions are positive, and equal for a triangle, "
                             f"got {list(shell.divisions)}")
        if shell.bending not in SHELL_BENDING:
            raise ValueError(f"{where}: bending is one of {list(SHELL_BENDING)}, got "
                             f"{shell.bending!r}")
        mat = shell.material
        nu = mat.E / (2 * mat.G) - 1
        terms = ShellTerms(shear=KAPPA_SHEAR * mat.G * shell.thickness
                           if shell.bending == "mindlin" else None)
        X = np.array([points[index[c]] for c in shell.nodes])
        local, elements = _grid(shell, X)
        node_of = np.empty(len(local), dtype=np.int64)
        known = set()
        for c, corner in enumerate(shell.nodes):
            j = int(np.argmin(np.linalg.norm(local - X[c], axis=1)))
            node_of[j] = index[corner]
            known.add(j)
        from scipy.spatial import cKDTree  # imported where used (start-up time)
        fresh = np.array([j for j in range(len(local)) if j not in known], dtype=np.int64)
        if fresh.size:
            # the new grid points are distinct from each other: one query against the nodes
            # made so far finds those that are existing nodes
            dist, near = cKDTree(np.asarray(points)).query(local[fresh])
            old = dist <= tol
            node_of[fresh[old]] = near[old]
            new = fresh[~old]
            start = len(points)
            points.extend(local[new])
            new_ids = range(max(ids) + 1, max(ids) + 1 + new.size)
            ids.extend(new_ids)
            index.update({i: start + k for k, i in enumerate(new_ids)})
            node_of[new] = start + np.arange(new.size)
        kind = "quad" if n == 4 else "triangle"
        nodes = node_of[np.asarray(elements, dtype=np.int64)]  # (m, n) node indices
        Xe = np.asarray(points)[nodes]
        try:
            Ke, Me = shell_matrices_batch(Xe, mat.E, nu, shell.thickness, mat.rho, mass,
                                          shell.nsm, terms=terms)
        except ValueError as err:
            raise ValueError(f"{where}: {err}") from None
        dofs = (6 * nodes[:, :, None] + np.arange(6)).reshape(len(nodes), -1)
        size = dofs.shape[1]
        out.rows.append(np.repeat(dofs, size, axis=1).ravel())
        out.cols.append(np.tile(dofs, (1, size)).ravel())
        out.kv.append(Ke.ravel())
        out.mv.append(Me.ravel())
        out.faces.setdefault(kind, []).extend(tuple(f) for f in nodes.tolist())
        out.h_max = max(out.h_max, float(np.linalg.norm(Xe - np.roll(Xe, 1, axis=1),
                                                        axis=2).max()))
    return out
