r"""The solids of a Nastran model (CHEXA, CPENTA, CTETRA with PSOLID and MAT1) as matrices on
the translations of its grids, in basic axes.

Linear elasticity with :math:`\lambda = E\nu / ((1 + \nu)(1 - 2\nu))`, :math:`\mu = G`,

.. math::  K_e = \int_{\Omega_e} \bigl(2 \mu\, \varepsilon(\Phi) : \varepsilon(\Phi) +
           \lambda\, \operatorname{div} \Phi \operatorname{div} \Phi\bigr)\, d\Omega, \qquad
           M_e = \int_{\Omega_e} \rho\, \Phi^T \Phi \, d\Omega

on scikit-fem's linear vector elements (``ElementHex1``, ``ElementWedge1``, ``ElementTetP1``)
over meshes made from the elements' grids (``MeshHex1`` and ``MeshTet1`` read through meshio,
whose corner order is Nastran's; ``MeshWedge1`` directly, its corner order being Nastran's too), with 2 Gauss points along each axis of the
hexahedron and the wedge (Nastran's ``IN = 2``, ``ISOP = FULL``): scikit-fem's own rule on
the hexahedron, and on the wedge the 3 x 2 rule of :func:`wedge_quadrature` (scikit-fem
12.0.2's wedge rules have weights summing to 1/4, not to the reference wedge's volume 1/2, so
they halve every matrix).  Elements of one kind and
one material make one mesh.  The 8-grid CHEXA and the 6-grid CPENTA whose PSOLID asks for
bubble functions (IN and ISOP blank, Nastran's default) take their stiffness from
:func:`substruct.models.nastran_bubble.bubble_hex_stiffness` and
:func:`~substruct.models.nastran_bubble.bubble_wedge_stiffness` instead, their mass as above.

The 10-grid CTETRA (all six mid-side grids) takes its stiffness and consistent mass from
:func:`substruct.models.nastran_tet10.tet10_matrices`, the 20-grid CHEXA and 15-grid CPENTA
from :func:`substruct.models.nastran_quad_solids.hex20_matrices` and
:func:`~substruct.models.nastran_quad_solids.penta15_matrices` (3 x 3 x 3 and 7 x 3 Gauss
points); all three need ``PARAM,COUPMASS``: Nastran's lumped mass of quadratic solids is not
published in detail and equal shares would be wrong.

Mass, as in Nastran: lumped by default, the element's mass :math:`\rho V_e` in equal shares on
the translations of its corners; coupled (``PARAM,COUPMASS`` positive), the consistent
:math:`M_e`.  The solids stiffen no rotation of a grid: with AUTOSPC those are removed unless
an element, a link or a point of the case names them.
"""

from __future__ import annotations

from typing import Callable, Iterator

import meshio
import numpy as np
import scipy.sparse as sp
from skfem import Basis, BilinearForm, ElementHex1, ElementTetP1, ElementVector, \
    ElementWedge1, Functional, MeshWedge1, asm
from skfem.helpers import dot
from skfem.io.meshio import from_meshio
from skfem.models.elasticity import linear_elasticity

from substruct.case.bdf_fields import BdfError
from substruct.case.bdf_model import BulkData
from substruct.case.bdf_solids import SOLID_CORNERS
from substruct.models.nastran_bubble import bubble_hex_stiffness, bubble_wedge_stiffness, \
    isotropic_D
from substruct.models.nastran_quad_solids import hex20_matrices, penta15_matrices
from substruct.models.nastran_tet10 import tet10_matrices

__all__ = ["solid_blocks", "wedge_quadrature"]

_ELEMENT = {"hexahedron": ElementHex1, "wedge": ElementWedge1, "tetra": ElementTetP1}


