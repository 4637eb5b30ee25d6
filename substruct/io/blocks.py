r"""Large arrays a block at a time: written to HDF5 as chunked datasets along their first axis
(frequencies of a receptance, instants of a transient), and reduced without a copy of the whole.

A receptance of 1,000 frequencies x 400 outputs x 400 inputs is 2.56 GB.  :func:`write_blocks`
writes it ``block_bytes`` at a time (whole frequencies, a whole number of chunks each), from
views of the array: HDF5 copies no more than one block, and complex values go to the file as
they are in memory (HDF5's compound ``{r, i}``, no conversion buffer).

The chunk is :math:`k_c` whole matrices,

.. math::  k_c = \max\left(1, \left\lfloor \frac{C}{n_{out} n_{in} s} \right\rfloor\right)

(``C`` = :data:`CHUNK_BYTES`, ``s`` the item size), so that the file holds no padding (edge
chunks of a split matrix dimension would be padded to a whole chunk) and a block of whole
chunks is written straight to the file.  Measured on a 512 MB receptance (200 x 400 x 400,
one core): 0.11 s of CPU for a contiguous dataset, 0.15 s chunked as here.

:class:`DatasetSink` is the same dataset filled by a sweep as it computes
(:class:`substruct.analysis.frf.stream.FrequencySink`): the sweep holds one block, never the
whole output.

Compression is optional (``compression="gzip"`` or ``"lzf"``, with the byte shuffle): on
receptances it saves little, because their mantissas are noise to a byte compressor, and costs
much.  The 512 MB receptance of two tied 200-mass chains at 200 frequencies (one core, CPU
time): uncompressed 0.2-0.4 s to write (1.4-3 GB/s into the page cache); LZF 3.9 s
(130 MB/s) for 9.7 % less space; gzip level 4 (h5py's default) 9.9 s (52 MB/s) for 16 %
less; reading back 0.3-1.0 s uncompressed, about 2 s compressed.  It is off by default.
"""

from __future__ import annotations

import contextlib
import math
import os
from typing import Any

import numpy as np

from substruct.io.paths import write_errors

__all__ = ["CHUNK_BYTES", "BLOCK_BYTES", "COMPRESSIONS", "chunk_rows", "block_rows",
           "write_blocks", "max_abs", "DatasetSink"]

#: Target size of one HDF5 chunk (the default chunk cache of HDF5 holds 1 MiB).
CHUNK_BYTES = 1 << 20
#: Bytes written (or reduced) at a time.
BLOCK_BYTES = 64 << 20
#: The compressions :func:`write_blocks` takes (HDF5 filters shipped with h5py).
COMPRESSIONS = (None, "gzip", "lzf")


def _row_bytes(shape: tuple[int, ...], itemsize: int) -> int:
    return max(1, math.prod(shape[1:]) * itemsize)


