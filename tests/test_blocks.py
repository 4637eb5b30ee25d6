"""Large arrays a block at a time (substruct/io/blocks.py): the receptances and snapshots
written in blocks read back equal to the arrays in memory, bit for bit; reductions in blocks
equal the whole-array ones; ``substruct run`` writes the file its library call computes."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import h5py
import numpy as np
import pytest

from substruct import cli
from substruct.analysis.results import Receptance
from substruct.io import hdf5 as results
from substruct.io.blocks import block_rows, chunk_rows, max_abs, write_blocks

from test_results import make_result

ROOT = Path(__file__).resolve().parents[1]


def _receptance(F: int, n_out: int, n_in: int, seed: int = 3) -> Receptance:
    rng = np.random.default_rng(seed)
    H = rng.standard_normal((F, n_out, n_in)) + 1j * rng.standard_normal((F, n_out, n_in))
    H[5, 1, 2] = np.finfo(float).tiny + 1j * np.finfo(float).max  # extremes kept bit for bit
    return Receptance(method="null-space", omega=np.linspace(1.0, 9.0, F), H=H,
                      inputs=[f"i{j}" for j in range(n_in)],
                      outputs=[f"o{i}" for i in range(n_out)], agreement={"kkt": 1e-13})


@pytest.mark.parametrize("block_bytes, chunk_bytes", [(1, 1), (3 * 96, 2 * 96), (200 * 96, 96),
                                                      (7 * 96, 4 * 96), (1 << 30, 1 << 20)])
def test_receptances_written_in_blocks_read_back_identical(tmp_path, block_bytes, chunk_bytes,
                                                          monkeypatch):
    """37 frequencies of 2 x 3 outputs (96 bytes a frequency), written from one frequency a
    block to all at once, in chunks of one to all frequencies: the file reads back equal to
    the array in memory, and it was written the number of blocks the sizes say."""
    frf = _receptance(37, 2, 3)
    result = dataclasses.replace(make_result(), frf=frf)
    calls = []
    real = h5py.Dataset.__setitem__

    def counted(self, key, value):
        calls.append((key, np.shape(value)))
        return real(self, key, value)

    monkeypatch.setattr(h5py.Dataset, "__setitem__", counted)
    path = results.save(result, tmp_path / "r.h5", block_bytes=block_bytes,
                        chunk_bytes=chunk_bytes)
    monkeypatch.undo()
    chunk = max(1, min(37, chunk_bytes // 96))
    step = max(chunk, max(1, block_bytes // 96) // chunk * chunk)
    writes = [c for c in calls if len(c[1]) == 3]
    assert [s[0] for _, s in writes] == [min(step, 37 - k) for k in range(0, 37, step)]
    back = results.load(path)
    assert back.frf is not None
    assert np.array_equal(back.frf.H, frf.H, equal_nan=True)
    assert back.frf.H.dtype == frf.H.dtype and back.frf.H.shape == (37, 2, 3)
    assert np.array_equal(back.frf.omega, frf.omega)
    with h5py.File(path, "r") as f:
        assert f["frf/H"].chunks == (chunk, 2, 3)


def test_chunks_and_blocks_are_whole_frequencies():
    # a 400 x 400 complex receptance: 2.56 MB a frequency, over the 1 MiB chunk target
    assert chunk_rows((1000, 400, 400), 16) == 1
    assert block_rows((1000, 400, 400), 16) == (64 << 20) // (400 * 400 * 16) == 26
    # 2 x 3 complex: 96 bytes; chunks of 10922 frequencies cut to the 37 there are
    assert chunk_rows((37, 2, 3), 16) == 37
    assert block_rows((100, 2, 3), 16, block_bytes=500, chunk=4) == 4  # one chunk at least
    assert block_rows((100, 2, 3), 16, block_bytes=1000, chunk=4) == 8  # 10 rows, cut to 8


@pytest.mark.parametrize("compression", ["gzip", "lzf"])
def test_compressed_receptances_read_back_identical(tmp_path, compression):
    frf = _receptance(40, 4, 5, seed=7)
    result = dataclasses.replace(make_result(), frf=frf)
    path = results.save(result, tmp_path / "r.h5", block_bytes=16 * 20 * 3,
                        compression=compression)
    with h5py.File(path, "r") as f:
        assert f["frf/H"].compression == compression
    back = results.load(path)
    assert np.array_equal(back.frf.H, frf.H, equal_nan=True)


def test_unknown_compression_is_refused(tmp_path):
    with h5py.File(tmp_path / "x.h5", "w") as f:
        with pytest.raises(ValueError, match="unknown compression 'zstd'"):
            write_blocks(f, "x", np.zeros((3, 2)), compression="zstd")


@pytest.mark.parametrize("shape", [(0, 3, 4), (5, 0, 2), (4,), ()])
def test_empty_and_small_arrays_are_written_as_they_are(tmp_path, shape):
    a = np.arange(int(np.prod(shape)), dtype=float).reshape(shape) * 0.5
    with h5py.File(tmp_path / "x.h5", "w") as f:
        write_blocks(f, "a", a, block_bytes=8)
    with h5py.File(tmp_path / "x.h5", "r") as f:
        back = f["a"][()]
    assert np.shape(back) == shape and np.array_equal(back, a)


@pytest.mark.parametrize("block_bytes", [1, 100, 1 << 30])
def test_max_abs_in_blocks_is_the_whole_array_max(block_bytes):
    H = _receptance(23, 3, 3).H
    H[5, 1, 2] = 0  # the nan of _receptance taken out: a plain maximum
    H[17, 2, 0] = 40.0 - 30.0j  # the largest, 50, in a late block
    assert max_abs(H, block_bytes) == float(np.abs(H).max()) == 50.0
    assert max_abs(np.zeros((0, 3))) == 0.0


def test_the_command_writes_the_receptances_the_library_computes(tmp_path, capsys):
    """``substruct run`` (the result computed, drawn and written in its child process) of an
    FRF case: the file holds exactly the receptances of ``run_case`` in this process, and
    ``--json`` reports their largest magnitude."""
    import substruct

    case = ROOT / "cases" / "three_dof_frf.yaml"
    out = tmp_path / "out"
    assert cli.main(["run", str(case), "--out", str(out), "--json", "--no-pictures"]) == 0
    report = json.loads(capsys.readouterr().out)
    mem = substruct.run_case(substruct.load_case(str(case)))
    back = results.load(out / f"{mem.case_name}.h5")
    assert np.array_equal(back.frf.H, mem.frf.H)
    assert np.array_equal(back.frf.omega, mem.frf.omega)
    assert report["frf"]["max_abs_H"] == float(np.abs(mem.frf.H).max())


@pytest.mark.parametrize("quantity", ["mobility", "accelerance"])
def test_mobility_and_accelerance_converted_in_place_are_the_same_numbers(quantity):
    """``analysis.frf.quantity`` converts the computed receptances in place (no second array
    of the size of the output): bit for bit the converted copy of ``as_quantity``."""
    import substruct
    from substruct.analysis.frf.quantity import as_quantity

    grid = "analysis.frf.omega={start: 0.5, stop: 3, num: 9}"
    case = ROOT / "cases" / "three_dof_frf.yaml"
    ref = substruct.run_case(substruct.load_case(str(case), [grid])).frf
    got = substruct.run_case(substruct.load_case(
        str(case), [grid, f"analysis.frf.quantity={quantity}"])).frf
    expected = as_quantity(ref, quantity)
    assert got.quantity == quantity and expected.H is not ref.H
    assert np.array_equal(got.H, expected.H)
    assert np.abs(got.H).max() > 0
