r"""Coupling and decoupling of substructures known by their receptances (frequency-based
substructuring, FBS).

Substructures ``s`` with receptances :math:`Y^{(s)}(\omega)` on labelled coordinates are
stacked block-diagonally, :math:`Y = \operatorname{diag}(Y^{(s)})`; the interface is the
signed Boolean compatibility :math:`B u = 0` (one row per pair of coordinates joined, ``+1`` and
``-1``).  With interface forces :math:`-B^T \lambda` the coupled receptance is the
Lagrange-multiplier (LM-FBS) form of eq (15), the constraint read on displacements with ``A = B``:

.. math::  Y_c = Y - Y B^T (B Y B^T)^{-1} B Y ,

solved per frequency without forming an inverse (:func:`lm_fbs`).  The check is the same
formula with the Moore-Penrose generalized inverse :math:`(B Y B^T)^+` computed by an SVD
(:func:`generalized_inverse_fbs`), which also takes redundant compatibility rows.

Decoupling (:func:`decouple`) removes a known substructure ``R`` from an assembly ``AR``: the
assembly and the negated receptance of ``R`` are coupled at the interface (all coordinates of
``R`` joined to those of the assembly, the extended interface),

.. math::  Y_A = \big[ Y - Y B^T (B Y B^T)^{+} B Y \big]_{AA}, \qquad
           Y = \operatorname{diag}(Y_{AR}, -Y_R) .

Frequency grids that differ are refused unless interpolation is asked for
(:func:`common_grid`, ``interpolate: linear``).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Sequence

import numpy as np

from substruct.analysis.errors import AnalysisInputError
from substruct.builder.frf_parts import FrfPart
from substruct.case.frf_files import GRID_DIGITS_RTOL

__all__ = ["FrfPart", "stack", "boolean_rows", "lm_fbs", "generalized_inverse_fbs",
           "couple", "decouple", "common_grid", "GRID_RTOL"]

#: Two grids are the same if they agree to this relative tolerance (the precision of a UFF 58
#: ASCII abscissa: 6 significant digits); the first part's grid is then used.
GRID_RTOL = GRID_DIGITS_RTOL


def common_grid(parts: Sequence[FrfPart], interpolate: str | None = None
                ) -> tuple[np.ndarray, list[FrfPart]]:
    """The parts on one frequency grid (the first part's).

    A part whose ``interpolate`` (or the ``interpolate`` given here, for every part) is
    ``"none"`` is refused if its grid differs (beyond :data:`GRID_RTOL`); ``"linear"``
    interpolates the real and imaginary parts of its receptances onto the first grid (refusing
    frequencies outside its range).

    Raises:
        ValueError: different grids without interpolation, or outside a range with it.
    """
    w = np.asarray(parts[0].omega, dtype=float)
    out = [parts[0]]
    for p in parts[1:]:
        how = p.interpolate if interpolate is None else interpolate
        if how not in ("none", "linear"):
            raise ValueError(f"unknown interpolation {how!r}; expected none or linear")
        same = p.omega.shape == w.shape and np.allclose(p.omega, w, rtol=GRID_RTOL, atol=0)
        if same:
            out.append(replace(p, omega=w.copy()))
            continue
        if how == "none":
            raise ValueError(f"the frequency grids of {parts[0].name} and {p.name} differ "
                             f"({len(w)} vs {len(p.omega)} frequencies); give interpolate: "
                             f"linear to interpolate {p.name} onto the grid of "
                             f"{parts[0].name}")
        lo, hi = float(p.omega.min()), float(p.omega.max())
        if w.min() < lo * (1 - GRID_RTOL) or w.max() > hi * (1 + GRID_RTOL):
            raise ValueError(f"{p.name} covers {lo:g} to {hi:g} rad/s, not the grid of "
                             f"{parts[0].name} ({w.min():g} to {w.max():g}): no extrapolation")
        flat = p.Y.reshape(len(p.omega), -1)
        Yi = np.empty((len(w), flat.shape[1]), dtype=complex)
        for j in range(flat.shape[1]):
            Yi[:, j] = np.interp(w, p.omega, flat[:, j].real) + \
                1j * np.interp(w, p.omega, flat[:, j].imag)
        out.append(FrfPart(p.name, w.copy(), list(p.labels),
                           Yi.reshape(len(w), *p.Y.shape[1:]), p.interpolate))
    return w, out


def stack(parts: Sequence[FrfPart]) -> tuple[np.ndarray, list[str]]:
    """``Y = diag(Y^(s))`` and the stacked labels ``"<part>@<label>"``."""
    n = sum(len(p.labels) for p in parts)
    k = len(parts[0].omega)
    Y = np.zeros((k, n, n), dtype=complex)
    labels: list[str] = []
    at = 0
    for p in parts:
        m = len(p.labels)
        Y[:, at:at + m, at:at + m] = p.Y
        labels += [f"{p.name}@{lab}" for lab in p.labels]
        at += m
    return Y, labels


def boolean_rows(labels: Sequence[str], pairs: Sequence[tuple[str, str]]) -> np.ndarray:
    r"""The signed Boolean compatibility rows: ``u(a) - u(b) = 0`` for each pair ``(a, b)``.

    .. math::  B_{r, a} = 1, \quad B_{r, b} = -1

    Raises:
        ValueError: a label not in ``labels``, or a coordinate joined to itself.
    """
    where = {lab: i for i, lab in enumerate(labels)}
    B = np.zeros((len(pairs), len(labels)))
    for r, (a, b) in enumerate(pairs):
        for lab in (a, b):
            if lab not in where:
                raise ValueError(f"no coordinate {lab!r} among the FRF parts")
        if a == b:
            raise ValueError(f"coordinate {a!r} joined to itself")
        B[r, where[a]] += 1.0
        B[r, where[b]] -= 1.0
    return B


def _interface(Y: np.ndarray, B: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``Y B^T``, ``B Y B^T`` and ``B Y`` using only the columns of ``B`` that are not zero
    (the interface coordinates): ``O(k n m)`` work instead of ``O(k n^2 m)``."""
    nz = np.flatnonzero(np.any(B != 0, axis=0))
    Bn = B[:, nz]
    YBt = Y[:, :, nz] @ Bn.T  # (k, n, m)
    BY = Bn @ Y[:, nz, :]  # (k, m, n)
    return YBt, BY[:, :, nz] @ Bn.T, BY


def lm_fbs(Y: np.ndarray, B: np.ndarray) -> np.ndarray:
    r"""LM-FBS coupling at every frequency, by a linear solve:

    .. math::  Y_c = Y - Y B^T (B Y B^T)^{-1} B Y

    Args:
        Y: ``(n_omega, n, n)`` stacked (block-diagonal) receptances.
        B: ``m x n`` independent compatibility rows.

    Raises:
        ValueError: ``B Y B^T`` singular at a frequency (redundant rows: use
            :func:`generalized_inverse_fbs`).
    """
    YBt, BYBt, BY = _interface(Y, B)
    try:
        X = np.linalg.solve(BYBt, BY)
    except np.linalg.LinAlgError:
        raise AnalysisInputError("the interface receptance B Y B^T is singular (redundant interface "
                         "rows?)") from None
    return Y - YBt @ X


def generalized_inverse_fbs(Y: np.ndarray, B: np.ndarray, rtol: float = 1e-12) -> np.ndarray:
    r"""The same coupling with the Moore-Penrose inverse of the interface receptance:

    .. math::  Y_c = Y - Y B^T (B Y B^T)^{+} B Y

    (:func:`numpy.linalg.pinv`, singular values below ``rtol`` of the largest dropped), so
    that redundant compatibility rows are taken.
    """
    YBt, BYBt, BY = _interface(Y, B)
    return Y - YBt @ (np.linalg.pinv(BYBt, rcond=rtol) @ BY)


def couple(parts: Sequence[FrfPart], pairs: Sequence[tuple[str, str]],
           interpolate: str | None = None) -> tuple[np.ndarray, np.ndarray, list[str], float]:
    """Couple FRF parts joined at ``pairs`` of ``"<part>@<label>"`` coordinates.

    Returns:
        ``(omega, Y_c, labels, agreement)``: the coupled receptances of every stacked
        coordinate by :func:`lm_fbs`, and ``max |Y_c^+ - Y_c| / max |Y_c|`` against
        :func:`generalized_inverse_fbs`.
    """
    w, same = common_grid(parts, interpolate)
    Y, labels = stack(same)
    B = boolean_rows(labels, pairs)
    Yc = lm_fbs(Y, B)
    Yg = generalized_inverse_fbs(Y, B)
    scale = max(float(np.abs(Yc).max(initial=0.0)), 1e-300)
    return w, Yc, labels, float(np.abs(Yg - Yc).max(initial=0.0) / scale)


def decouple(assembly: FrfPart, known: FrfPart, pairs: Sequence[tuple[str, str]],
             keep: Sequence[str] | None = None, interpolate: str | None = None) -> FrfPart:
    r"""Remove the substructure ``known`` from the measured ``assembly``.

    ``pairs`` join each coordinate of ``known`` to the coordinate of ``assembly`` where it
    sits: ``(label in assembly, label in known)`` (every coordinate of ``known``: the extended
    interface).  The result is the receptance of the rest of the assembly on the assembly's
    coordinates ``keep`` (default: those not joined; the interface coordinates, which belong
    to the rest too, may be kept; those inside ``known`` have no meaning there).

    .. math::  Y_A = \big[ Y - Y B^T (B Y B^T)^{+} B Y \big]_{AA}, \quad
               Y = \operatorname{diag}(Y_{AR}, -Y_R)
    """
    neg = replace(known, Y=-known.Y)
    w, (asm, kn) = common_grid([assembly, neg], interpolate)
    Y, labels = stack([asm, kn])
    B = boolean_rows(labels, [(f"{asm.name}@{a}", f"{kn.name}@{b}") for a, b in pairs])
    Yd = generalized_inverse_fbs(Y, B)
    joined = {a for a, _ in pairs}
    names = [lab for lab in asm.labels if lab not in joined] if keep is None else list(keep)
    idx = [asm.index(lab) for lab in names]
    return FrfPart(f"{asm.name}-{kn.name}", w, names, Yd[:, idx][:, :, idx], asm.interpolate)
