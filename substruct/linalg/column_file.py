"""An ``n x p`` matrix of doubles kept in a file as blocks of ``width`` columns, read and
written a block at a time by explicit reads and writes.

Each block is stored row by row (C order), so that a read gives the C-ordered ``n x width``
array that the sparse products and the solves take without a transposing copy (which costs
as much as the read itself).  Nothing is mapped: the pages of the file are the operating
system's cache, not the process's memory, so a computation that goes over the matrix block
by block holds one block (and what it makes of it), however large the matrix.  Used for the
Ritz vectors of the AMLS subspace iteration (:func:`substruct.linalg.amls.amls_modes`), which
otherwise sit in memory beside the full factorization: ``n x p`` doubles, 2.4 GB for the
1,012 vectors of 500 modes of a 297,714-coordinate solid.
"""

from __future__ import annotations

import os
import weakref

import numpy as np

__all__ = ["ColumnFile"]


def _close(fd: int) -> None:
    try:
        os.close(fd)
    except OSError:
        pass


class ColumnFile:
    """The ``n x p`` ``float64`` matrix in the file ``filename`` (opened for reading and
    writing, made if missing, extended with zeros to its ``8 n p`` bytes), as blocks of
    ``width`` columns (the last one narrower), block ``i`` (columns ``i width`` to
    ``(i + 1) width``) stored C-ordered after the blocks before it.  The descriptor is closed
    with the object or by :meth:`close`; the file itself belongs to the caller (e.g. a
    :class:`~substruct.linalg.scratch_arrays.ScratchArrays` directory)."""

    def __init__(self, filename: str, shape: tuple[int, int], width: int) -> None:
        if width < 1:
            raise ValueError(f"width must be at least 1, got {width}")
        self.filename = filename
        self.shape = (int(shape[0]), int(shape[1]))
        self.width = int(width)
        self.fd = os.open(filename, os.O_RDWR | os.O_CREAT, 0o600)
        if os.fstat(self.fd).st_size < 8 * self.shape[0] * self.shape[1]:
            os.ftruncate(self.fd, 8 * self.shape[0] * self.shape[1])
        self._finalizer = weakref.finalize(self, _close, self.fd)

    def close(self) -> None:
        """Close the descriptor (the file stays)."""
        self._finalizer()

    def _span(self, start: int) -> tuple[int, int]:
        """The byte offset and size of the block of columns from ``start``."""
        n, p = self.shape
        if start % self.width or not 0 <= start < p:
            raise IndexError(f"no block of {self.width} columns starts at column {start} of {p}")
        return 8 * n * start, 8 * n * min(self.width, p - start)

    def read(self, start: int) -> np.ndarray:
        """The block of columns from ``start`` (a multiple of ``width``): a new C-ordered
        ``n x min(width, p - start)`` array."""
        offset, size = self._span(start)
        flat = np.empty(size // 8)
        view = flat.data.cast("B")
        done = 0
        while done < size:   # a read returns at most about 2 GB
            got = os.preadv(self.fd, [view[done:]], offset + done)
            if got <= 0:
                raise OSError(f"{self.filename}: {size - done} bytes missing at {offset + done}")
            done += got
        return flat.reshape((self.shape[0], -1))

    def write(self, start: int, block: np.ndarray) -> None:
        """The block of columns from ``start`` (a multiple of ``width``) set to ``block``
        (``n x min(width, p - start)``)."""
        offset, size = self._span(start)
        if block.shape != (self.shape[0], size // (8 * self.shape[0])):
            raise ValueError(f"block of columns {start}: shape {block.shape}, expected "
                             f"{(self.shape[0], size // (8 * self.shape[0]))}")
        flat = np.ascontiguousarray(block, dtype=np.float64).reshape(-1)
        view = flat.data.cast("B")
        done = 0
        while done < size:
            done += os.pwritev(self.fd, [view[done:]], offset + done)
