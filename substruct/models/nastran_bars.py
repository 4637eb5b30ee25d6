r"""The CBAR and CBEAM elements of a Nastran model (module docstring of
:mod:`substruct.models.nastran` for their semantics): one element at a time
(:func:`bar_matrices`) and all at once (:func:`bar_blocks`), the batch taking its stiffness and
consistent mass from :func:`substruct.models.beam_batch.beam_matrices_batch`.

The batch maps each element onto a :class:`~substruct.models.beam_batch.BeamBatch` between its
offset ends :math:`a = x_A + w_A`, :math:`b = x_B + w_B`: ``Iz = I1``, ``ky = K1`` (plane 1,
the orientation vector's), ``Iy = I2``, ``kz = K2``, and the mass per length
:math:`\mu = \rho A + nsm` as a density :math:`\mu / A`, with the polar inertia chosen so that
:math:`(\mu / A)\, I_p = \rho (I_1 + I_2)` (CBEAM's torsional inertia; 0 for a CBAR's lumped
mass).  Then, with :math:`T = \mathrm{diag}(R, R, R, R)` and the rigid offsets
:math:`E_o = [I, -[w_A]_\times; 0, I] \oplus [I, -[w_B]_\times; 0, I]`,

.. math::  K_e = E_o^T (T^T K_l T) E_o, \qquad M_e = E_o^T (T^T M_l T) E_o.

* Coupled mass without shear flexibility is the batch's consistent mass.  With it, the batch's
  Timoshenko mass holds a rotary inertia :math:`\rho I \int N_\theta^T N_\theta` that Nastran's
  coupled mass has not; the mass is linear in ``(rho A, rho I)`` at fixed
  :math:`\phi = 12 E I / (K G A L^2)`, so two evaluations, with ``(E, I)`` and ``(E/2, 2 I)``,
  give it without that term: :math:`M = 2 M(E, I) - M(E/2, 2I)`.
* Lumped mass is diagonal in the element's axes: :math:`\mu L / 2` on each end's
  translations (the same in any axes) and, for CBEAM, :math:`\rho (I_1 + I_2) L / 2` on its
  twist, :math:`T^T` of it being :math:`\rho (I_1 + I_2) L/2\; e_x e_x^T` on the rotations.
* Elements with pin flags, without area (``A = 0``), with a shear factor 0 in one plane only,
  or that the batch finds degenerate (no length, an orientation along the axis) are made one
  at a time by :func:`bar_matrices` (the last to name the card in the error).
"""

from __future__ import annotations

import numpy as np

from substruct.case.bdf_cards import Bar
from substruct.case.bdf_fields import BdfError
from substruct.case.bdf_model import BdfSection, BulkData
from substruct.models.beam import bending_matrices, release, rotation
from substruct.models.beam_batch import BeamBatch, beam_matrices_batch

__all__ = ["bar_matrices", "bar_element_matrices", "bar_blocks"]


