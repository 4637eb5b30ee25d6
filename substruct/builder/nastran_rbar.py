r"""A Nastran RBAR (:class:`~substruct.case.bdf_constraints.Rbar`) as a link of
:mod:`substruct.assembly.links`.

An RBAR is a rigid bar between grids ``A`` and ``B``: its twelve coordinates move with the
bar's rigid motion :math:`q = (u_A, \theta_A)`,

.. math::  \begin{bmatrix} u_A \\ \theta_A \end{bmatrix} = q, \qquad
           \begin{bmatrix} u_B \\ \theta_B \end{bmatrix} =
           \begin{bmatrix} I & -[r]_\times \\ 0 & I \end{bmatrix} q, \qquad r = x_B - x_A,

i.e. the twelve rows ``R`` (12 x 6).  The six independent components (CNA at A, CNB at B)
fix ``q = R_N^{-1} u_N``; each dependent component ``m`` (CMA, CMB) is the row
:math:`u_m - R_m R_N^{-1} u_N = 0`.  When all six independent components are at one grid
(``CNA = 123456``, the common case), these are exactly the rows of an RBE2 from that grid
(:func:`~substruct.assembly.links.rigid_link`), which is used.  Independent components that do
not determine the rigid motion (``R_N`` singular: Nastran's remark that CNA and CNB must
"jointly be capable of representing any general rigid body motion") are refused.
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from substruct.assembly.links import Link, LinkError, NodeRef, mpc, rigid_link
from substruct.case.bdf_constraints import Rbar
from substruct.substructure import Substructure

__all__ = ["RBAR_RANK_TOL", "rbar_rows", "rbar_link"]

#: Smallest singular value of the scaled independent rows ``R_N`` (translations and rotations
#: times the bar's length) relative to its largest, below which CNA and CNB do not determine
#: the rigid motion.
RBAR_RANK_TOL = 1e-9


def rbar_rows(r: np.ndarray) -> np.ndarray:
    """The 12 x 6 rigid-body rows ``R`` of a bar whose end B is at ``r`` from end A (module
    docstring): rows 0-5 the components 1-6 at A, rows 6-11 those at B."""
    skew = np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])
    R = np.zeros((12, 6))
    R[:6] = np.eye(6)
    R[6:9, :3] = np.eye(3)
    R[6:9, 3:] = -skew
    R[9:, 3:] = np.eye(3)
    return R


def rbar_link(subs: Mapping[str, Substructure], name: str, rb: Rbar, positions: np.ndarray,
              link_name: str, frames: np.ndarray | None = None) -> Link:
    """The link of RBAR ``rb`` in substructure ``name`` (module docstring); ``positions``:
    the places of GA and GB (2 x 3, basic); ``frames``: ``diag(F_A, F_A, F_B, F_B)`` (12 x
    12) when a grid has a displacement system (GRID ``CD``,
    :mod:`substruct.models.nastran_cd`): the twelve coordinates are then
    :math:`F^T R q` and CNA, CNB, CMA, CMB are in the grids' CD systems.

    Raises:
        LinkError: CNA and CNB that do not determine the rigid motion, a component a grid
            does not have.
    """
    ends = (NodeRef(name, {"node": rb.ga}), NodeRef(name, {"node": rb.gb}))
    for k in (0, 1):  # all six independent at one grid: the RBE2 rows from it
        if (rb.cna, rb.cnb)[k] == "123456" and frames is None:
            return rigid_link(subs, ends[k], [ends[1 - k]], (rb.cma, rb.cmb)[1 - k],
                              name=link_name)
    r = positions[1] - positions[0]
    R = rbar_rows(r) if frames is None else frames.T @ rbar_rows(r)
    indep = [int(d) - 1 for d in rb.cna] + [6 + int(d) - 1 for d in rb.cnb]
    dep = [int(d) - 1 for d in rb.cma] + [6 + int(d) - 1 for d in rb.cmb]
    length = max(float(np.linalg.norm(r)), 1e-300)
    scale = np.diag([1.0, 1.0, 1.0, length, length, length])  # rotations times the length
    sv = np.linalg.svd(R[indep] @ scale, compute_uv=False)
    if sv[-1] <= RBAR_RANK_TOL * sv[0]:
        raise LinkError(f"{link_name}: CNA {rb.cna or 'blank'} and CNB {rb.cnb or 'blank'} do "
                        "not determine the bar's rigid motion (they must jointly represent "
                        "any rigid-body motion)")
    coef = R[dep] @ np.linalg.inv(R[indep])
    coef[np.abs(coef) <= 1e-14 * max(1.0, float(np.abs(coef).max()))] = 0.0
    parts = []
    for i, m in enumerate(dep):
        terms = [(ends[m // 6], str(m % 6 + 1), 1.0)]
        terms += [(ends[n // 6], str(n % 6 + 1), -float(a)) for n, a in zip(indep, coef[i])
                  if a != 0.0]
        parts.append(mpc(subs, terms, name=link_name))
    return Link.joined(link_name, "rigid", parts)
