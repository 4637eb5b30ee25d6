r"""The shells and bushings of a Nastran model (:class:`~substruct.case.bdf.BulkData`) as
element matrices on its grids, six coordinates each in basic axes.

* **CQUAD4 / CTRIA3 + PSHELL**: the flat shells of :mod:`substruct.models.shell` (DKQ / DKT
  bending, QM6 / CST membrane, the drilling penalty), membrane from MID1 and bending from MID2
  with :math:`D = \frac{12 I}{T^3} \frac{E_2 T^3}{12 (1 - \nu_2^2)}`; a blank MID1 gives no
  membrane (nor drilling) stiffness, a blank MID2 no bending.  Mass :math:`(\rho T + nsm)`
  per area with the density of MID1 (MID2's if MID1 is blank): lumped (Nastran's default), a
  quarter or a third on the translations of each corner and no rotary inertia; coupled
  (``PARAM,COUPMASS``), the elements' consistent mass with the rotary inertia of the
  thickness.  ``MID3`` blank: Kirchhoff plates (DKQ / DKT), as Nastran's; ``MID3`` given
  (and every PCOMP): Reissner-Mindlin plates (MITC4 / MITC3) of transverse shear stiffness
  per width ``TS/T * T * G3`` (:mod:`substruct.models.mindlin_plate`).
* **CBUSH + PBUSH**: stiffnesses ``K1 - K6`` along the element axes (a coordinate system's,
  or the axis ``GA -> GB`` with the orientation vector), acting at the point ``S`` of the way
  from ``GA`` to ``GB``, joined rigidly to both grids:

  .. math::  d = E_B q_B - E_A q_A, \qquad E_X = \begin{bmatrix} I & -[P - x_X]_\times \\
             0 & I \end{bmatrix}, \qquad K = D^T T^T \mathrm{diag}(K_1 .. K_6)\, T D

  with ``T = diag(R, R)``; a grounded bushing (``GB`` blank) is :math:`T^T \mathrm{diag}(K)
  T` on ``GA``.
"""

from __future__ import annotations

from typing import Iterator

import numpy as np

from substruct.case.bdf_fields import BdfError
from substruct.case.bdf_model import BulkData, BushSpring
from substruct.models.beam import rotation
from substruct.models.shell import ShellTerms, shell_matrices

__all__ = ["plate_matrices", "bush_matrices"]


def plate_matrices(bulk: BulkData, index: dict[int, int]
                   ) -> Iterator[tuple[str, tuple[int, ...], np.ndarray, np.ndarray]]:
    """``(kind, grid indices, K, M)`` of each CQUAD4 and CTRIA3 of ``bulk`` (module
    docstring), ``kind`` ``"quad"`` or ``"triangle"``.

    Raises:
        BdfError: a degenerate, non-convex or warped element, naming its card.
    """
    for plate, sec in bulk.plates:
        X = np.array([bulk.grids[g] for g in plate.nodes])
        m1, m2 = sec.membrane, sec.bending
        main = m1 if m1 is not None else m2
        assert main is not None
        bend_mat = (m2.E, m2.nu) if m2 is not None else None
        try:
            K, M = shell_matrices(X, main.E, main.nu, sec.t, sec.rho,
                                  "consistent" if bulk.coupled else "lumped", sec.nsm,
                                  terms=ShellTerms(bending_material=bend_mat, bend=sec.bend,
                                                   membrane=m1 is not None,
                                                   bending=m2 is not None,
                                                   rotary=bulk.coupled,
                                                   shear=sec.shear))
        except ValueError as err:
            raise BdfError(bulk.source, str(err), line=plate.line, card=plate.kind,
                           ident=plate.id) from None
        kind = "quad" if len(plate.nodes) == 4 else "triangle"
        yield kind, tuple(index[g] for g in plate.nodes), K, M


def _offset(r: np.ndarray) -> np.ndarray:
    E = np.eye(6)
    E[:3, 3:] = -np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])
    return E


def bush_matrices(bulk: BulkData, b: BushSpring) -> tuple[list[int], np.ndarray]:
    """``(grids, K)`` of a CBUSH: ``K`` is 6 x 6 on ``GA`` (grounded) or 12 x 12 on ``GA``,
    ``GB`` (module docstring).

    Raises:
        BdfError: an orientation vector along ``GA -> GB``, naming the card.
    """
    bush = b.bush
    xa = bulk.grids[bush.ga]
    xb = bulk.grids[bush.gb] if bush.gb is not None else xa
    if b.axes is not None:
        R = np.asarray(b.axes, dtype=float)
    else:
        assert b.v is not None
        try:
            R = rotation(xa.tolist(), xb.tolist(), np.asarray(b.v, dtype=float).tolist())
        except ValueError as err:
            raise BdfError(bulk.source, str(err), line=bush.line, card="CBUSH",
                           ident=bush.id) from None
    T = np.kron(np.eye(2), R)
    k = T.T @ np.diag(b.k) @ T
    if bush.gb is None:
        return [bush.ga], k
    P = xa + bush.s * (xb - xa)
    D = np.hstack([-_offset(P - xa), _offset(P - xb)])
    return [bush.ga, bush.gb], D.T @ k @ D