def solid_blocks(bulk: BulkData, index: dict[int, int]
                 ) -> Iterator[tuple[str, np.ndarray, sp.coo_array, sp.coo_array]]:
    """``(cell kind, grid indices of the cells (ne, nv), K, M)`` of each group of solids of one
    kind and one material (module docstring); ``K`` and ``M`` are on the coordinates
    ``6 * grid index + component`` of the whole model.

    Raises:
        BdfError: an element of zero volume, naming its card.
    """
    N = 6 * len(index)
    groups: dict[tuple[str, int, bool, int], list] = {}
    for cell, mat in bulk.solids:
        groups.setdefault((cell.kind, mat.id, cell.bubble, len(cell.nodes)), []).append(
            (cell, mat))
    for (card, _, bubble, nv), items in groups.items():
        if nv > SOLID_CORNERS[card][0]:  # the quadratic solids
            yield _quadratic_block(bulk, items, index)
            continue
        kind = SOLID_CORNERS[card][2]
        mat = items[0][1]
        conn = np.array([[index[g] for g in cell.nodes] for cell, _ in items], dtype=np.int64)
        used, local = np.unique(conn, return_inverse=True)
        local = local.reshape(conn.shape)
        xyz = np.array([bulk.grids[g] for g in (list(index)[k] for k in used)])
        _check_volumes(bulk, items, xyz[local])
        mesh = MeshWedge1(xyz.T, local.T) if kind == "wedge" else \
            from_meshio(meshio.Mesh(xyz, [(kind, local)]))
        basis = Basis(mesh, ElementVector(_ELEMENT[kind]()), intorder=2) if kind != "wedge" \
            else Basis(mesh, ElementVector(ElementWedge1()), quadrature=wedge_quadrature())
        nu = mat.nu
        lam = mat.E * nu / ((1 + nu) * (1 - 2 * nu))
        if bubble:  # CHEXA or CPENTA with bubble functions, IN blank or BUBBLE
            K = _bubble_stiffness(kind, xyz[local], local, len(used), mat.E, nu)
        else:
            K = asm(linear_elasticity(lam, mat.E / (2 * (1 + nu))), basis)
        if bulk.coupled:
            M = asm(BilinearForm(lambda u, v, w: mat.rho * dot(u, v)), basis)
        else:
            vol = Functional(lambda w: 1.0 + 0.0 * w.x[0]).elemental(basis)
            share = np.zeros(len(used))
            np.add.at(share, local, (mat.rho * vol / conn.shape[1])[:, None])
            M = sp.diags(np.repeat(share, 3))  # scikit-fem's vertex order is the mesh's
        # the coordinate of each basis DOF in the whole model: vertex k, component c
        target = np.empty(basis.N, dtype=np.int64)
        for c in range(3):
            target[basis.nodal_dofs[c]] = 6 * used + c
        if bubble:  # assembled on the coordinates 3 * vertex + component
            target_K = np.repeat(6 * used, 3) + np.tile(np.arange(3), len(used))
        else:
            target_K = target
        if bulk.coupled:
            yield kind, conn, _moved(K, target_K, N), _moved(M, target, N)
        else:
            lumped = sp.coo_array(M)
            order = np.repeat(6 * used, 3) + np.tile(np.arange(3), len(used))
            yield kind, conn, _moved(K, target_K, N), sp.coo_array(
                (lumped.data, (order[lumped.row], order[lumped.col])), shape=(N, N))


def wedge_quadrature() -> tuple[np.ndarray, np.ndarray]:
    r"""Points ``(3, 6)`` and weights of the 3 x 2 Gauss rule on the reference wedge
    :math:`\{x, y \ge 0, x + y \le 1\} \times [0, 1]`: the triangle's three points
    :math:`(1/6, 1/6), (2/3, 1/6), (1/6, 2/3)` (weights 1/6, degree 2) times two Gauss points
    :math:`1/2 \mp 1/(2\sqrt3)` (weights 1/2); the weights sum to 1/2, the wedge's volume."""
    tri = np.array([[1 / 6, 1 / 6], [2 / 3, 1 / 6], [1 / 6, 2 / 3]])
    line = 0.5 + np.array([-0.5, 0.5]) / np.sqrt(3.0)
    X = np.array([[a, b, z] for z in line for a, b in tri]).T
    return X, np.full(6, 1 / 12)


def _bubble_stiffness(kind: str, X: np.ndarray, local: np.ndarray, nv: int, E: float,
                      nu: float) -> sp.coo_array:
    """The condensed hexahedra of :func:`bubble_hex_stiffness` or wedges of
    :func:`bubble_wedge_stiffness` assembled on the coordinates ``3 * vertex + component`` of
    ``nv`` vertices."""
    D = isotropic_D(E, nu)
    element = bubble_hex_stiffness if kind == "hexahedron" else bubble_wedge_stiffness
    n = 3 * local.shape[1]
    # in blocks of elements: the strain matrices take 8 x 6 x 33 numbers a hexahedron
    Ke = np.concatenate([element(X[k:k + 4096], D)
                         for k in range(0, len(X), 4096)]) if len(X) else np.zeros((0, n, n))
    dofs = (3 * local[:, :, None] + np.arange(3)).reshape(len(local), n)
    rows = np.repeat(dofs, n, axis=1).ravel()
    cols = np.tile(dofs, (1, n)).ravel()
    return sp.coo_array((Ke.ravel(), (rows, cols)), shape=(3 * nv, 3 * nv))


