"""``/random`` and ``/srs`` read back from a result file: ``results.load`` returns what the run
wrote, value for value (``substruct info`` prints it again), and a corrupt group is refused in
one line.  The random case is a single-DOF oscillator under a white force PSD ``S0``
(one-sided, per Hz), whose displacement RMS has the closed form ``sqrt(S0 / (4 k c))``."""

import h5py
import numpy as np
import pytest

from cli_helpers import assert_one_line_error, run
from substruct.io import hdf5 as results

M, K, C, S0 = 2.0, 8.0e5, 40.0, 3.0

CASE = f"""
name: readback
units: N, m, kg, s
substructures:
  - {{name: a, type: fixed-free, mass: {M}, stiffness: {K}, damping: {C}}}
analysis:
  random:
    frequencies: {{start: 1, stop: 10000, num: 1000, spacing: log}}
    forces:
      - {{at: a@mass, psd: [[1, {S0}], [10000, {S0}]]}}
    outputs: [a@mass]
    quantity: displacement
    check: [null-space]
  transient:
    t_end: 0.05
    dt: 1.0e-4
    loads:
      - {{point: a@mass, amplitude: 100, shape: half-sine, duration: 0.002}}
    outputs: [a@mass]
  srs:
    frequencies: {{start: 5, stop: 500, num: 12}}
    Q: 10
output:
  pictures: false
"""


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    """The case run once through the command line: its result file and what it printed."""
    d = tmp_path_factory.mktemp("readback")
    (d / "readback.yaml").write_text(CASE)
    code = __import__("substruct").cli.main(["run", str(d / "readback.yaml"), "--out", str(d),
                                             "--quiet"])
    assert code == 0
    return d / "readback.h5"


def test_random_and_srs_read_back_as_written(written, capsys):
    r = results.load(written)
    assert r.random is not None and r.srs is not None
    with h5py.File(written) as f:
        for name in ("f", "input_psd", "psd", "rms"):
            np.testing.assert_array_equal(getattr(r.random, name), f["random"][name][()])
        for name in ("fn", "pos", "neg", "maxabs", "pv"):
            np.testing.assert_array_equal(getattr(r.srs, name), f["srs"][name][()])
        assert r.srs.zeta == f["srs"].attrs["zeta"] == 0.05
    assert r.random.outputs == ["a@mass"] and r.random.quantity == "displacement"
    assert not r.random.base and r.srs.outputs == ["a@mass"]
    # the numbers are the oscillator's: the closed form int_0^inf S0 |H|^2 df = S0 / (4 k c)
    # less the band below 1 Hz, where |H| = 1/k to (f/f_n)^2 = 1e-4 (above 1e4 Hz: 1e-9 of
    # it); what is left is the trapezoid rule's error on 1000 log-spaced points (1.2e-5)
    expected = np.sqrt(S0 / (4 * K * C) - S0 * 1.0 / K ** 2)
    assert abs(r.random.rms[0] / expected - 1) < 5e-5
    # a copy saved from the loaded result holds the same groups
    copy = written.parent / "copy.h5"
    results.save(r, copy)
    back = results.load(copy)
    np.testing.assert_array_equal(back.random.psd, r.random.psd)
    np.testing.assert_array_equal(back.srs.maxabs, r.srs.maxabs)
    code, out, err = run(capsys, "info", written)
    assert code == 0, err
    assert "random response (displacement" in out and "shock response spectra" in out


def test_base_random_keeps_its_kind(tmp_path):
    """A base-driven random response reads back as one (its Miles check is printed again)."""
    case = CASE.replace("fixed-free", "free-free").replace(
        "    forces:\n      - {at: a@mass, psd: [[1, 3.0], [10000, 3.0]]}\n",
        "    base: {at: [a@boundary], psd: [[1, 3.0], [10000, 3.0]]}\n").replace(
        "substructures:", "constraints:\n  - {name: table, terms: {a@boundary: 1}}\n"
                          "substructures:")
    case = case[:case.index("  transient:")] + "output:\n  pictures: false\n"
    (tmp_path / "c.yaml").write_text(case)
    assert __import__("substruct").cli.main(["run", str(tmp_path / "c.yaml"), "--out",
                                             str(tmp_path), "--quiet"]) == 0
    assert results.load(tmp_path / "readback.h5").random.base


@pytest.mark.parametrize("group, name, value, fragment", [
    ("random", "rms", np.nan, "/random/rms holds values that are not finite"),
    ("random", "psd", None, "/random/psd has shape"),
    ("srs", "maxabs", -1.0, "/srs/maxabs holds the negative value"),
])
def test_corrupt_group_is_refused(written, tmp_path, capsys, group, name, value, fragment):
    bad = tmp_path / "bad.h5"
    bad.write_bytes(written.read_bytes())
    with h5py.File(bad, "r+") as f:
        data = f[group][name][()]
        del f[group][name]
        if value is None:
            f[group].create_dataset(name, data=data[:, :0])
        else:
            data.flat[0] = value
            f[group].create_dataset(name, data=data)
    with pytest.raises(ValueError, match="not a substruct result"):
        results.load(bad)
    code, out, err = run(capsys, "info", bad)
    assert_one_line_error(code, out, err, fragment)
