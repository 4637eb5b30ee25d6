"""The ``monte_carlo:`` block of ``virtual_points:``: the shipped two-frame case with noise,
through the command line, the study written to ``/virtual_points/monte_carlo`` and read back,
and its refusals."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

from substruct import cli
from substruct.io.result_reader import load

ROOT = Path(__file__).resolve().parent.parent
CASE = ROOT / "cases" / "vpt_coupling.yaml"
DATA = ROOT / "cases" / "vpt_coupling"
ANCHOR = "          impacts: [H1, H2, H3, H4, H5, H6, H7, H8, H9]\n  - name: B"


def _case(tmp_path: Path, block: str, name: str = "case.yaml") -> Path:
    text = CASE.read_text().replace("vpt_coupling/", f"{DATA}/")
    assert ANCHOR in text
    text = text.replace(ANCHOR, ANCHOR.replace("\n  - name: B", f"\n{block}  - name: B"))
    path = tmp_path / name
    path.write_text(text)
    return path


def _run(path: Path, out: Path) -> int:
    return cli.main(["run", str(path), "--out", str(out), "--quiet", "--no-pictures"])


def _study(tmp_path: Path, level: float, seed: int = 0, tag: str = "a"):
    block = (f"      monte_carlo: {{level: {level}, samples: 6, seed: {seed}, "
             f"outputs: [A@vp:J:ux, A@vp:J:uy, A@ch:A4x], inputs: [B@ch:B14x, A@vp:J:uz]}}\n")
    out = tmp_path / f"out_{tag}"
    assert _run(_case(tmp_path, block, f"{tag}.yaml"), out) == 0
    return load(out / "vpt_coupling.h5")


def test_zero_noise_is_the_coupled_result_and_spread_grows_with_the_level(tmp_path):
    r0 = _study(tmp_path, 0.0, tag="zero")
    mc = r0.monte_carlo
    assert mc is not None and mc.samples == 6 and mc.outputs[2] == "A@ch:A4x"
    H = r0.frf.H
    o = [r0.frf.outputs.index(p) for p in mc.outputs]
    i = [r0.frf.inputs.index(p) for p in mc.inputs]
    assert np.array_equal(mc.nominal, H[:, o][:, :, i])
    assert np.array_equal(mc.mean, mc.nominal) and not mc.std.any()
    lo, hi = _study(tmp_path, 1e-5, tag="lo"), _study(tmp_path, 1e-4, tag="hi")
    s_lo, s_hi = (np.median(r.monte_carlo.relative_spread()) for r in (lo, hi))
    assert abs(np.log10(s_hi / s_lo) - 1) < 0.02  # first order in the level, same draws
    again = _study(tmp_path, 1e-4, tag="again")
    assert np.array_equal(again.monte_carlo.std, hi.monte_carlo.std)
    with h5py.File(tmp_path / "out_hi" / "vpt_coupling.h5") as f:
        assert f["virtual_points/monte_carlo"].attrs["level"] == 1e-4
        assert f["virtual_points/monte_carlo/bands"].shape == (3, 40, 3, 2)


def test_refusals(tmp_path, capsys):
    for block, field in (
            ("      monte_carlo: {level: 0.01, samples: 1}\n", "monte_carlo.samples"),
            ("      monte_carlo: {level: 0.01, samples: 5, sigma: 2}\n", "monte_carlo.sigma"),
            ("      monte_carlo: {level: 0.01, samples: 5, outputs: [B@ch:B14x]}\n",
             "monte_carlo.outputs[0]"),
            ("      monte_carlo: {level: 0.01, samples: 5, percentiles: [101]}\n",
             "monte_carlo.percentiles[0]")):
        out = tmp_path / "out"
        assert _run(_case(tmp_path, block), out) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and field in err[0], err
        assert not (out / "vpt_coupling.h5").exists()


def test_samples_as_dask_tasks_give_the_same_bits(tmp_path):
    """``substruct run --workers 2`` runs the samples on a local Dask cluster: the study is
    the in-process one bit for bit (each sample seeded by its index)."""
    pytest.importorskip("distributed")
    block = "      monte_carlo: {level: 0.01, samples: 4, seed: 3}\n"
    case = _case(tmp_path, block)
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1",
           "MPLBACKEND": "Agg", "SUBSTRUCT_PROGRESS": "1"}
    runs = {}
    for tag, extra in (("serial", []), ("dask", ["--workers", "2"])):
        done = subprocess.run([sys.executable, "-m", "substruct.cli", "run", str(case),
                               "--out", str(tmp_path / tag), "--no-pictures", *extra],
                              capture_output=True, text=True, timeout=600, env=env,
                              cwd=tmp_path)
        assert done.returncode == 0, done.stderr[-3000:]
        runs[tag] = load(tmp_path / tag / "vpt_coupling.h5").monte_carlo
        if extra:
            assert "Monte Carlo samples on LocalCluster (2 workers)" in done.stderr
    for key in ("nominal", "mean", "std", "bands"):
        assert np.array_equal(getattr(runs["serial"], key), getattr(runs["dask"], key)), key
    assert runs["dask"].std.any()


def test_the_run_prints_the_spread(tmp_path, capsys):
    block = "      monte_carlo: {level: 1.0e-4, samples: 5, seed: 2}\n"
    out = tmp_path / "out"
    assert cli.main(["run", str(_case(tmp_path, block)), "--out", str(out),
                     "--no-pictures"]) == 0
    mc = load(out / "vpt_coupling.h5").monte_carlo
    spread = mc.relative_spread()
    line = [x for x in capsys.readouterr().out.splitlines() if "samples" in x]
    assert line == [f"  noise 0.0001 on the measured receptances, 5 samples: relative spread "
                    f"of the coupled result median {np.median(spread):.3g}, max "
                    f"{spread.max():.3g}"]