#: Per quadratic card: its element matrices, meshio's name of the cell drawn and the grids of
#: the card in meshio's (VTK's) order, whose edge grids come in another order than Nastran's;
#: the 15-grid CPENTA is drawn by its corners (meshio 5.3 has no 15-node wedge).
_QUADRATIC = {
    "CTETRA": (tet10_matrices, "tetra10", tuple(range(10))),
    "CHEXA": (hex20_matrices, "hexahedron20",
              tuple(range(12)) + (16, 17, 18, 19, 12, 13, 14, 15)),
    "CPENTA": (penta15_matrices, "wedge", tuple(range(6))),
}


def _quadratic_block(bulk: BulkData, items: list, index: dict[int, int]
                     ) -> tuple[str, np.ndarray, sp.coo_array, sp.coo_array]:
    """The 10-grid CTETRA (:func:`tet10_matrices`), 20-grid CHEXA (:func:`hex20_matrices`) or
    15-grid CPENTA (:func:`penta15_matrices`) of one material, coupled mass only; the cells
    returned as meshio draws them (``_QUADRATIC``)."""
    cell0, mat = items[0]
    element, kind, order = _QUADRATIC[cell0.kind]
    nv = len(cell0.nodes)
    if not bulk.coupled:
        raise BdfError(bulk.source, f"the {nv}-grid {cell0.kind} needs coupled mass "
                       "(PARAM,COUPMASS,1): Nastran's lumped mass of quadratic solids is not "
                       "reproduced", "no COUPMASS", line=cell0.line, card=cell0.kind,
                       ident=cell0.id)
    N = 6 * len(index)
    conn = np.array([[index[g] for g in cell.nodes] for cell, _ in items], dtype=np.int64)
    X = np.array([[bulk.grids[g] for g in cell.nodes] for cell, _ in items], dtype=float)
    _check_volumes(bulk, items, X[:, :SOLID_CORNERS[cell0.kind][0]])
    D = isotropic_D(mat.E, mat.nu)
    Ks, Ms = [], []
    chunk = max(1, 2 ** 17 // nv ** 2)  # about 12 MB of element matrices at a time
    for k in range(0, len(X), chunk):
        try:
            Ke, Me = element(X[k:k + chunk], D, mat.rho)
        except ValueError as err:
            bad = next(j for j in range(k, min(k + chunk, len(X)))
                       if _fails(element, X[j:j + 1], D, mat.rho))
            cell = items[bad][0]
            raise BdfError(bulk.source, str(err), list(cell.nodes), line=cell.line,
                           card=cell.kind, ident=cell.id) from None
        Ks.append(Ke)
        Ms.append(Me)
    n = 3 * nv
    dofs = (6 * conn[:, :, None] + np.arange(3)).reshape(len(conn), n)
    rows = np.repeat(dofs, n, axis=1).ravel()
    cols = np.tile(dofs, (1, n)).ravel()
    K = sp.coo_array((np.concatenate(Ks).ravel(), (rows, cols)), shape=(N, N))
    M = sp.coo_array((np.concatenate(Ms).ravel(), (rows, cols)), shape=(N, N))
    return kind, conn[:, list(order)], K, M


def _fails(element: Callable, X: np.ndarray, D: np.ndarray, rho: float) -> bool:
    try:
        element(X, D, rho)
    except ValueError:
        return True
    return False


def _moved(A: sp.sparray | sp.spmatrix, target: np.ndarray, N: int) -> sp.coo_array:
    a = sp.coo_array(A)
    return sp.coo_array((a.data, (target[a.row], target[a.col])), shape=(N, N))


def _check_volumes(bulk: BulkData, items: list, X: np.ndarray) -> None:
    """Refuse an element whose corners span no volume (relative to its size cubed)."""
    span = np.ptp(X, axis=1).max(axis=1)
    c = X.mean(axis=1, keepdims=True)
    d = X - c
    # the smallest singular value of the corners' spread measures their flatness
    flat = np.linalg.svd(d, compute_uv=False)[:, -1]
    for k in np.flatnonzero(~(flat > 1e-8 * np.maximum(span, 1e-300))):
        cell = items[int(k)][0]
        raise BdfError(bulk.source, "the corners span no volume (a flat or collapsed "
                       "element)", list(cell.nodes), line=cell.line, card=cell.kind,
                       ident=cell.id)
