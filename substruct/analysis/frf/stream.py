r"""Receptances a block of frequencies at a time: where a sweep sends its output when the
output is not to be held whole (``substruct run`` writes each block to the result file as it
is computed).

A sweep given a :class:`FrequencySink` calls ``open(shape, dtype)`` once (the answer: how many
frequencies a block holds), then ``write(start, block)`` for consecutive blocks
``H[start:start + len(block)]``.  :class:`SweepTap` stands between a sweep and the sink that
stores the blocks: as each block passes it

* keeps a copy of the frequencies the checks need (:meth:`SweepTap.keep`), as computed;
* multiplies the block in place by a factor a frequency, ``H[k] <- f_k H[k]`` (a mobility or
  accelerance, :func:`substruct.analysis.frf.quantity.quantity_factor`), when asked;
* takes what the summary and the pictures read: :math:`\max |H|`, the count of values that
  are not finite, the curves ``H[:, i, j]`` of the first :data:`KEPT_PAIRS` outputs x inputs,
  and the whole output when it has at most :data:`SMALL_OUTPUT` values;
* hands the block to the sink.

The memory it adds is the kept frequencies and curves, not a copy of the output.  The
sweep's result is then a :class:`StreamedArray`: the shape of the output, its summary, and
selections read back from the sink.
"""

from __future__ import annotations

from typing import Any, Callable, Protocol

import numpy as np

__all__ = ["FrequencySink", "SweepTap", "StreamedArray", "KEPT_PAIRS", "SMALL_OUTPUT",
           "feed"]

#: The curves ``H[:, i, j]`` kept for ``i, j`` below this (the picture's first 9 pairs and
#: the summary's 6 x 6 peaks are among them).
KEPT_PAIRS = 9
#: Outputs of at most this many values are also kept whole (the tables print them).
SMALL_OUTPUT = 4096


class FrequencySink(Protocol):
    """Where a sweep puts its receptances, a block of whole frequencies at a time."""

    def open(self, shape: tuple[int, ...], dtype: np.dtype) -> int:
        """Start an output of ``shape`` (frequencies first); return the frequencies a block
        holds (at least 1)."""

    def write(self, start: int, block: np.ndarray) -> None:
        """Store ``block`` as ``H[start:start + len(block)]`` (the block is reused after)."""

    def read(self, key: Any) -> np.ndarray:
        """A selection of the stored output, read back."""


class StreamedArray:
    """The output of a sweep whose blocks went to a sink: its shape and summary, and
    selections (``H[:, i, j]``, ``H[k]``) from what was kept or read back from the sink.

    ``np.asarray`` of it reads the whole output back (a full copy: the command never asks for
    it)."""

    def __init__(self, sink: FrequencySink, shape: tuple[int, ...], dtype: np.dtype,
                 peak: float, nonfinite: int, curves: np.ndarray,
                 whole: np.ndarray | None) -> None:
        self.sink = sink
        self.shape = tuple(shape)
        self.dtype = np.dtype(dtype)
        self.ndim = len(self.shape)
        self.size = int(np.prod(self.shape))
        self.nbytes = self.size * self.dtype.itemsize
        #: ``max |H|`` (0 for an empty output) and the number of values that are inf or NaN
        self.peak = peak
        self.nonfinite = nonfinite
        self.curves = curves
        self.whole = whole

    def __len__(self) -> int:
        return self.shape[0]

    def __array__(self, dtype: Any = None, copy: Any = None) -> np.ndarray:
        a = self.whole if self.whole is not None else np.asarray(self.sink.read(()))
        return a if dtype is None else a.astype(dtype)

    def __getitem__(self, key: Any) -> np.ndarray:
        if self.whole is not None:
            return self.whole[key]
        if isinstance(key, tuple) and len(key) == 3 and key[0] == slice(None):
            i, j = np.asarray(key[1]), np.asarray(key[2])
            kept = self.curves.shape[1:]
            if i.shape == j.shape and i.dtype.kind in "iu" and j.dtype.kind in "iu" and \
                    np.all((0 <= i) & (i < kept[0])) and np.all((0 <= j) & (j < kept[1])):
                return self.curves[:, i, j]
        return np.asarray(self.sink.read(key))


class SweepTap:
    """A :class:`FrequencySink` that keeps the checked frequencies and the summary of each
    block, applies ``factor`` (``factor(start, count)``: one number a frequency) in place,
    and passes the block on to ``sink`` (module docstring)."""

    def __init__(self, sink: FrequencySink,
                 factor: Callable[[int, int], np.ndarray] | None = None) -> None:
        self.sink = sink
        self.factor = factor
        self.kept_at = np.zeros(0, dtype=int)
        self.checked = np.zeros((0, 0, 0), dtype=complex)
        self.shape: tuple[int, ...] = (0, 0, 0)
        self.dtype = np.dtype(complex)
        self.peak, self.nonfinite = 0.0, 0
        self.curves = np.zeros((0, 0, 0), dtype=complex)
        self.whole: np.ndarray | None = None

    def keep(self, at: np.ndarray) -> None:
        """Keep a copy of the frequencies ``at`` (indices) as computed, before ``factor``:
        :attr:`checked` ``[m] = H[at[m]]``."""
        self.kept_at = np.asarray(at, dtype=int)

    def open(self, shape: tuple[int, ...], dtype: np.dtype) -> int:
        self.shape, self.dtype = tuple(shape), np.dtype(dtype)
        n, q, p = self.shape
        self.checked = np.empty((self.kept_at.size, q, p), dtype=self.dtype)
        self.curves = np.empty((n, min(q, KEPT_PAIRS), min(p, KEPT_PAIRS)), dtype=self.dtype)
        self.whole = np.empty(self.shape, self.dtype) if n * q * p <= SMALL_OUTPUT else None
        self.peak, self.nonfinite = 0.0, 0
        return self.sink.open(shape, dtype)

    def write(self, start: int, block: np.ndarray) -> None:
        stop = start + block.shape[0]
        for m in np.flatnonzero((self.kept_at >= start) & (self.kept_at < stop)):
            self.checked[m] = block[self.kept_at[m] - start]
        if self.factor is not None:
            f = self.factor(start, block.shape[0])[:, None, None]
            if block.flags.writeable:
                np.multiply(block, f, out=block)
            else:
                block = block * f
        if block.size:
            mag = np.abs(block)
            self.peak = max(self.peak, float(mag.max()))
            self.nonfinite += int(block.size - np.count_nonzero(np.isfinite(mag)))
        q, p = self.curves.shape[1:]
        self.curves[start:stop] = block[:, :q, :p]
        if self.whole is not None:
            self.whole[start:stop] = block
        self.sink.write(start, block)

    def read(self, key: Any) -> np.ndarray:
        return self.sink.read(key)

    def array(self) -> StreamedArray:
        """What the sweep returns as its ``H``."""
        return StreamedArray(self.sink, self.shape, self.dtype, self.peak, self.nonfinite,
                             self.curves, self.whole)


def feed(sink: FrequencySink, H: np.ndarray) -> None:
    """Send a whole ``H`` (computed at once) to ``sink``, a block of views at a time (the
    sweeps that are not computed by blocks: the direct formulations of small models)."""
    rows = max(1, sink.open(H.shape, H.dtype))
    for start in range(0, H.shape[0], rows):
        sink.write(start, H[start:start + rows])
