"""The receptances of ``substruct run`` streamed into the result file a block of frequencies at
a time: the file holds the numbers of the in-memory sweep (the same arithmetic: bit for bit),
a failure half-way leaves no file, and the sweep never holds the whole output."""

from __future__ import annotations

import errno
import tracemalloc

import h5py
import numpy as np
import pytest
import scipy.sparse as sp

import substruct.io.blocks as blocks
from substruct.analysis.api import receptance_sweep
from substruct.analysis.frf.quantity import as_quantity, quantity_factor
from substruct.analysis.frf.stream import KEPT_PAIRS, StreamedArray, SweepTap
from substruct.analysis.system import ConstrainedSystem, SweepOptions
from substruct.io.blocks import DatasetSink
from substruct.io.hdf5 import result_file
from substruct.io.paths import WriteError

from cli_helpers import run
from test_sweep_fast import chains, random_assembly


def _system(K, M, C, A):
    return ConstrainedSystem.of(M, C, K, A)


@pytest.fixture
def h5(tmp_path):
    with h5py.File(tmp_path / "s.h5", "w") as f:
        yield f


def _streamed(f, system, w, E, O, options=None, block_bytes=1 << 20, tap=None):
    """The sweep into a chunked dataset of the open file ``f``, ``block_bytes`` a block;
    ``(result, H read back)``."""
    sink = DatasetSink(f, "H", block_bytes=block_bytes, chunk_bytes=64 << 10)
    res = receptance_sweep(system, w, E, O, options=options, sink=tap(sink) if tap else sink)
    return res, f["H"][()]


@pytest.mark.parametrize("make", [lambda: chains(60), lambda: random_assembly(150, 6)],
                         ids=["band", "superlu"])
def test_streamed_file_equals_the_in_memory_sweep_bit_for_bit(h5, make):
    """Several blocks of frequencies (band solves and SuperLU), every output x input: the file
    is the array of the sweep without a sink, the checks and the residual the same figures."""
    K, M, C, A = make()
    n = K.shape[0]
    w = np.linspace(1.0, 150.0, 61)
    E, O = sp.eye_array(n, format="csc")[:, ::2], sp.eye_array(n, format="csr")[1::3]
    system = _system(K, M, C, A)
    opts = SweepOptions(checks=["kkt"])
    ref = receptance_sweep(system, w, E, O, options=opts)
    block = ref.H[0].nbytes * 7  # 7 frequencies a block: 9 blocks, the last one short
    res, H = _streamed(h5, system, w, E, O, opts, block_bytes=block)
    assert ref.method == res.method == "null-space/sparse"
    assert np.array_equal(H, ref.H)
    assert res.agreement == ref.agreement and res.agreement["kkt"] < 1e-9
    assert res.constraint_residual == ref.constraint_residual
    assert isinstance(res.H, StreamedArray) and res.H.shape == ref.H.shape
    assert res.H.peak == float(np.abs(ref.H).max()) and res.H.nonfinite == 0
    q, p = min(O.shape[0], KEPT_PAIRS), min(E.shape[1], KEPT_PAIRS)
    assert np.array_equal(res.H[:, [0, q - 1], [p - 1, 0]], ref.H[:, [0, q - 1], [p - 1, 0]])
    assert np.array_equal(res.H[:, q, 0], ref.H[:, q, 0])  # beyond the kept: read back
    assert np.array_equal(res.H[30], ref.H[30])


def test_a_quantity_converted_as_the_blocks_pass_equals_the_converted_array(h5):
    """Accelerance by the tap (each block multiplied in place after the checked frequencies
    were kept) is the accelerance of the whole array, bit for bit; the checks are the
    receptance's."""
    K, M, C, A = chains(60)
    n = K.shape[0]
    w = np.linspace(1.0, 150.0, 40)
    E, O = sp.eye_array(n, format="csc")[:, :5], sp.eye_array(n, format="csr")
    system = _system(K, M, C, A)
    ref = receptance_sweep(system, w, E, O)
    factor = quantity_factor(w, "accelerance")
    res, H = _streamed(h5, system, w, E, O, block_bytes=ref.H[0].nbytes * 6,
                          tap=lambda s: SweepTap(s, lambda a, k: factor[a:a + k]))
    assert np.array_equal(H, as_quantity(ref, "accelerance").H)
    assert res.agreement == ref.agreement


@pytest.mark.parametrize("method", ["modal", "kkt"])
def test_modal_and_small_direct_sweeps_reach_the_sink_unchanged(h5, method):
    """The modal sweep (computed a block at a time) and a small model's direct formulation
    (computed whole) reach the file as their arrays."""
    K, M, C, A = chains(20 if method == "kkt" else 60)
    n = K.shape[0]
    w = np.linspace(1.0, 150.0, 25)
    E, O = sp.eye_array(n, format="csc")[:, :3], sp.eye_array(n, format="csr")[:4]
    opts = SweepOptions(method=method)
    ref = receptance_sweep(_system(K, M, C, A), w, E, O, options=opts)
    res, H = _streamed(h5, _system(K, M, C, A), w, E, O, opts,
                          block_bytes=ref.H[0].nbytes * 4)
    assert ref.method == res.method and np.array_equal(H, ref.H)
    assert res.agreement == ref.agreement


