"""The fields a transient run stores (``field_every``) streamed into the result file a block of
instants at a time as they are recorded: the file holds the numbers of the in-memory run (the
same copies of the same vectors: bit for bit), the checks are the same figures, a failure
half-way leaves no file, the animation reads back a selection, and the run never holds the
whole history."""

from __future__ import annotations

import dataclasses
import errno
import tracemalloc

import h5py
import numpy as np
import pytest
import scipy.sparse as sp

import substruct.io.blocks as blocks
from substruct.analysis.transient import (InitialConditions, LoadHistory, TransientOptions,
                                          TransientOutputs, transient)
from substruct.analysis.transient.fields import StoredFields, field_steps
from substruct.io import hdf5 as results
from substruct.io.blocks import DatasetSink

from cli_helpers import run

ROD = """\
name: rod_fields
units: "N, m, kg, s"
substructures:
  - name: rod
    type: rod
    length: 1.0
    EA: 2.1e7
    m: 0.785
    support: fixed-free
    discretization: {method: fe, elements: 40, order: 1}
  - {name: a, type: fixed-free, mass: 0.05, stiffness: 2.0e5}
connections:
  - [rod@0.5, a]
constraints:
  - name: tie
    terms: {rod@0.25: 1, rod@0.75: -1}
analysis:
  transient:
    t_end: 3.0e-3
    dt: 1.0e-4
    check: [null-space, modal]
    loads:
      - {point: rod@1, amplitude: 500, shape: half-sine, duration: 5.0e-4}
    outputs: [rod@1, a@mass]
    every: 2
    field_every: 4
"""


def _tied(n_dof, method, every, field_every, steps=40):
    """The tied two-mass model with a massless absorber coordinate of test_transient_io,
    padded with springs to ``n_dof``; ``(M, C, K, A, load, outputs, options)``."""
    M = sp.diags_array([1.0, 2.0, 0.0, 0.5] + [1.0] * (n_dof - 4)).tocsr()
    K = sp.block_diag([sp.csr_array(np.array([[900.0, -100, 0, 0], [-100, 400, 0, 0],
                                              [0, 0, 300, -300], [0, 0, -300, 300]])),
                       sp.diags_array(50.0 + np.arange(n_dof - 4))]).tocsr()
    A = sp.csr_array((np.array([1.0, -1.0, 1.0, -1.0]), ([0, 0, 1, 1], [0, 1, 1, 2])),
                     shape=(2, n_dof))
    B = np.zeros((n_dof, 1))
    B[3] = 1.0
    t = 1e-3 * np.arange(steps + 1)
    load = LoadHistory(B, np.sin(40 * t)[:, None], 1e-3, steps)
    outs = TransientOutputs(sp.csr_array(np.eye(n_dof)[[0, 3]]), ["m1", "absorber"])
    checks = [m for m in ("generalized-inverse", "null-space", "modal") if m != method]
    opts = TransientOptions(method=method, checks=checks, every=every, field_every=field_every,
                            integrator="generalized-alpha", rho_inf=0.8)
    return M, 0.01 * K, K, A, load, outs, opts


def _initial(n_dof):
    d0 = np.zeros(n_dof)
    d0[4:] = 1e-3 * np.cos(np.arange(n_dof - 4))  # every coordinate moves from the start
    return InitialConditions(d0=d0)


@pytest.mark.parametrize("steps,every,field_every", [(40, 1, 1), (40, 3, 2), (41, 4, 6),
                                                     (7, 10, 1), (0, 1, 1), (40, 2, 0)])
def test_field_steps_are_the_recorded_steps_that_field_every_divides(steps, every,
                                                                     field_every):
    """The set S of the module docstring, by its definition, against the instants a run
    stores (which the store refuses to take out of that order)."""
    recorded = sorted({0, steps, *range(every, steps + 1, every)})
    expected = [k for k in recorded if field_every and k % field_every == 0]
    assert field_steps(steps, every, field_every).tolist() == expected
    if not steps:  # a run has at least one step
        return
    M, C, K, A, load, outs, opts = _tied(8, "generalized-inverse", every, field_every, steps)
    tr = transient(M, C, K, A, None, load, outs, options=dataclasses.replace(opts, checks=()))
    assert np.array_equal(tr.snapshot_t, 1e-3 * np.asarray(expected, dtype=float))
    assert tr.snapshots.shape == (len(expected), 8)


