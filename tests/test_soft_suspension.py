"""A stiff body on soft springs: its suspension modes are modes, not rigid-body modes.

A steel box of 1 mm elements (``tr K / tr M`` about ``1.7e14``) on springs of 0.1 N/m at one
face has six suspension modes at 6 to 61 rad/s, with ``omega^2`` below ``1e-12 tr K / tr M``:
an eigenvalue threshold alone read them as rigid-body modes and reported them at 0 (the sparse
path and AMLS did). Their strain energy is ``1e3 .. 1e6 eps`` of ``|u|^T |K| |u|``, the
rigid-body modes' below ``0.1 eps`` (:func:`substruct.linalg.scaling.rigid_modes`).

Reference, independent of the eigen solvers: the suspension modes of a body much stiffer than
its springs are those of the rigid body on the springs, the ``6 x 6`` pencil
``(R^T K_s R, R^T M R)`` of the free body's rigid-body modes ``R``, to ``O(k / k_body)``.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from substruct.analysis.api import modes
from substruct.analysis.modes.sparse import DENSE_FREE
from substruct.linalg.amls import amls_modes
from substruct.linalg.scaling import rigid_eigenvalue, stiffness_over_mass
from substruct.models.craig_bampton import fixed_interface_modes
from substruct.models.solid import BoxGrid, solid_box

H = 1e-3  # element size, m
NX, NY = 20, 6


def free_box() -> tuple[sp.csr_array, sp.csr_array]:
    """A free steel box of ``20 x 6 x 6`` hexahedra of 1 mm: 3,087 coordinates."""
    box = solid_box("box", BoxGrid((NX * H, NY * H, NY * H), (NX, NY, NY)), 2.1e11, 0.3,
                    7800.0, fixed=[])
    return sp.csr_array(box.K), sp.csr_array(box.M)


def springs(n: int, k: float) -> sp.csr_array:
    """A spring ``k`` to ground in x, y and z at every node of the face ``x = 0`` (the first
    ``3 (NY + 1)^2`` coordinates)."""
    face = 3 * (NY + 1) ** 2
    return sp.csr_array(sp.diags_array(np.where(np.arange(n) < face, k, 0.0)))


def rigid_body_pencil(K: sp.csr_array, M: sp.csr_array, Ks: sp.csr_array) -> np.ndarray:
    """``omega`` of the rigid body on the springs, from the free body's six rigid modes."""
    lam, U = sla.eigh(K.toarray(), M.toarray(), subset_by_index=[0, 5])
    assert np.abs(lam).max() < 1e2 * rigid_eigenvalue(K, M)
    return np.sqrt(sla.eigh(U.T @ (Ks @ U), U.T @ (M @ U), eigvals_only=True))


def test_suspension_modes_keep_their_frequencies_on_the_sparse_path_and_in_amls():
    K, M = free_box()
    n = K.shape[0]
    assert n > DENSE_FREE  # the Krylov path, not the dense pencil of few coordinates
    Ks = springs(n, 0.1)
    exact = rigid_body_pencil(K, M, Ks)
    Kt = sp.csr_array(K + Ks)
    assert exact[0] ** 2 < rigid_eigenvalue(Kt, M)  # below the eigenvalue threshold
    # omega^2 to the round-off of the stiffness's scale, eps tr K / tr M (0.04 rad^2/s^2, 1e-3
    # of the lowest); the rigid-body idealization's own error, (omega / omega_1)^2 of the
    # body's first flexible mode, is 2e-10
    atol = np.finfo(float).eps * stiffness_over_mass(Kt, M)
    res = modes(M, None, Kt, None, 8, checks=("null-space",), solver="sparse")
    np.testing.assert_allclose(res.omega[:6] ** 2, exact ** 2, rtol=1e-9, atol=atol)
    assert res.omega[6] > 5e3 * exact[-1]   # the first flexible mode
    amls = amls_modes(Kt, M, 2.0 * exact[-1], cutoff=5, leaf_size=400)
    np.testing.assert_allclose(amls.lam[:6], exact ** 2, rtol=1e-9, atol=atol)


def test_the_free_body_still_has_six_rigid_body_modes_at_zero():
    K, M = free_box()
    res = modes(M, None, K, None, 8, checks=("null-space",), solver="sparse")
    assert np.all(res.omega[:6] == 0.0)
    assert res.omega[6] > 1e5
    amls = amls_modes(K, M, 1.0, cutoff=5, leaf_size=400)
    assert amls.lam.size == 6 and np.all(amls.lam == 0.0)


def test_craig_bampton_of_a_part_on_soft_springs_keeps_its_suspension_modes():
    """The box held at its last node (the boundary) and by the springs: 60 fixed-interface
    modes reach 3e6 rad/s while the three lowest are the body's rotations about that node on
    the springs, 18 to 49 rad/s. A test relative to the highest mode kept (``1e-10`` of it)
    refused the part as not held; they are the ``3 x 3`` pencil of those rotations."""
    K, M = free_box()
    n = K.shape[0]
    Ks = springs(n, 0.1)
    Kt = sp.csr_array(K + Ks)
    boundary = np.arange(n - 3, n)
    interior = np.setdiff1d(np.arange(n), boundary)
    _, lam, _ = fixed_interface_modes("box", Kt, M, interior, 60)
    _, R = sla.eigh(K.toarray(), M.toarray(), subset_by_index=[0, 5])
    R = R @ sla.null_space(R[boundary])       # the rigid motions that hold the node still
    exact = sla.eigh(R.T @ (Ks @ R), R.T @ (M @ R), eigvals_only=True)
    atol = np.finfo(float).eps * stiffness_over_mass(Kt, M)
    np.testing.assert_allclose(lam[:3], exact, rtol=1e-9, atol=atol)
    assert lam[59] > 1e10 * lam[0]   # beyond the ratio that was refused
