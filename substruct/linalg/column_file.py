"""An ``n x p`` matrix of doubles kept in a file, column-major, read and written a block of
columns at a time by explicit reads and writes.

Nothing is mapped: the pages of the file are the operating system's cache, not the process's
memory, so a computation that goes over the matrix block by block holds one block (and what
it makes of it), however large the matrix.  Used for the Ritz vectors of the AMLS subspace
iteration (:func:`substruct.linalg.amls.amls_modes`), which otherwise sit in memory beside the
full factorization: ``n x p`` doubles, 2.4 GB for the 1,012 vectors of 500 modes of a
297,714-coordinate solid.
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
    """The ``n x p`` ``float64`` matrix stored column-major in ``path`` (``filename``) from byte
    ``offset`` (the file is opened for reading and writing, made if missing, and extended to
    ``8 n p`` bytes from there if shorter: zeros).  The descriptor is closed with the object or by :meth:`close`; the
    file itself belongs to the caller (e.g. a :class:`~substruct.linalg.scratch_arrays.
    ScratchArrays` directory)."""

    def __init__(self, path: str, shape: tuple[int, int], offset: int = 0) -> None:
        self.filename = path
        self.shape = (int(shape[0]), int(shape[1]))
        self.offset = int(offset)
        self.fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o600)
        end = self.offset + 8 * self.shape[0] * self.shape[1]
        if os.fstat(self.fd).st_size < end:
            os.ftruncate(self.fd, end)
        self._finalizer = weakref.finalize(self, _close, self.fd)

    @classmethod
    def of(cls, array: np.memmap) -> "ColumnFile":
        """The file behind a column-major ``float64`` memory map of two dimensions (e.g.
        :meth:`~substruct.linalg.scratch_arrays.ScratchArrays.empty`), same numbers; drop the
        map afterwards, or its pages stay in the process."""
        if array.ndim != 2 or array.dtype != np.float64 or not array.flags.f_contiguous \
                or array.filename is None:
            raise ValueError("a column-major float64 memory map of two dimensions is needed")
        return cls(str(array.filename), array.shape, array.offset)

    def close(self) -> None:
        """Close the descriptor (the file stays)."""
        self._finalizer()

    def _span(self, a: int, b: int) -> tuple[int, int]:
        n, p = self.shape
        if not 0 <= a <= b <= p:
            raise IndexError(f"columns {a}:{b} of {p}")
        return self.offset + 8 * n * a, 8 * n * (b - a)

    def read(self, a: int, b: int) -> np.ndarray:
        """Columns ``a:b``, a new column-major ``n x (b - a)`` array."""
        start, size = self._span(a, b)
        flat = np.empty(size // 8)
        view = flat.data.cast("B")
        done = 0
        while done < size:   # a read returns at most about 2 GB
            got = os.preadv(self.fd, [view[done:]], start + done)
            if got <= 0:
                raise OSError(f"{self.filename}: {size - done} bytes missing at {start + done}")
            done += got
        return flat.reshape((self.shape[0], b - a), order="F")

    def write(self, a: int, block: np.ndarray) -> None:
        """Columns ``a : a + block.shape[1]`` set to ``block`` (``n`` rows)."""
        if block.ndim != 2 or block.shape[0] != self.shape[0]:
            raise ValueError(f"a block of {self.shape[0]} rows is needed, got {block.shape}")
        start, size = self._span(a, a + block.shape[1])
        flat = np.ravel(np.asfortranarray(block, dtype=np.float64), order="F")
        view = flat.data.cast("B")
        done = 0
        while done < size:
            done += os.pwritev(self.fd, [view[done:]], start + done)
