"""The answer of a computation in a child process (substruct/cli/isolated.py): large arrays come
back through a mapped temporary file, bit for bit, writable, whatever their layout."""

from __future__ import annotations

import os
import sys

import numpy as np

from substruct.cli.isolated import call_isolated


def test_arrays_of_every_layout_come_back_bit_for_bit(monkeypatch):
    # a process that has loaded CHOLMOD computes in-process (its thread pool does not survive
    # a fork); this child never factorizes, so the fork is safe whatever ran before
    monkeypatch.delitem(sys.modules, "sksparse.cholmod", raising=False)
    rng = np.random.default_rng(1)
    big = rng.standard_normal((50, 40, 30)) + 1j * rng.standard_normal((50, 40, 30))

    def compute():
        return {"big": big, "view": big[:, :7], "fortran": np.asfortranarray(big[0]),
                "empty": np.zeros((0, 3)), "ints": np.arange(11), "text": "x" * 10,
                "scalar": 3.5, "pid": os.getpid()}

    value = call_isolated(compute)
    for name in ("big", "view", "fortran", "empty", "ints"):
        expected = compute()[name]
        assert value[name].dtype == expected.dtype and value[name].shape == expected.shape
        assert np.array_equal(value[name], expected), name
    assert value["text"] == "x" * 10 and value["scalar"] == 3.5
    assert value["pid"] != os.getpid()  # computed in a child
    value["big"][0, 0, 0] = 7.0  # writable (a private copy of the mapped pages)
    assert value["big"][0, 0, 0] == 7.0 and big[0, 0, 0] != 7.0