class _Counting(DatasetSink):
    """A dataset sink that notes the first row of every block written."""

    starts: list[int]

    def write(self, start, block):
        self.starts.append(start)
        super().write(start, block)


@pytest.mark.parametrize("method", ["generalized-inverse", "null-space", "modal"])
def test_streamed_fields_equal_the_in_memory_run_bit_for_bit(tmp_path, method):
    """Each form as the main one, 41 fields in blocks of 7 (the last one short): the file holds
    the fields of the run without a sink, and every other record, the checks' figures (which
    compare the final fields) and the drift are the same to the last bit."""
    n = 30
    M, C, K, A, load, outs, opts = _tied(n, method, 1, 1)
    ref = transient(M, C, K, A, None, load, outs, initial=_initial(n), options=opts)
    with h5py.File(tmp_path / "f.h5", "w") as f:
        sink = _Counting(f, "F", block_bytes=7 * n * 8, chunk_bytes=n * 8)
        sink.starts = []
        got = transient(M, C, K, A, None, load, dataclasses.replace(outs, fields=sink),
                        initial=_initial(n), options=opts)
        assert sink.starts == [0, 7, 14, 21, 28, 35]
        assert isinstance(got.snapshots, StoredFields) and got.snapshots.shape == (41, n)
        stored = f["F"][()]
        assert np.array_equal(got.snapshots[[0, 17, 40]], ref.snapshots[[0, 17, 40]])
    assert stored.dtype == ref.snapshots.dtype and stored.tobytes() == ref.snapshots.tobytes()
    assert np.abs(ref.snapshots[-1]).max() > 1e-4  # the fields are not trivially zero
    for field in dataclasses.fields(ref):
        if field.name != "snapshots":
            a, b = getattr(got, field.name), getattr(ref, field.name)
            if isinstance(b, np.ndarray):
                assert a.tobytes() == b.tobytes(), field.name
            else:
                assert a == b, field.name
    assert set(ref.agreement) == {"generalized-inverse", "null-space", "modal"} - {method}
    assert max(ref.agreement.values()) < 1e-6


def _same_files(a, b):
    """Every group, dataset (values to the bit, dtype, shape, chunks) and attribute of the
    HDF5 files ``a`` and ``b``, in the same order (the creation time apart)."""
    with h5py.File(a) as fa, h5py.File(b) as fb:
        def same(x, y):
            assert list(x.attrs) == list(y.attrs), x.name
            for key in x.attrs:
                if key != "created":
                    assert np.array_equal(x.attrs[key], y.attrs[key]), (x.name, key)
            if isinstance(x, h5py.Dataset):
                assert (x.dtype, x.shape, x.chunks) == (y.dtype, y.shape, y.chunks), x.name
                u, v = x[()], y[()]
                if u.dtype.kind == "O":  # strings
                    assert u.tolist() == v.tolist(), x.name
                else:
                    assert u.tobytes() == v.tobytes(), x.name
                return
            assert list(x) == list(y), x.name
            for key in x:
                same(x[key], y[key])

        same(fa, fb)


def test_substruct_run_writes_the_fields_of_the_library(tmp_path, capsys, monkeypatch):
    """The command's result file (8 fields of a constrained rod checked by two forms,
    streamed in blocks of 3 instants, the last of 2) equals the file the in-memory library
    result saves, every dataset and attribute; the whole history is never read back."""
    from substruct.case.loader import load_case
    from substruct.run.runner import run_case

    case = tmp_path / "rod_fields.yaml"
    case.write_text(ROD)
    ref = run_case(load_case(case, []))
    assert ref.transient is not None and ref.transient.snapshots.shape[0] == 8
    ref.attrs["pictures"] = ""  # what the command lists without pictures
    results.save(ref, tmp_path / "library.h5")
    monkeypatch.setattr(blocks, "block_rows", lambda *a, **k: 3)  # blocks of 3, the last of 2

    def whole(self, dtype=None, copy=None):
        raise AssertionError("the whole stored history was read back")

    monkeypatch.setattr(StoredFields, "__array__", whole)
    code, _, err = run(capsys, "run", case, "--out", tmp_path / "out", "--quiet",
                       "--no-pictures")
    assert code == 0, err
    _same_files(tmp_path / "out" / "rod_fields.h5", tmp_path / "library.h5")
    with h5py.File(tmp_path / "out" / "rod_fields.h5") as f:
        assert "_transient_snapshots_streaming" not in f
        assert f["transient/snapshots"].shape == (8, ref.transient.snapshots.shape[1])


