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
from substruct.builder.frf_part import FrfPart
from substruct.case.frf_files import GRID_DIGITS_RTOL

__all__ = ["FrfPart", "stack", "boolean_rows", "lm_fbs", "generalized_inverse_fbs",
           "couple", "decouple", "common_grid", "GRID_RTOL"]

#: Two grids are the same if they agree to this relative tolerance (the precision of a UFF 58
#: ASCII abscissa: 6 significant digits); the first part's grid is then used.
GRID_RTOL = GRID_DIGITS_RTOL
#: Singular values of ``B Y B^T`` below this fraction of the largest are dropped by the
#: generalized inverse (:func:`generalized_inverse_fbs`).
GENERALIZED_RTOL = 1e-12
#: About this many bytes of receptances a block of frequencies in :func:`lm_fbs` and
#: :func:`couple`.
BLOCK_BYTES = 16 << 20


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
        out.append(replace(p, omega=w.copy(), Y=Yi.reshape(len(w), *p.Y.shape[1:])))
    return w, out


def stack(parts: Sequence[FrfPart], frequencies: slice = slice(None)
          ) -> tuple[np.ndarray, list[str]]:
    """``Y = diag(Y^(s))`` (at the grid's ``frequencies``, all by default) and the stacked
    labels ``"<part>@<label>"``."""
    n = sum(len(p.labels) for p in parts)
    k = len(range(*frequencies.indices(len(parts[0].omega))))
    Y = np.zeros((k, n, n), dtype=complex)
    labels: list[str] = []
    at = 0
    for p in parts:
        m = len(p.labels)
        Y[:, at:at + m, at:at + m] = p.Y[frequencies]
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


def _interface_rows(Y: np.ndarray, B: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The rows' side of :func:`_interface`: ``B`` on its non-zero columns ``nz``, those
    columns, ``B Y B^T`` and ``B Y`` (``Y B^T`` is formed a block at a time by the callers,
    the same products a frequency)."""
    nz = np.flatnonzero(np.any(B != 0, axis=0))
    Bn = B[:, nz]
    BY = Bn @ Y[:, nz, :]  # (k, m, n)
    return Bn, nz, BY[:, :, nz] @ Bn.T, BY


def _blocks(Y: np.ndarray) -> list[slice]:
    """Slices of the frequencies of ``Y``, each about :data:`BLOCK_BYTES` of ``n x n``
    receptances (at least one frequency): the products and differences of a block stay small
    (cache-sized temporaries instead of arrays as large as the whole sweep)."""
    k, n = Y.shape[0], Y.shape[1] * Y.shape[2]
    step = max(1, BLOCK_BYTES // max(1, 16 * n))
    return [slice(s, s + step) for s in range(0, k, step)]


def _solve_interface(BYBt: np.ndarray, BY: np.ndarray) -> np.ndarray:
    """``(B Y B^T)^{-1} B Y`` at every frequency (one batched LU solve)."""
    try:
        return np.linalg.solve(BYBt, BY)
    except np.linalg.LinAlgError:
        raise AnalysisInputError("the interface receptance B Y B^T is singular (redundant "
                                 "interface rows?)") from None


def lm_fbs(Y: np.ndarray, B: np.ndarray) -> np.ndarray:
    r"""LM-FBS coupling at every frequency, by a linear solve:

    .. math::  Y_c = Y - Y B^T (B Y B^T)^{-1} B Y

    (``Y B^T`` times the solution formed a block of frequencies at a time, :func:`_blocks`).

    Args:
        Y: ``(n_omega, n, n)`` stacked (block-diagonal) receptances.
        B: ``m x n`` independent compatibility rows.

    Raises:
        ValueError: ``B Y B^T`` singular at a frequency (redundant rows: use
            :func:`generalized_inverse_fbs`).
    """
    Bn, nz, BYBt, BY = _interface_rows(Y, B)
    X = _solve_interface(BYBt, BY)
    out = np.empty(Y.shape, dtype=np.result_type(Y, X))
    for sl in _blocks(Y):
        np.subtract(Y[sl], (Y[sl][:, :, nz] @ Bn.T) @ X[sl], out=out[sl])
    return out


def generalized_inverse_fbs(Y: np.ndarray, B: np.ndarray, rtol: float = GENERALIZED_RTOL
                            ) -> np.ndarray:
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
    labels = [f"{p.name}@{lab}" for p in same for lab in p.labels]
    B = boolean_rows(labels, pairs)
    Yc = np.empty((len(w), len(labels), len(labels)), dtype=complex)
    worst, scale = 0.0, 0.0
    for sl in _blocks(Yc):  # the stack, both forms and their difference a block at a time:
        # the numbers of lm_fbs and generalized_inverse_fbs on the whole stack (the same
        # operations a frequency), with one sweep-sized array (the answer) instead of three
        Y, _ = stack(same, sl)
        Bn, nz, BYBt, BY = _interface_rows(Y, B)
        YBt = Y[:, :, nz] @ Bn.T
        np.subtract(Y, YBt @ _solve_interface(BYBt, BY), out=Yc[sl])
        Yg = Y - YBt @ (np.linalg.pinv(BYBt, rcond=GENERALIZED_RTOL) @ BY)
        worst = max(worst, float(np.abs(Yg - Yc[sl]).max(initial=0.0)))
        scale = max(scale, float(np.abs(Yc[sl]).max(initial=0.0)))
    return w, Yc, labels, worst / max(scale, 1e-300)


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
