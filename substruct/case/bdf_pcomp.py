r"""PCOMP, a laminate of plies, as the PSHELL Nastran makes of it (its "equivalent PSHELL",
MSC Nastran Reference Manual, composite shells): classical lamination theory over the plies
``k`` between :math:`z_{k-1}` and :math:`z_k` (from ``Z0``, the bottom surface, default
:math:`-T/2`):

.. math::  A = \sum_k Q_k (z_k - z_{k-1}), \qquad
           B = \tfrac12 \sum_k Q_k (z_k^2 - z_{k-1}^2), \qquad
           D = \tfrac13 \sum_k Q_k (z_k^3 - z_{k-1}^3)

with :math:`Q_k` the plane-stress matrix of ply ``k``'s MAT1 (isotropic, so ``THETA`` has no
effect).  A sum of isotropic plane-stress matrices is isotropic, so :math:`A` and :math:`D`
are those of an isotropic membrane (:math:`\nu_m = A_{12}/A_{11}`,
:math:`E_m = A_{11}(1-\nu_m^2)/T`) and plate (:math:`\nu_b = D_{12}/D_{11}`,
:math:`E_b = 12 D_{11} (1-\nu_b^2)/T^3`) of thickness :math:`T = \sum t_k`: the PSHELL's
MID1 and MID2 with ``12I/T^3 = 1``.  A laminate with membrane-bending coupling
(:math:`B \ne 0`: an offset ``Z0`` or an unsymmetric stack) is refused, as is PSHELL's MID4.
The laminate is a Reissner-Mindlin plate (MITC4 / MITC3, as a PSHELL with MID3) of
transverse shear stiffness per width :math:`S = \tfrac56 \sum_k G_k t_k` (isotropic plies:
the thickness-weighted shear modulus with the homogeneous plate's factor 5/6; for plies of
one material Nastran's default ``TS/T`` of a PSHELL).  Mass per area
:math:`\sum_k \rho_k t_k + NSM`.

Fields: ``PID Z0 NSM SB FT TREF GE LAM / MIDi Ti THETAi SOUTi ...``; a blank ``MIDi`` or
``Ti`` repeats the ply before, a ply with all four fields blank does not exist (Nastran's
rules); ``LAM`` blank (every ply listed) or ``SYM`` (the plies listed are the lower half of a
symmetric stack); ``SB, FT, TREF`` (failure, thermal) are read and not used, a ``GE``
other than 0 (damping) is refused.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from substruct.case.bdf_cards import Mat1
from substruct.case.bdf_fields import RawCard

__all__ = ["Pcomp", "read_pcomp", "laminate"]

#: A coupling ``|B|`` below this fraction of ``A11 T`` is round-off of a symmetric stack.
COUPLING_TOLERANCE = 1e-9


@dataclass(frozen=True)
class Pcomp:
    """PCOMP: ``plies`` ``(mid, t, field index)`` bottom to top (the symmetric half mirrored
    when ``LAM = SYM``), ``z0`` (``None``: :math:`-T/2`), ``nsm``."""

    id: int
    plies: tuple[tuple[int, float, int], ...]
    z0: float | None
    nsm: float
    line: int


def read_pcomp(c: RawCard) -> Pcomp:
    """PCOMP (module docstring).

    Raises:
        BdfError: no ply, a non-positive thickness, LAM other than blank or SYM, a bad SOUT.
    """
    z0 = c.real(1, "Z0") if c.text(1) else None
    nsm = c.real(2, "NSM", 0.0)
    if nsm < 0:
        raise c.error("must not be negative", nsm, "NSM")
    c.real(3, "SB", 0.0)
    ft = c.text(4)
    if ft not in ("", "HILL", "HOFF", "TSAI", "STRN"):
        raise c.error("must be HILL, HOFF, TSAI or STRN", ft, "FT")
    c.real(5, "TREF", 0.0)
    c.no_damping(6, "GE")
    lam = c.text(7)
    if lam not in ("", "SYM"):
        raise c.error("LAM blank (all plies) or SYM is supported (MEM, BEND, SMEAR and "
                      "SMCORE are not)", lam, "LAM")
    plies: list[tuple[int, float, int]] = []
    mid: int | None = None
    t: float | None = None
    for i in range(8, len(c.fields), 4):
        if not any(c.text(i + j) for j in range(4)):
            continue
        n = len(plies) + 1
        mid = c.integer(i, f"MID{n}", mid)
        t = c.real(i + 1, f"T{n}", t)
        if mid <= 0:
            raise c.error("material ids are positive", mid, f"MID{n}")
        if not t > 0:
            raise c.error("must be positive", t, f"T{n}")
        c.real(i + 2, f"THETA{n}", 0.0)  # ply angle: no effect on an isotropic MAT1
        if c.text(i + 3) not in ("", "YES", "NO"):
            raise c.error("must be YES or NO", c.text(i + 3), f"SOUT{n}")
        plies.append((mid, t, i))
    if not plies:
        raise c.error("a PCOMP needs at least one ply", name="MID1")
    if lam == "SYM":
        plies = plies + plies[::-1]
    return Pcomp(c.integer(0, "PID"), tuple(plies), z0, nsm, c.line)


def laminate(p: Pcomp, mats: list[Mat1]) -> tuple[float, tuple[float, float],
                                                   tuple[float, float], float, float, float]:
    r"""The equivalent PSHELL of ``p`` with its plies' materials ``mats`` (module docstring):
    ``(T, (E_m, nu_m), (E_b, nu_b), rho, coupling, S)`` where ``rho`` is the mean density
    :math:`\sum \rho_k t_k / T`, ``coupling`` is :math:`\max |B_{ij}| / (A_{11} T)` and
    ``S`` the transverse shear stiffness per width :math:`\tfrac56 \sum_k G_k t_k`."""
    t = np.array([ply[1] for ply in p.plies])
    T = float(t.sum())
    z = (-T / 2 if p.z0 is None else p.z0) + np.concatenate([[0.0], np.cumsum(t)])
    E = np.array([m.E for m in mats])
    nu = np.array([m.E / (2 * m.G) - 1 for m in mats])
    q11 = E / (1 - nu ** 2)
    q12 = nu * q11
    sums = []
    for power in (1, 2, 3):
        dz = (z[1:] ** power - z[:-1] ** power) / power
        sums.append((float(q11 @ dz), float(q12 @ dz)))
    (a11, a12), (b11, b12), (d11, d12) = sums
    nu_m, nu_b = a12 / a11, d12 / d11
    rho = float(np.array([m.rho for m in mats]) @ t) / T
    coupling = max(abs(b11), abs(b12)) / (a11 * T)
    shear = 5.0 / 6.0 * float(np.array([m.G for m in mats]) @ t)
    return (T, (a11 * (1 - nu_m ** 2) / T, nu_m), (12 * d11 * (1 - nu_b ** 2) / T ** 3, nu_b),
            rho, coupling, shear)