def test_the_animation_reads_its_frames_back(tmp_path, capsys, monkeypatch):
    """With pictures, the GIF is drawn from the frames read back from the open result file
    (the whole history is never read: that would fail the run)."""
    def whole(self, dtype=None, copy=None):
        raise AssertionError("the whole stored history was read back")

    monkeypatch.setattr(StoredFields, "__array__", whole)
    case = tmp_path / "rod_fields.yaml"
    case.write_text(ROD)
    code, _, err = run(capsys, "run", case, "--out", tmp_path / "out", "--quiet")
    assert code == 0, err
    assert (tmp_path / "out" / "rod_fields_transient.gif").stat().st_size > 1000


def test_a_full_disk_mid_run_writes_nothing(tmp_path, capsys, monkeypatch):
    """The second block of fields fails to write (a full disk): one line, exit code 2, no
    file of the set in the output folder."""
    monkeypatch.setattr(blocks, "block_rows", lambda *a, **k: 3)
    real = h5py.Dataset.__setitem__
    count = []

    def setitem(self, key, value):
        if "snapshots_streaming" in self.name:
            count.append(key)
            if len(count) == 2:
                raise OSError(errno.ENOSPC, "No space left on device")
        real(self, key, value)

    monkeypatch.setattr(h5py.Dataset, "__setitem__", setitem)
    case = tmp_path / "rod_fields.yaml"
    case.write_text(ROD)
    out = tmp_path / "out"
    code, stdout, err = run(capsys, "run", case, "--out", out, "--quiet", "--no-pictures")
    assert code == 2 and "No space left" in err and err.count("\n") == 1, err
    assert "Traceback" not in err and stdout == ""
    assert not out.exists() or [p.name for p in out.iterdir()] == [], list(out.iterdir())


def test_the_streamed_run_never_holds_the_history(tmp_path):
    """A chain of 2,000 masses released from a deformed state, its field stored at each of
    600 steps (9.6 MB), into a file 256 kB a block: the traced peak stays below a bound taken
    from the block (the block itself) plus 4 MB for the run's working set (the matrices, the
    factor of the tridiagonal effective matrix, a few vectors of 16 kB and the records of
    600 steps); the same run without a sink peaks above the history's size."""
    n, steps = 2000, 600
    K = sp.diags_array([-np.ones(n - 1), 2 * np.ones(n), -np.ones(n - 1)], offsets=[-1, 0, 1],
                       format="csr") * 1e4
    M = sp.identity(n, format="csr")
    load = LoadHistory(np.zeros((n, 0)), np.zeros((steps + 1, 0)), 1e-3, steps)
    outs = TransientOutputs(sp.csr_array(np.eye(n)[[0, n // 2]]), ["first", "middle"])
    init = InitialConditions(d0=np.sin(np.pi * np.arange(1, n + 1) / (n + 1)))
    opts = TransientOptions(field_every=1)
    history = (steps + 1) * n * 8
    block = 256 << 10
    transient(M, None, K, None, None, dataclasses.replace(load, n_steps=2, f=load.f[:3]),
              outs, initial=init, options=opts)  # imports and caches before measuring
    with h5py.File(tmp_path / "f.h5", "w") as f:
        sink = DatasetSink(f, "F", block_bytes=block)
        tracemalloc.start()
        try:
            tr = transient(M, None, K, None, None, load, dataclasses.replace(outs, fields=sink),
                           initial=init, options=opts)
            streamed = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
        assert f["F"].shape == (steps + 1, n) and tr.snapshots.shape == (steps + 1, n)
        last = f["F"][steps]
    bound = block + (4 << 20)
    assert streamed < bound < history / 2, (streamed, bound, history)
    tracemalloc.start()
    try:
        ref = transient(M, None, K, None, None, load, outs, initial=init, options=opts)
        whole = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert whole > history and np.array_equal(ref.snapshots[-1], last)