def _skew(r: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


def bar_matrices(xa: np.ndarray, xb: np.ndarray, v: np.ndarray, s: BdfSection, coupled: bool,
                 shear: bool, released: list[int], wa: np.ndarray, wb: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness and mass (12 x 12, basic) of a CBAR/CBEAM between grids at ``xa``, ``xb`` with
    end offsets ``wa``, ``wb`` (module docstring of :mod:`substruct.models.nastran`)."""
    a, b = xa + wa, xb + wb
    R = rotation(a.tolist(), b.tolist(), v.tolist())
    L = float(np.linalg.norm(b - a))
    E, G = s.mat.E, s.mat.G
    mu = s.mat.rho * s.A + s.nsm
    K, M = np.zeros((12, 12)), np.zeros((12, 12))
    bar = np.array([[1.0, -1.0], [-1.0, 1.0]])
    pair = np.array([[2.0, 1.0], [1.0, 2.0]]) / 6.0
    for dof, stiff in ((0, E * s.A), (3, G * s.J)):
        K[np.ix_([dof, dof + 6], [dof, dof + 6])] = stiff / L * bar
    if coupled:
        M[np.ix_([0, 6], [0, 6])] = mu * L * pair
        M[np.ix_([3, 9], [3, 9])] = s.mat.rho * (s.I1 + s.I2) * L * pair
    for vv, t, I, sign, k in ((1, 5, s.I1, 1.0, s.kshear[0]),
                              (2, 4, s.I2, -1.0, s.kshear[1])):
        kga = k * G * s.A if shear and k > 0 else None
        Kb, Mb = bending_matrices(L, E * I, kga if kga else None, mu, 0.0)
        D = np.diag([1.0, sign, 1.0, sign])
        idx = np.ix_([vv, t, vv + 6, t + 6], [vv, t, vv + 6, t + 6])
        K[idx] = D @ Kb @ D
        if coupled:
            M[idx] = D @ Mb @ D
    if not coupled:
        M[[0, 1, 2, 6, 7, 8], [0, 1, 2, 6, 7, 8]] = mu * L / 2
        if s.beam:  # CBEAM's lumped mass holds the torsional inertia, CBAR's does not
            M[[3, 9], [3, 9]] = s.mat.rho * (s.I1 + s.I2) * L / 2
    K, M = release(K, M, released)
    T = np.kron(np.eye(4), R)
    Eo = np.eye(12)
    Eo[:3, 3:6] = -_skew(wa)
    Eo[6:9, 9:12] = -_skew(wb)
    TE = T @ Eo
    return TE.T @ K @ TE, TE.T @ M @ TE


def _ends(bulk: BulkData, bar: Bar) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    xa, xb = bulk.grids[bar.nodes[0]], bulk.grids[bar.nodes[1]]
    v = np.asarray(bar.v) if bar.g0 is None else bulk.grids[bar.g0] - xa
    return np.asarray(xa, dtype=float), np.asarray(xb, dtype=float), np.asarray(v, dtype=float)


def bar_element_matrices(bulk: BulkData, bar: Bar, s: BdfSection
                         ) -> tuple[np.ndarray, np.ndarray]:
    """:func:`bar_matrices` of one element of ``bulk``.

    Raises:
        BdfError: no length, an orientation along the axis, releases leaving a mechanism,
            naming the card.
    """
    xa, xb, v = _ends(bulk, bar)
    released = [int(c) - 1 for c in bar.pa] + [6 + int(c) - 1 for c in bar.pb]
    try:
        return bar_matrices(xa, xb, v, s, bulk.coupled, s.shear, released,
                            np.asarray(bar.wa), np.asarray(bar.wb))
    except ValueError as err:
        raise BdfError(bulk.source, str(err), line=bar.line, card=bar.kind,
                       ident=bar.id) from None


def bar_blocks(bulk: BulkData) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness and mass ``(n, 12, 12)`` in basic axes of the ``n`` CBAR/CBEAM of ``bulk`` in
    order, each equal to :func:`bar_element_matrices` to round-off (module docstring).

    Raises:
        BdfError: as :func:`bar_element_matrices`.
    """
    n = len(bulk.bars)
    K, M = np.zeros((n, 12, 12)), np.zeros((n, 12, 12))
    if n == 0:
        return K, M
    ends = [_ends(bulk, bar) for bar, _ in bulk.bars]
    secs = [s for _, s in bulk.bars]
    wa = np.array([bar.wa for bar, _ in bulk.bars], dtype=float)
    wb = np.array([bar.wb for bar, _ in bulk.bars], dtype=float)

    def col(f) -> np.ndarray:
        return np.array([f(s) for s in secs], dtype=float)

    A, I1, I2, J, nsm = col(lambda s: s.A), col(lambda s: s.I1), col(lambda s: s.I2), \
        col(lambda s: s.J), col(lambda s: s.nsm)
    E, G, rho = col(lambda s: s.mat.E), col(lambda s: s.mat.G), col(lambda s: s.mat.rho)
    k1, k2 = col(lambda s: s.kshear[0]), col(lambda s: s.kshear[1])
    shear = np.array([s.shear for s in secs]) & (k1 > 0) & (k2 > 0)
    beam = np.array([s.beam for s in secs])
    one_plane = np.array([s.shear for s in secs]) & ((k1 > 0) != (k2 > 0))
    pinned = np.array([bool(bar.pa or bar.pb) for bar, _ in bulk.bars])
    batch = ~pinned & ~one_plane & (A > 0)
    mu = rho * A + nsm
    dens = np.where(batch, mu / np.where(A > 0, A, 1.0), 0.0)
    tors = rho * (I1 + I2)
    Ip = np.where(dens > 0, tors / np.where(dens > 0, dens, 1.0), 0.0)
    a = np.array([e[0] for e in ends]) + wa
    b = np.array([e[1] for e in ends]) + wb
    v = np.array([e[2] for e in ends])

    def run(scale: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return beam_matrices_batch(BeamBatch(
            xa=a, xb=b, v=v, E=E / scale, G=G, rho=dens, A=np.where(A > 0, A, 1.0),
            Iy=I2 * scale, Iz=I1 * scale, J=J, Ip=Ip, ky=k1, kz=k2, timoshenko=shear),
            mass="consistent")

    Kg, Mg, ok = run(1.0)
    batch &= ok & ((dens > 0) | (tors == 0))
    if bulk.coupled:
        if shear.any():  # the rotary inertia of bending taken out by linearity
            Mg = np.where(shear[:, None, None], 2 * Mg - run(2.0)[1], Mg)
    else:
        L = np.linalg.norm(b - a, axis=1)
        Mg = np.zeros_like(Kg)
        half = (mu * L / 2)[:, None]
        for end in (0, 6):
            Mg[:, end + np.arange(3), end + np.arange(3)] = half
        ex = (b - a) / np.where(L > 0, L, 1.0)[:, None]
        twist = np.where(beam, tors * L / 2, 0.0)[:, None, None] * ex[:, :, None] * \
            ex[:, None, :]
        Mg[:, 3:6, 3:6] = twist
        Mg[:, 9:12, 9:12] = twist
    Eo = np.tile(np.eye(12), (n, 1, 1))
    for r, w in ((slice(0, 3), wa), (slice(6, 9), wb)):
        c = slice(r.start + 3, r.stop + 3)
        Eo[:, r, c] = -np.stack([np.zeros(n), -w[:, 2], w[:, 1], w[:, 2], np.zeros(n), -w[:, 0],
                                 -w[:, 1], w[:, 0], np.zeros(n)], axis=1).reshape(n, 3, 3)
    K[:] = np.einsum("nji,njk,nkl->nil", Eo, Kg, Eo, optimize=True)
    M[:] = np.einsum("nji,njk,nkl->nil", Eo, Mg, Eo, optimize=True)
    for e in np.flatnonzero(~batch):
        bar, s = bulk.bars[e]
        K[e], M[e] = bar_element_matrices(bulk, bar, s)
    return K, M
