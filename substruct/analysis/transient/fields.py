r"""The full displacement fields a transient run stores every ``field_every`` steps
(``Transient.snapshots``): held whole in memory, or handed to a sink a block of instants at a
time as they are recorded (the result file of ``substruct run``, ``/transient/snapshots``), so
that a run with a long field history holds one block, never the history.

The stored instants are known before the run: the recorder sees step 0, every ``e``-th step
and the last one (:func:`~substruct.analysis.transient.integrators.integrate`), and keeps the
field at those of them that are multiples of ``f = field_every``,

.. math::  S = \{\, k \in \{0\} \cup \{ j e : 1 \le j e \le N \} \cup \{N\}
           \;:\; k \bmod f = 0 \,\}

(:func:`field_steps`), so the shape of the output, :math:`|S| \times n`, is given to the sink
(``open(shape, dtype)``, which answers how many instants a block holds) before the first
block.  Each block is then ``write(start, block)`` (rows ``start .. start + len(block)``), as
a receptance sweep's blocks of frequencies are
(:class:`substruct.analysis.frf.stream.FrequencySink`; the result file's
:class:`~substruct.io.blocks.DatasetSink` takes both).  A field is copied once, into its row of
the block (or of the whole array): the values are those recorded, bit for bit, either way.
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np

__all__ = ["FieldSink", "StoredFields", "FieldStore", "field_steps"]


class FieldSink(Protocol):
    """Where a run puts its stored fields, a block of whole instants at a time."""

    def open(self, shape: tuple[int, ...], dtype: np.dtype) -> int:
        """Start an output of ``shape`` (instants first); return the instants a block holds
        (at least 1)."""

    def write(self, start: int, block: np.ndarray) -> None:
        """Store ``block`` as rows ``start .. start + len(block)`` (the block is reused)."""

    def read(self, key: Any) -> np.ndarray:
        """A selection of the stored output, read back."""


def field_steps(n_steps: int, every: int, field_every: int) -> np.ndarray:
    r"""The steps whose field is stored: :math:`S` of the module docstring (empty for
    ``field_every = 0``), ascending."""
    if field_every <= 0:
        return np.zeros(0, dtype=np.int64)
    seen = np.arange(0, n_steps + 1, every, dtype=np.int64)
    if seen[-1] != n_steps:
        seen = np.append(seen, np.int64(n_steps))
    return seen[seen % field_every == 0]


class StoredFields:
    """The stored fields of a run whose blocks went to a sink: their shape, and selections
    (``F[k]``, ``F[[k1, k2, ...]]``, ``F[:, j]``) read back from the sink.  ``np.asarray`` of
    it reads the whole history back (a full copy: ``substruct run`` never asks for it)."""

    def __init__(self, sink: FieldSink, shape: tuple[int, int]) -> None:
        self.sink = sink
        self.shape = tuple(shape)
        self.dtype = np.dtype(float)
        self.ndim = 2
        self.size = int(np.prod(self.shape))
        self.nbytes = self.size * self.dtype.itemsize

    def __len__(self) -> int:
        return self.shape[0]

    def __array__(self, dtype: Any = None, copy: Any = None) -> np.ndarray:
        a = np.asarray(self.sink.read(()))
        return a if dtype is None else a.astype(dtype)

    def __getitem__(self, key: Any) -> np.ndarray:
        return np.asarray(self.sink.read(key))


class FieldStore:
    """Collects the fields of the steps ``steps`` (:func:`field_steps`) of ``n`` coordinates,
    recorded at ``t = step dt``: into one array, or with a ``sink`` into a block of the rows
    the sink asks for, handed to it when full (module docstring).

    Raises:
        RuntimeError: (:meth:`add`, :meth:`stored`) a field of a step not in ``steps``, out of
            order, or fewer fields than ``steps`` (a bug of the caller).
    """

    def __init__(self, n: int, steps: np.ndarray, dt: float,
                 sink: FieldSink | None = None) -> None:
        self.steps = np.asarray(steps, dtype=np.int64)
        self.t = np.asarray([int(k) * dt for k in self.steps], dtype=float)
        self.shape = (int(self.steps.size), int(n))
        self.sink = sink if self.shape[0] else None  # nothing stored: nothing streamed
        self.count = 0
        self.start = 0  # the first row of the current block
        if self.sink is None:
            self.block = np.empty(self.shape)
        else:
            rows = max(1, int(self.sink.open(self.shape, np.dtype(float))))
            self.block = np.empty((min(rows, self.shape[0]), self.shape[1]))
        self.done: np.ndarray | StoredFields | None = None

    def wants(self, step: int) -> bool:
        """Whether the field of ``step`` is the next one stored."""
        return self.count < self.shape[0] and step == self.steps[self.count]

    def add(self, step: int, q: np.ndarray) -> None:
        """Store the field ``q`` of ``step`` (copied into its row)."""
        if not self.wants(step):
            raise RuntimeError(f"the field of step {step} is not the next one stored "
                               f"(stored {self.count} of {self.shape[0]})")
        row = self.count - self.start
        self.block[row] = q
        self.count += 1
        if self.sink is not None and (row + 1 == self.block.shape[0]
                                      or self.count == self.shape[0]):
            self.sink.write(self.start, self.block[:row + 1])
            self.start = self.count

    def stored(self) -> np.ndarray | StoredFields:
        """The fields, ``len(steps) x n``: the array, or with a sink what was written there
        (:class:`StoredFields`)."""
        if self.done is None:
            if self.count != self.shape[0]:
                raise RuntimeError(f"{self.count} of the {self.shape[0]} fields were stored")
            self.done = self.block if self.sink is None else \
                StoredFields(self.sink, self.shape)
            if self.sink is not None:
                self.block = np.empty((0, self.shape[1]))  # the last block is written
        return self.done
