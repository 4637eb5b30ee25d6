r"""Coupling and decoupling at virtual points, with a regularised interface inversion and
interface weakening.

A part after the virtual point transformation (:mod:`substruct.analysis.frf.virtual_point`) has
receptances from its inputs (virtual-point loads and impacts that pass through) to its outputs
(virtual-point motions and sensors that pass through): :class:`VpPart`, not square.  Parts
are stacked block-diagonally and joined by signed Boolean rows on the virtual-point
coordinates: :math:`B_u` (compatibility, on the outputs) and :math:`B_f` (equilibrium, on the
inputs).  The coupled receptance is the LM-FBS form

.. math::  Y_c = Y - Y B_f^T \, (B_u Y B_f^T)^{\dagger} \, B_u Y ,

which needs only the receptances from the inputs and the interface to the outputs and the
interface, so the stacked ``Y`` is embedded in a square one on the union of a part's labels
(entries from an output-only row to an input-only column are never used).  With
:math:`B_u = B_f` and no regularisation it is :func:`substruct.analysis.frf.coupling.lm_fbs`
itself, checked by :func:`~substruct.analysis.frf.coupling.generalized_inverse_fbs`.

**Interface weakening** drops chosen virtual-point coordinates (e.g. the rotations, which
impacts excite poorly) from compatibility (rows of :math:`B_u`) or equilibrium (rows of
:math:`B_f`); when the two differ, :math:`B_u Y B_f^T` is rectangular and its inverse is the
(regularised) pseudo-inverse.

**Regularisation** of the interface inversion (:class:`Regularisation`), at each frequency from
the SVD :math:`Z = B_u Y B_f^T = U \Sigma V^H`:

* ``tsvd``: :math:`Z^\dagger = \sum_{\sigma_r > \tau \sigma_1} v_r u_r^H / \sigma_r` with the
  stated rule :math:`\tau` = ``rtol`` (a singular value below ``rtol`` times the largest is
  noise: choose ``rtol`` about the relative noise level of the data), or the ``rank`` largest;
* ``tikhonov``: :math:`Z^\dagger = V \,\mathrm{diag}(\sigma_r / (\sigma_r^2 + \lambda^2))\, U^H`,
  :math:`\lambda = \alpha\, \sigma_1` with ``alpha`` given.

**Singular-vector interface reduction** (``reduction``,
:mod:`substruct.analysis.frf.vp_reduction`) replaces :math:`B_u`, :math:`B_f` by their
projections on the dominant singular vectors of :math:`Z` over the band before the inversion.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from substruct.analysis.frf.coupling import generalized_inverse_fbs, lm_fbs
from substruct.analysis.frf.virtual_point import VirtualPointTransform
from substruct.analysis.frf.vp_reduction import InterfaceReduction, reduce_rows

#: The components of a virtual point that are rotations.
ROTATIONS = ("rx", "ry", "rz")

__all__ = ["ROTATIONS", "VpPart", "Regularisation", "regularised_inverse", "interface_fbs",
           "vp_part", "couple_virtual_points", "decouple_virtual_points", "CoupledVp"]


@dataclass(frozen=True)
class VpPart:
    """Receptances from inputs to outputs of a part (after a virtual point transformation).

    Attributes:
        name: the part's name (labels are stacked as ``"<name>@<label>"``).
        omega: circular frequencies (rad/s).
        out_labels, in_labels: row and column labels (virtual-point coordinates in both).
        Y: ``(n_omega, len(out_labels), len(in_labels))``.
    """

    name: str
    omega: np.ndarray
    out_labels: list[str]
    in_labels: list[str]
    Y: np.ndarray

    def __post_init__(self) -> None:
        shape = (len(self.omega), len(self.out_labels), len(self.in_labels))
        if self.Y.shape != shape:
            raise ValueError(f"{self.name}: receptances of shape {list(self.Y.shape)}, "
                             f"expected {list(shape)}")
        for labels in (self.out_labels, self.in_labels):
            if len(set(labels)) != len(labels):
                raise ValueError(f"{self.name}: labels repeated")

    def block(self, outs: Sequence[str], ins: Sequence[str]) -> np.ndarray:
        """``Y[:, outs, ins]`` by label."""
        for lab in [*outs, *ins]:
            if lab not in self.out_labels and lab not in self.in_labels:
                raise ValueError(f"{self.name} has no coordinate {lab!r}")
        i = [self.out_labels.index(o) for o in outs]
        j = [self.in_labels.index(c) for c in ins]
        return self.Y[:, i][:, :, j]


def vp_part(name: str, omega: np.ndarray, vpt: VirtualPointTransform, Y: np.ndarray) -> VpPart:
    r"""The part measured with receptances ``Y`` (sensors x impacts of ``vpt``), transformed:
    :math:`Y_{qm} = T_u Y T_f^T`."""
    return VpPart(name, np.asarray(omega, dtype=float), list(vpt.out_labels),
                  list(vpt.in_labels), vpt.apply(Y))


@dataclass(frozen=True)
class Regularisation:
    """How the interface receptance is inverted (module docstring).

    Attributes:
        kind: ``"none"`` (a solve, or the pseudo-inverse to round-off if rectangular),
            ``"tsvd"`` or ``"tikhonov"``.
        rtol: ``tsvd``: singular values at or below ``rtol`` times the largest are dropped.
        rank: ``tsvd``: keep this many singular values instead (``None``: by ``rtol``).
        alpha: ``tikhonov``: :math:`\\lambda = \\alpha \\sigma_1`.
    """

    kind: str = "none"
    rtol: float = 1e-12
    rank: int | None = None
    alpha: float = 0.0

    def __post_init__(self) -> None:
        if self.kind not in ("none", "tsvd", "tikhonov"):
            raise ValueError(f"regularisation is none, tsvd or tikhonov, got {self.kind!r}")
        if not (np.isfinite(self.rtol) and 0 <= self.rtol < 1):
            raise ValueError(f"rtol must be in [0, 1), got {self.rtol!r}")
        if not (np.isfinite(self.alpha) and self.alpha >= 0):
            raise ValueError(f"alpha must be finite and >= 0, got {self.alpha!r}")
        if self.rank is not None and (isinstance(self.rank, bool) or self.rank < 1):
            raise ValueError(f"rank must be a positive integer, got {self.rank!r}")


def regularised_inverse(Z: np.ndarray, reg: Regularisation) -> np.ndarray:
    r"""The regularised inverse :math:`Z^\dagger` of ``(k, m, p)`` matrices, frequency by
    frequency from the SVD (module docstring; ``none``: singular values below ``1e-12``
    of the largest dropped)."""
    U, s, Vh = np.linalg.svd(Z, full_matrices=False)
    s1 = s[:, :1]
    if reg.kind == "tikhonov":
        lam = reg.alpha * s1
        g = s / np.maximum(s ** 2 + lam ** 2, 1e-300)
    else:
        keep = s > (reg.rtol if reg.kind == "tsvd" else 1e-12) * s1
        if reg.kind == "tsvd" and reg.rank is not None:
            keep = np.arange(s.shape[1])[None, :] < reg.rank
        g = np.where(keep, 1.0 / np.where(keep, s, 1.0), 0.0)
    return np.conj(np.swapaxes(Vh, 1, 2)) @ (g[:, :, None] * np.conj(np.swapaxes(U, 1, 2)))


def interface_fbs(Y: np.ndarray, Bu: np.ndarray, Bf: np.ndarray,
                  reg: Regularisation = Regularisation(), su: np.ndarray | None = None,
                  sf: np.ndarray | None = None,
                  reduction: InterfaceReduction | None = None) -> np.ndarray:
    r""":math:`Y_c = Y - Y B_f^T (B_u Y B_f^T)^{\dagger} B_u Y` at every frequency, ``Y``
    square ``(k, n, n)``.  With ``Bu`` equal to ``Bf`` and ``reg.kind == "none"`` it is
    :func:`~substruct.analysis.frf.coupling.lm_fbs` (a linear solve).

    ``su``, ``sf`` scale the interface rows before the regularised inversion, so that its
    singular values compare quantities of one unit:
    :math:`Z^\dagger = S_f (S_u Z S_f)^\dagger S_u` (a rotation row scaled by a length
    ``L``: :math:`L\theta` and :math:`m / L` have the units of a displacement and a force).
    ``reduction`` first projects the scaled rows on the dominant singular vectors of
    :math:`S_u Z S_f` over the band (:func:`~substruct.analysis.frf.vp_reduction.reduce_rows`;
    the reduced rows are already scaled).
    """
    a = np.ones(len(Bu)) if su is None else np.asarray(su, dtype=float)
    b = np.ones(len(Bf)) if sf is None else np.asarray(sf, dtype=float)
    if reduction is not None:
        Bu, Bf = reduce_rows(Bu, Bf, Bu @ Y @ Bf.T, a, b, reduction)
        a, b = np.ones(len(Bu)), np.ones(len(Bf))
    elif reg.kind == "none" and Bu.shape == Bf.shape and np.array_equal(Bu, Bf):
        return lm_fbs(Y, Bu)
    YBt = Y @ Bf.T
    BY = Bu @ Y
    Zs = a[None, :, None] * (BY @ Bf.T) * b[None, None, :]
    inv = b[None, :, None] * regularised_inverse(Zs, reg) * a[None, None, :]
    return Y - YBt @ (inv @ BY)


def _embed(parts: Sequence[VpPart]) -> tuple[np.ndarray, list[str], list[int], list[int]]:
    """The square stacked ``Y`` on every part's labels, and the indices of the outputs and
    the inputs in it."""
    labels: list[str] = []
    rows: list[int] = []
    cols: list[int] = []
    for p in parts:
        union = list(dict.fromkeys([*p.out_labels, *p.in_labels]))
        at = len(labels)
        rows += [at + union.index(o) for o in p.out_labels]
        cols += [at + union.index(c) for c in p.in_labels]
        labels += [f"{p.name}@{u}" for u in union]
    Y = np.zeros((len(parts[0].omega), len(labels), len(labels)), dtype=complex)
    r0 = c0 = 0
    for p in parts:
        ri, ci = rows[r0:r0 + len(p.out_labels)], cols[c0:c0 + len(p.in_labels)]
        Y[:, np.asarray(ri)[:, None], np.asarray(ci)[None, :]] = p.Y
        r0, c0 = r0 + len(ri), c0 + len(ci)
    return Y, labels, rows, cols


def _rows(labels: list[str], pairs: Sequence[tuple[str, str]], drop: Sequence[str],
          allowed: set[str], what: str, length: float) -> tuple[np.ndarray, np.ndarray]:
    """The signed Boolean rows of the pairs not dropped, and each row's scale (``length``
    for a rotation, ``1`` otherwise)."""
    where = {lab: i for i, lab in enumerate(labels)}
    kept = [(a, b) for a, b in pairs if not _dropped(a, drop)]
    scale = np.array([length if a.rsplit(":", 1)[-1] in ROTATIONS else 1.0 for a, _ in kept])
    B = np.zeros((len(kept), len(labels)))
    for r, (a, b) in enumerate(kept):
        for lab in (a, b):
            if lab not in allowed:
                raise ValueError(f"{lab!r} is not a coordinate measured as {what} in both "
                                 f"directions (a virtual-point coordinate)")
        B[r, where[a]] += 1.0
        B[r, where[b]] -= 1.0
    return B, scale


def _dropped(label: str, drop: Sequence[str]) -> bool:
    return label in drop or label.rsplit(":", 1)[-1] in drop


@dataclass(frozen=True)
class CoupledVp:
    """A coupled (or decoupled) result: the receptances and the check against the
    generalized-inverse form (``nan`` when regularised or weakened: no reference)."""

    part: VpPart
    agreement: float


def couple_virtual_points(parts: Sequence[VpPart], pairs: Sequence[tuple[str, str]],
                          reg: Regularisation = Regularisation(),
                          weaken_compatibility: Sequence[str] = (),
                          weaken_equilibrium: Sequence[str] = (),
                          name: str = "coupled", length: float = 1.0,
                          check: bool = True,
                          reduction: InterfaceReduction | None = None) -> CoupledVp:
    r"""Couple parts joined at ``pairs`` of ``"<part>@<vp>:<c>"`` coordinates (module
    docstring).  ``weaken_*`` name coordinates (a stacked label, or a component such as
    ``"rx"``, matched against a pair's first label) dropped from compatibility or equilibrium.
    ``length`` scales the rotation rows for the regularised inversion (:func:`interface_fbs`;
    a length of the joint, such as the distance of its sensors from the virtual point; it
    scales them for the ``reduction`` to singular vectors too).

    Returns:
        The coupled receptances from every stacked input to every stacked output, and, without
        regularisation or weakening and with ``check``, ``max |Y_c^+ - Y_c| / max |Y_c|``
        against :func:`~substruct.analysis.frf.coupling.generalized_inverse_fbs` (``nan``
        otherwise; the check doubles the time).

    Raises:
        ValueError: grids that differ, a label that is not a virtual-point coordinate, every
            row dropped, a singular interface without regularisation.
    """
    w = parts[0].omega
    for p in parts[1:]:
        if p.omega.shape != w.shape or not np.allclose(p.omega, w, rtol=1e-12, atol=0):
            raise ValueError(f"the frequency grids of {parts[0].name} and {p.name} differ")
    Y, labels, rows, cols = _embed(parts)
    both = {labels[i] for i in rows} & {labels[j] for j in cols}
    if not (np.isfinite(length) and length > 0):
        raise ValueError(f"length must be finite and positive, got {length!r}")
    Bu, su = _rows(labels, pairs, weaken_compatibility, both, "output and input", length)
    Bf, sf = _rows(labels, pairs, weaken_equilibrium, both, "output and input", length)
    if not pairs:
        raise ValueError("no connection between the virtual points: nothing couples the parts")
    if not len(Bu) or not len(Bf):
        raise ValueError("every interface row is dropped by the weakening")
    Yc = interface_fbs(Y, Bu, Bf, reg, su, sf, reduction)
    agreement = float("nan")
    if check and reg.kind == "none" and reduction is None and np.array_equal(Bu, Bf):
        Yg = generalized_inverse_fbs(Y, Bu)[:, rows][:, :, cols]
        ref = Yc[:, rows][:, :, cols]
        agreement = float(np.abs(Yg - ref).max() / max(float(np.abs(ref).max()), 1e-300))
    out = VpPart(name, w, [labels[i] for i in rows], [labels[j] for j in cols],
                 Yc[:, rows][:, :, cols])
    return CoupledVp(out, agreement)


def decouple_virtual_points(assembly: VpPart, known: VpPart, pairs: Sequence[tuple[str, str]],
                            reg: Regularisation = Regularisation("tsvd", rtol=1e-12),
                            weaken: Sequence[str] = ()) -> CoupledVp:
    r"""Remove the part ``known`` from the ``assembly`` joined at ``pairs``
    ``(label in assembly, label in known)``, every coordinate of ``known`` joined (the
    extended interface):

    .. math::  Y_A = \big[ Y - Y B^T (B Y B^T)^{\dagger} B Y \big]_{AA}, \quad
               Y = \operatorname{diag}(Y_{AR}, -Y_R)

    The result has the assembly's labels (those at the interface belong to the remaining
    part too).  ``weaken`` drops coordinates from both compatibility and equilibrium.
    """
    neg = VpPart(known.name, known.omega, known.out_labels, known.in_labels, -known.Y)
    full = [(f"{assembly.name}@{a}", f"{known.name}@{b}") for a, b in pairs]
    res = couple_virtual_points([assembly, neg], full, reg, weaken, weaken,
                                f"{assembly.name}-{known.name}")
    n_o, n_i = len(assembly.out_labels), len(assembly.in_labels)
    p = res.part
    out = VpPart(p.name, p.omega, list(assembly.out_labels), list(assembly.in_labels),
                 p.Y[:, :n_o, :n_i])
    return CoupledVp(out, res.agreement)