def chunk_rows(shape: tuple[int, ...], itemsize: int, chunk_bytes: int = CHUNK_BYTES) -> int:
    r"""Rows (first-axis entries) of one chunk: :math:`k_c` of the module docstring, at most
    the number of rows (at least 1)."""
    return max(1, min(shape[0], chunk_bytes // _row_bytes(shape, itemsize)))


def block_rows(shape: tuple[int, ...], itemsize: int, block_bytes: int = BLOCK_BYTES,
               chunk: int = 1) -> int:
    """Rows of one block: as many as ``block_bytes`` holds, a multiple of ``chunk`` (at least
    one chunk)."""
    rows = max(1, block_bytes // _row_bytes(shape, itemsize))
    return max(chunk, rows // chunk * chunk)


def _check_options(compression: str | None, block_bytes: int, chunk_bytes: int) -> None:
    if compression not in COMPRESSIONS:
        raise ValueError(f"unknown compression {compression!r}; expected one of "
                         f"{', '.join(str(c) for c in COMPRESSIONS)}")
    if block_bytes < 1 or chunk_bytes < 1:
        raise ValueError(f"block and chunk sizes must be positive, got {block_bytes}, "
                         f"{chunk_bytes}")


def _create(group: Any, name: str, shape: tuple[int, ...], dtype: np.dtype, chunk_bytes: int,
            compression: str | None) -> Any:
    """The chunked dataset of :func:`write_blocks` (``shape`` not empty)."""
    chunk = chunk_rows(shape, dtype.itemsize, chunk_bytes)
    return group.create_dataset(name, shape=shape, dtype=dtype, chunks=(chunk, *shape[1:]),
                                compression=compression, shuffle=compression is not None)


class DatasetSink:
    """The dataset ``group[name]`` of :func:`write_blocks`, filled a block of frequencies at a
    time by a sweep (:class:`substruct.analysis.frf.stream.FrequencySink`): :meth:`open`
    creates it and asks for :func:`block_rows` rows a block, :meth:`write` writes each block
    as it comes, :meth:`read` reads a selection back.  With ``where``, an error of the file
    system is a :class:`~substruct.io.paths.WriteError` naming it.  The file, read back, is the same as
    :func:`write_blocks` of the whole array would have written.

    Raises:
        ValueError: (on creation) as :func:`write_blocks`.
    """

    def __init__(self, group: Any, name: str, *, block_bytes: int = BLOCK_BYTES,
                 chunk_bytes: int = CHUNK_BYTES, compression: str | None = None,
                 where: str | os.PathLike | None = None) -> None:
        _check_options(compression, block_bytes, chunk_bytes)
        self.group, self.name, self.where = group, name, where
        self.block_bytes, self.chunk_bytes, self.compression = block_bytes, chunk_bytes, \
            compression
        self.dataset: Any = None

    def _guard(self) -> contextlib.AbstractContextManager:
        return write_errors(self.where) if self.where is not None else \
            contextlib.nullcontext()

    def open(self, shape: tuple[int, ...], dtype: np.dtype) -> int:
        """Create the dataset; return the rows of a block (whole chunks)."""
        with self._guard():
            return self._open(tuple(shape), np.dtype(dtype))

    def _open(self, shape: tuple[int, ...], dtype: np.dtype) -> int:
        if self.dataset is not None:
            raise RuntimeError(f"the dataset {self.name!r} is already written")
        if math.prod(shape) == 0:
            self.dataset = self.group.create_dataset(self.name, shape=shape, dtype=dtype)
            return 1
        self.dataset = _create(self.group, self.name, shape, dtype, self.chunk_bytes,
                               self.compression)
        chunk = self.dataset.chunks[0]
        return block_rows(shape, dtype.itemsize, self.block_bytes, chunk)

    def write(self, start: int, block: np.ndarray) -> None:
        """``dataset[start:start + len(block)] = block``."""
        if block.shape[0]:
            with self._guard():
                self.dataset[start:start + block.shape[0]] = block

    def read(self, key: Any) -> np.ndarray:
        """``dataset[key]``, read back from the file."""
        return np.asarray(self.dataset[key])


def write_blocks(group: Any, name: str, array: np.ndarray, *, block_bytes: int = BLOCK_BYTES,
                 chunk_bytes: int = CHUNK_BYTES, compression: str | None = None) -> Any:
    """Write ``array`` as the dataset ``group[name]``, chunked along its first axis
    (:func:`chunk_rows`) and written :func:`block_rows` rows at a time; return the dataset.

    An empty array (or a 0-d one) is written as it is (a chunk cannot be empty).  Read back
    with ``dataset[()]`` it is equal to ``array``, bit for bit.

    Raises:
        ValueError: an unknown ``compression`` (:data:`COMPRESSIONS`), or block or chunk
            sizes below one byte.
    """
    _check_options(compression, block_bytes, chunk_bytes)
    a = np.asarray(array)
    if a.ndim == 0 or a.size == 0:
        return group.create_dataset(name, data=a)
    ds = _create(group, name, a.shape, a.dtype, chunk_bytes, compression)
    step = block_rows(a.shape, a.itemsize, block_bytes, ds.chunks[0])
    for start in range(0, a.shape[0], step):
        ds[start:start + step] = a[start:start + step]
    return ds


def max_abs(array: np.ndarray, block_bytes: int = BLOCK_BYTES) -> float:
    """``np.abs(array).max()`` (0 for an empty array), computed ``block_bytes`` of ``array``
    at a time along its first axis: the temporary is one block, not a copy of the whole.  An
    output streamed to the file (:class:`substruct.analysis.frf.stream.StreamedArray`) gives
    the maximum it took as its blocks passed."""
    peak = getattr(array, "peak", None)
    if peak is not None:
        return float(peak)
    a = np.asarray(array)
    if a.size == 0:
        return 0.0
    if a.ndim == 0:
        return float(np.abs(a))
    step = block_rows(a.shape, a.itemsize, block_bytes)
    return max(float(np.abs(a[s:s + step]).max()) for s in range(0, a.shape[0], step))
