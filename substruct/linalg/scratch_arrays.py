"""Large arrays kept on disk instead of in memory: each written once to a ``.npy`` file of a
private temporary directory and read back as a read-only memory map, whose pages the
operating system reads on use and drops under memory pressure.  A file is removed at
:meth:`ScratchArrays.discard`, the directory when the :class:`ScratchArrays` holding it is
collected; on a POSIX system a file removed while mapped stays readable until unmapped.

Used for what a multilevel reduction must keep but reads once
(:mod:`substruct.linalg.amls_reduce`: the separators' constraint modes, 13 GB at 10^6
coordinates of a solid, and the condensations waiting for their parents), and for mode shapes
larger than the memory (:func:`substruct.linalg.amls.amls_modes`: 2,000 modes of 2 x 10^6
coordinates are 32 GB), written a block of columns at a time (:meth:`ScratchArrays.empty`),
and for the Ritz vectors of the subspace iteration, read and written by blocks of columns
without a map (:meth:`ScratchArrays.columns`).
A map outlives its directory: the file stays on disk, nameless, until the map is collected.  The directory is
made in the system's temporary directory (``TMPDIR``).
"""

from __future__ import annotations

import os
import shutil
import tempfile
import weakref

import numpy as np

from substruct.linalg.column_file import ColumnFile

__all__ = ["ScratchArrays", "read_whole"]


def read_whole(array: np.ndarray) -> np.ndarray:
    """``array`` itself, or, for a memory map of a ``.npy`` file (:meth:`ScratchArrays.keep`),
    its values read from the file into a new array: a map's pages, once touched, stay in the
    process (counted in its resident memory) until the map is collected, while a read's pages
    are the operating system's cache, and the new array goes when its user drops it."""
    if isinstance(array, np.memmap) and array.filename is not None:
        return np.load(array.filename, allow_pickle=False)
    return array


class ScratchArrays:
    """A private temporary directory of arrays (made at the first :meth:`keep`)."""

    def __init__(self, prefix: str = "substruct-") -> None:
        self.prefix = prefix
        self.path: str | None = None
        self.count = 0
        self._finalizer: weakref.finalize | None = None

    def keep(self, array: np.ndarray) -> np.ndarray:
        """``array`` written to a file of the directory, returned as a read-only memory map
        of it (the same values, bit for bit)."""
        name = self._new_name()
        np.save(name, np.asarray(array), allow_pickle=False)
        return np.load(name, mmap_mode="r", allow_pickle=False)

    def _new_name(self) -> str:
        if self.path is None:
            self.path = tempfile.mkdtemp(prefix=self.prefix)
            self._finalizer = weakref.finalize(self, shutil.rmtree, self.path, True)
        name = os.path.join(self.path, f"{self.count}.npy")
        self.count += 1
        return name

    def empty(self, shape: tuple[int, int]) -> np.ndarray:
        """A new writable ``float64`` array of ``shape`` in a file of the directory, in
        column-major (Fortran) order: a block of columns is one contiguous stretch of the
        file, written and read without touching the others' pages."""
        name = self._new_name()
        return np.lib.format.open_memmap(name, mode="w+", dtype=np.float64, shape=shape,
                                         fortran_order=True)

    def columns(self, shape: tuple[int, int], width: int) -> ColumnFile:
        """A new ``n x p`` :class:`~substruct.linalg.column_file.ColumnFile` of blocks of
        ``width`` columns (zeros) in a file of the directory."""
        return ColumnFile(self._new_name(), shape, width)

    def discard(self, array: np.ndarray | ColumnFile) -> None:
        """Remove the file behind ``array`` (a map from :meth:`keep` or :meth:`empty`, a
        :meth:`columns` file; anything else is left alone): a map's pages stay readable until
        it is collected."""
        name = getattr(array, "filename", None)
        if self.path is not None and name and os.path.dirname(name) == self.path:
            os.remove(name)