def _full_disk_at(monkeypatch, count):
    """Make the ``count``-th block written to an HDF5 dataset fail as a full disk does; the
    list of the blocks' first rows is returned."""
    real = h5py.Dataset.__setitem__
    starts = []

    def setitem(self, key, value):
        starts.append(key.start)
        if len(starts) == count:
            raise OSError(errno.ENOSPC, "No space left on device")
        real(self, key, value)

    monkeypatch.setattr(h5py.Dataset, "__setitem__", setitem)
    return starts


def test_a_failure_in_the_middle_of_the_sweep_leaves_no_file(tmp_path, monkeypatch):
    """The third block fails to write (a full disk): the sweep stops there, and neither the
    result file nor its temporary file is left; an older file it would replace is untouched."""
    K, M, C, A = chains(60)
    n = K.shape[0]
    w = np.linspace(1.0, 150.0, 50)
    E, O = sp.eye_array(n, format="csc"), sp.eye_array(n, format="csr")
    target = tmp_path / "case.h5"
    target.write_bytes(b"the previous result")
    starts = _full_disk_at(monkeypatch, 3)
    with pytest.raises(WriteError, match="No space left"):
        with result_file(target, where=tmp_path) as out:
            sink = DatasetSink(out.file, "H", block_bytes=n * n * 16 * 8, where=tmp_path)
            receptance_sweep(_system(K, M, C, A), w, E, O, sink=sink)
    assert starts == [0, 8, 16]  # 8 frequencies a block, stopped at the failing one
    assert sorted(p.name for p in tmp_path.iterdir()) == ["case.h5"]
    assert target.read_bytes() == b"the previous result"


def test_substruct_run_failing_mid_sweep_writes_nothing(tmp_path, capsys, monkeypatch):
    """``substruct run`` whose result file fills up at the third block of its sweep: one
    line, exit code 2, no file of the set in the output folder."""
    monkeypatch.setattr(blocks, "block_rows", lambda *a, **k: 16)  # 400 frequencies: 25 blocks
    _full_disk_at(monkeypatch, 3)
    out = tmp_path / "out"
    code, stdout, err = run(capsys, "run", "cases/two_rods_spring.yaml", "--out", out,
                            "--quiet", "--no-pictures")
    assert code == 2 and "No space left" in err and err.count("\n") == 1, err
    assert "Traceback" not in err and stdout == ""
    assert not out.exists() or [p.name for p in out.iterdir()] == [], list(out.iterdir())


def test_substruct_run_writes_the_receptances_of_the_library(tmp_path, capsys):
    """The command's ``/frf/H`` (streamed) is the library sweep of the same case, bit for
    bit, and it reports that sweep's largest value."""
    from substruct.case.loader import load_case
    from substruct.run.runner import run_case

    case = load_case("cases/two_rods_spring.yaml", [])
    ref = run_case(case).frf
    code, stdout, err = run(capsys, "run", "cases/two_rods_spring.yaml", "--out", tmp_path,
                            "--json", "--no-pictures")
    assert code == 0, err
    with h5py.File(tmp_path / "two_rods_spring.h5") as f:
        assert np.array_equal(f["frf/H"][()], ref.H)
        assert list(f["frf"]) == ["omega", "H", "inputs", "outputs"]
        assert "_frf_H_streaming" not in f
    import json

    assert json.loads(stdout)["frf"]["max_abs_H"] == float(np.abs(ref.H).max())


def test_the_streamed_sweep_never_holds_the_whole_output(tmp_path):
    """Two tied 100-mass chains, all 200 x 200 receptances at 200 frequencies (128 MB), into
    a file 4 MB a block: the traced peak stays below a bound derived from the block (the
    block, |block| and the finite mask taken of it: 1.6 blocks, and the copies the tap keeps,
    the checked frequencies and the kept curves) plus 8 MB for the sweep's own working set
    (matrices, factors, one solution of 200 x 200), far below the output; the same sweep
    without a sink peaks above the output's size (the measure sees the array)."""
    K, M, C, A = chains(100)
    n = K.shape[0]
    w = np.linspace(1.0, 150.0, 200)
    E, O = sp.eye_array(n, format="csc"), sp.eye_array(n, format="csr")
    system = _system(K, M, C, A)
    output = w.size * n * n * 16
    block = 4 << 20
    receptance_sweep(system, w[:3], E, O)  # compiled and cached before measuring
    with h5py.File(tmp_path / "s.h5", "w") as f:
        sink = DatasetSink(f, "H", block_bytes=block)
        tracemalloc.start()
        try:
            res = receptance_sweep(system, w, E, O, sink=sink)
            streamed = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
        assert f["H"].shape == (w.size, n, n)
    kept = 3 * n * n * 16 + w.size * KEPT_PAIRS ** 2 * 16
    bound = 1.6 * block + kept + (8 << 20)
    assert res.H.nonfinite == 0
    assert streamed < bound < output / 4, (streamed, bound, output)
    tracemalloc.start()
    try:
        receptance_sweep(system, w, E, O)
        whole = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert whole > output
