r"""LM-FBS coupling of FRF parts for the outputs and inputs asked for only.

With the parts' receptances stacked block-diagonally, :math:`Y = \operatorname{diag}(Y^{(s)})`,
and the signed Boolean interface :math:`B` (its non-zero columns ``I``, the interface
coordinates), the coupled receptance of eq (15) with ``A = B`` at outputs ``o`` and inputs
``i`` needs only the rows ``o``, the columns ``i`` and the interface:

.. math::  Y_c[o, i] = Y[o, i] - (Y[o, I] B_I^T)\,(B_I Y[I, I] B_I^T)^{-1}\,(B_I Y[I, i]) .

:func:`couple_selected` forms exactly these products, a block of frequencies at a time, taking
the entries of ``Y`` from the parts' own arrays (the stacked ``Y`` is never formed: its
off-diagonal blocks are zero, so ``Y[o, i]`` is added part by part).  The cheap side is formed
first: ``G = Y[o, I] B_I^T`` (``o x n_c``, ``n_c`` the interface rows) and ``X`` from one LU
of the ``n_c x n_c`` interface receptance a frequency (``n_c`` right-hand sides ``B_I Y[I,
i]``); the ``o x i`` answer is then completed a few frequencies at a time
(:data:`CACHE_BYTES`): the rank-``n_c`` product written into the answer, the parts' entries
added and its largest value taken while those frequencies sit in the processor's cache, so
that the answer goes to memory once and no temporary of its size is made.  For every output
and input it does the same operations as :func:`substruct.analysis.frf.coupling.couple` on the
whole stack (the same products of the same numbers), hence the same numbers.

Checks, as the production sweep of finite-element models does
(:mod:`substruct.analysis.frf.production`):

* the generalized-inverse form :math:`(B Y B^T)^+` (:func:`numpy.linalg.pinv`) at
  :func:`check_frequencies` (every frequency of a grid of up to :data:`CHECK_FREQUENCIES`,
  else that many spread evenly, first and last included), for every output and input asked:
  :math:`\delta = \max_{k} |H^+_k - H_k| / \max_{k} |H_k|` over the checked ``k``.  The
  linear solve at every frequency still refuses a singular interface at any frequency.
* the interface compatibility of the coupled responses to the inputs asked for, at every
  frequency: :math:`\max |B_I Y_c[I, i]| / \max |Y_c|`, the maximum of :math:`|Y_c|` over the
  entries computed (``o x i`` and ``I x i``).  With every coordinate an input this is
  :math:`\max |B Y_c| / \max |Y_c|` over the whole coupled receptance; with fewer inputs it
  bounds the columns asked for only.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from substruct.analysis.errors import AnalysisInputError
from substruct.analysis.frf.coupling import (
    BLOCK_BYTES,
    GENERALIZED_RTOL,
    FrfPart,
    boolean_rows,
    common_grid,
)
from substruct.analysis.frf.stream import FrequencySink

__all__ = ["CoupledSelection", "couple_selected", "check_frequencies", "CHECK_FREQUENCIES"]

#: Where a part's entries sit: a run of consecutive indices (a slice) or the indices.
Index = slice | np.ndarray
#: A part's share of a selection: the part, its rows and columns among the selection's,
#: and which of its own coordinates they are.
Piece = tuple[FrfPart, Index, Index, Index, Index]
#: How many frequencies of the grid the generalized-inverse form checks.
CHECK_FREQUENCIES = 32
#: About this many bytes of coupled receptances are completed at a time (within a block of
#: frequencies), so that the product, the parts' entries added to it and the largest value
#: are taken while they sit in the processor's cache.
CACHE_BYTES = 512 << 10


def check_frequencies(count: int) -> np.ndarray:
    """Indices of the frequencies checked on a grid of ``count``: all of them up to
    :data:`CHECK_FREQUENCIES`, else that many spread evenly, the first and last included."""
    if count <= CHECK_FREQUENCIES:
        return np.arange(count)
    return np.unique(np.linspace(0, count - 1, CHECK_FREQUENCIES).round().astype(int))


@dataclass(frozen=True)
class CoupledSelection:
    """The coupled receptances asked for.

    Attributes:
        omega: the grid (the first part's).
        H: ``(n_omega, n_outputs, n_inputs)``, ``H[k, a, b] = Y_c[outputs[a], inputs[b]]``
            (``None`` when the blocks went to a sink).
        agreement: :math:`\\delta` of the generalized-inverse form at ``checked``.
        residual: the interface compatibility of the columns asked for (module docstring).
        checked: the indices of the checked frequencies.
    """

    omega: np.ndarray
    H: np.ndarray | None
    agreement: float
    residual: float
    checked: np.ndarray


def _run(idx: np.ndarray) -> Index:
    """``idx`` as a slice if it is a run of consecutive integers (a view, not a copy)."""
    if len(idx) and np.array_equal(idx, np.arange(idx[0], idx[0] + len(idx))):
        return slice(int(idx[0]), int(idx[0]) + len(idx))
    return idx


class _Stack:
    """The entries of ``Y = diag(Y^(s))`` at given stacked rows and columns, read from the
    parts (zero between parts)."""

    def __init__(self, parts: Sequence[FrfPart]) -> None:
        self.parts = [p for p in parts if p.labels]
        sizes = [len(p.labels) for p in self.parts]
        self.start = np.concatenate([[0], np.cumsum(sizes)]).astype(int)

    def pieces(self, rows: np.ndarray, cols: np.ndarray
               ) -> list[Piece]:
        """Per part: its array, where its rows and columns sit among ``rows`` / ``cols``
        and which of its own coordinates they are (slices where consecutive)."""
        out = []
        for p, s, e in zip(self.parts, self.start[:-1], self.start[1:]):
            r = np.flatnonzero((rows >= s) & (rows < e))
            c = np.flatnonzero((cols >= s) & (cols < e))
            if len(r) and len(c):
                out.append((p, _run(r), _run(c), _run(rows[r] - s), _run(cols[c] - s)))
        return out

    def add(self, out: np.ndarray, sl: slice,
            pieces: list[Piece]) -> None:
        """``out += Y[sl][:, rows][:, :, cols]`` (the parts' blocks only)."""
        for p, r, c, lr, lc in pieces:
            src = _pick(p.Y[sl], lr, lc)
            if isinstance(r, slice) and isinstance(c, slice):
                out[:, r, c] += src
            else:
                out[:, _arr(r)[:, None], _arr(c)[None, :]] += src

    def take(self, sl: slice, k: int, shape: tuple[int, int], pieces: list[Piece]
             ) -> np.ndarray:
        """``Y[sl][:, rows][:, :, cols]``, a new ``(k, *shape)`` array, given the
        :meth:`pieces` of ``rows`` and ``cols``."""
        out = np.zeros((k, *shape), dtype=complex)
        self.add(out, sl, pieces)
        return out


def _arr(idx: Index) -> np.ndarray:
    """A slice of :func:`_run` back as indices."""
    if isinstance(idx, slice):
        return np.arange(idx.start, idx.stop)
    return np.asarray(idx)


def _pick(Y: np.ndarray, r: Index, c: Index) -> np.ndarray:
    """``Y[:, r][:, :, c]`` with one copy at most (a view where both are slices)."""
    if isinstance(r, slice) and isinstance(c, slice):
        return Y[:, r, c]
    return Y[:, _arr(r)[:, None], _arr(c)[None, :]]


def couple_selected(parts: Sequence[FrfPart], pairs: Sequence[tuple[str, str]],
                    outputs: Sequence[str], inputs: Sequence[str],
                    interpolate: str | None = None, sink: FrequencySink | None = None
                    ) -> CoupledSelection:
    """Couple FRF parts joined at ``pairs`` of ``"<part>@<label>"`` coordinates and return
    the coupled receptances of ``outputs`` x ``inputs`` (stacked labels), with the checks of
    the module docstring.

    Given a ``sink``, each block of frequencies goes to it as soon as it is computed and
    checked (blocks of the length its ``open`` answers, in one reused buffer), and the
    result's ``H`` is ``None``: the whole output is never held.

    Raises:
        ValueError: a label not among the parts; grids that differ (:func:`common_grid`).
        AnalysisInputError: the interface receptance ``B Y B^T`` singular at a frequency.
    """
    w, same = common_grid(parts, interpolate)
    labels = [f"{p.name}@{lab}" for p in same for lab in p.labels]
    B = boolean_rows(labels, pairs)
    where = {lab: i for i, lab in enumerate(labels)}
    for lab in [*outputs, *inputs]:
        if lab not in where:
            raise ValueError(f"no coordinate {lab!r} among the FRF parts")
    o = np.array([where[x] for x in outputs], dtype=int)
    i = np.array([where[x] for x in inputs], dtype=int)
    nz = np.flatnonzero(np.any(B != 0, axis=0))
    Bn = B[:, nz]
    k = len(w)
    Y = _Stack(same)
    # where each part's entries sit, found once: Y[o, i], Y[I, I], Y[I, i], Y[o, I]
    oi, II, Ii, oI = Y.pieces(o, i), Y.pieces(nz, nz), Y.pieces(nz, i), Y.pieces(o, nz)
    checked = check_frequencies(k)
    step = max(1, BLOCK_BYTES // max(1, 16 * (len(o) + len(nz)) * (len(i) + len(nz))))
    H: np.ndarray | None = None
    if sink is None:
        H = np.empty((k, len(o), len(i)), dtype=complex)
    else:
        step = max(1, int(sink.open((k, len(o), len(i)), np.dtype(complex))))
        buf = np.empty((min(step, k), len(o), len(i)), dtype=complex)
    # the outputs x inputs a few frequencies at a time, in cache while they are formed,
    # completed and measured: the answer is written to memory once
    inner = max(1, CACHE_BYTES // max(1, 16 * len(o) * len(i)))
    mag = np.empty((min(inner, k), len(o), len(i)))
    worst = scale_checked = residual = scale = 0.0
    for s in range(0, k, step):
        sl = slice(s, min(k, s + step))
        kb = sl.stop - sl.start
        YII, YIi = Y.take(sl, kb, (len(nz), len(nz)), II), Y.take(sl, kb, (len(nz), len(i)), Ii)
        G = Y.take(sl, kb, (len(o), len(nz)), oI) @ Bn.T  # Y[o, I] B_I^T, o x n_c
        BYBt, BYi = (Bn @ YII) @ Bn.T, Bn @ YIi
        try:  # one LU of B Y B^T a frequency, n_c x n_c
            X = np.linalg.solve(BYBt, BYi)
        except np.linalg.LinAlgError:
            raise AnalysisInputError("the interface receptance B Y B^T is singular (redundant "
                                     "interface rows?)") from None
        out = H[sl] if H is not None else buf[:kb]
        negG = -G
        for a in range(0, kb, inner):
            b = min(kb, a + inner)
            # Y[o, i] - G X as (-G) X + Y[o, i], the parts' blocks of Y only: the same
            # numbers (negating a factor negates each product and each rounded sum exactly)
            np.matmul(negG[a:b], X[a:b], out=out[a:b])
            Y.add(out[a:b], slice(s + a, s + b), oi)
            np.abs(out[a:b], out=mag[:b - a])
            scale = max(scale, float(mag[:b - a].max(initial=0.0)))
        YcI = YIi - (YII @ Bn.T) @ X  # the interface rows of Y_c, for the compatibility
        residual = max(residual, float(np.abs(Bn @ YcI).max(initial=0.0)))
        scale = max(scale, float(np.abs(YcI).max(initial=0.0)))
        sel = checked[(checked >= sl.start) & (checked < sl.stop)] - sl.start
        if len(sel):  # the generalized-inverse form at the checked frequencies
            Yoi = np.concatenate([Y.take(slice(s + j, s + j + 1), 1, (len(o), len(i)), oi)
                                  for j in sel])
            Hg = Yoi - G[sel] @ (np.linalg.pinv(BYBt[sel], rcond=GENERALIZED_RTOL) @ BYi[sel])
            worst = max(worst, float(np.abs(Hg - out[sel]).max(initial=0.0)))
            scale_checked = max(scale_checked, float(np.abs(out[sel]).max(initial=0.0)))
        if sink is not None:
            sink.write(sl.start, out)
    return CoupledSelection(w, H, worst / max(scale_checked, 1e-300),
                            residual / max(scale, 1e-300) if len(nz) else 0.0, checked)
