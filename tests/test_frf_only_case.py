"""Assemblies of FRF substructures only, through a case file and ``substruct run``: two parts
given as the computed receptances of two known models (one as UFF 58, one as NPZ) coupled by
LM-FBS agree with the finite-element coupling of the same models; a known part given with
``decouple: true`` is removed from a measured assembly; modes of such an assembly are refused."""

from __future__ import annotations

import numpy as np
import pytest

from substruct import cli
from substruct.analysis.api import receptance_sweep
from substruct.case.loader import CaseError, load_case
from substruct.io.hdf5 import load
from substruct.io.uff import uff58_sets, write_uff
from substruct.run.runner import build_model, run_case
from test_frf_coupling import B_LABELS, _assembly_parts, _b_matrices_spec, _case, _matrices

A_LABELS = [f"{k}:x" for k in range(1, 7)]
HZ = np.linspace(0.5, 12, 116)


def _receptance(M, C, K, w):
    eye = np.eye(len(M))
    return receptance_sweep(K, M, C, None, w, eye, eye, method="kkt").H


def _frf_only_case(tmp_path):
    """The case of test_frf_coupling with A given as its receptances in UFF 58 and B in NPZ."""
    w = 2 * np.pi * HZ
    (MA, CA, KA), (MB, CB, KB) = _matrices()
    write_uff(tmp_path / "a.uff", uff58_sets(w, _receptance(MA, CA, KA, w), A_LABELS,
                                             A_LABELS))
    np.savez(tmp_path / "b.npz", H=_receptance(MB, CB, KB, w), labels=np.array(B_LABELS),
             freq_hz=HZ)
    return tmp_path / "frf_only.yaml", f"""
name: frf_only
units: "N, m, kg, s"
substructures:
  - {{name: A, type: frf, file: a.uff}}
  - {{name: B, type: frf, file: b.npz}}
connections:
  - [A@6:x, B@1:x]
  - [A@4:x, B@3:x]
analysis:
  frf:
    omega: {{start: 0.5, stop: 12, num: 116}}
    units: Hz
    inputs: [A@2:x, B@4:x]
    outputs: [A@2:x, A@6:x, B@2:x, B@4:x]
    magnitude: db
"""


def test_frf_only_assembly_runs_and_equals_the_fe_coupling(tmp_path, capsys):
    path, text = _frf_only_case(tmp_path)
    path.write_text(text)
    out = tmp_path / "out"
    assert cli.main(["run", str(path), "--out", str(out), "--quiet"]) == 0, \
        capsys.readouterr().err
    assert sorted(p.name for p in out.iterdir()) == ["frf_only.h5", "frf_only_frf.png"]
    frf = load(out / "frf_only.h5").frf
    case = load_case(_case(_b_matrices_spec()))
    fe = run_case(case, model=build_model(case)).frf
    assert frf.method == "lm-fbs"
    assert frf.inputs == ["A@2:x", "B@4:x"]
    assert np.abs(frf.H - fe.H).max() / np.abs(fe.H).max() < 1e-9
    assert frf.agreement["generalized-inverse"] < 1e-9
    assert frf.constraint_residual < 1e-12


def test_frf_only_grid_refused_or_interpolated(tmp_path):
    """A grid of the case that is not the files' is refused; with interpolate: linear, the
    interpolated receptances are coupled (a grid of the files' points: the same numbers)."""
    path, text = _frf_only_case(tmp_path)
    path.write_text(text.replace("num: 116", "num: 40"))
    with pytest.raises(CaseError, match="the frequency grid of A differs from analysis.frf.omega"):
        run_case(load_case(path))
    full = run_case(load_case(path, ["analysis.frf.omega.num=116"])).frf
    path.write_text(text.replace("num: 116", "num: 24").replace("stop: 12", "stop: 12")
                    .replace("a.uff}", "a.uff, interpolate: linear}")
                    .replace("b.npz}", "b.npz, interpolate: linear}"))
    frf = run_case(load_case(path)).frf  # 24 points of the 116: every fifth
    assert np.abs(frf.H - full.H[::5]).max() / np.abs(full.H).max() < 1e-9


def test_decoupling_through_a_case_file(tmp_path):
    """``decouple: true``: the assembly of A and B (measured: its receptances on A's six
    coordinates and B's two others) less B joined at B's four coordinates is A, to 1e-9."""
    w, Y_ab, Y_a, Y_b = _assembly_parts()
    ab = [f"q{i}" for i in range(1, 7)] + ["b2", "b4"]
    np.savez(tmp_path / "ab.npz", H=Y_ab, labels=np.array(ab), omega=w)
    np.savez(tmp_path / "b.npz", H=Y_b, labels=np.array(B_LABELS), omega=w)
    outputs = [f"AB@q{i}" for i in range(1, 7)]
    text = f"""
name: decoupled
substructures:
  - {{name: AB, type: frf, file: {tmp_path / 'ab.npz'}}}
  - {{name: B, type: frf, file: {tmp_path / 'b.npz'}, decouple: true}}
connections:
  - [AB@q6, B@1:x]
  - [AB@b2, B@2:x]
  - [AB@q4, B@3:x]
  - [AB@b4, B@4:x]
analysis:
  frf: {{omega: {list(map(float, w))}, inputs: {outputs}, outputs: {outputs}}}
"""
    frf = run_case(load_case(text)).frf
    assert frf.method == "generalized-inverse decoupling"
    assert np.abs(frf.H - Y_a).max() / np.abs(Y_a).max() < 1e-9
    assert frf.agreement == {}  # no second form to check a rank-deficient interface with


def test_modes_of_an_frf_only_assembly_refused(tmp_path):
    path, text = _frf_only_case(tmp_path)
    path.write_text(text.replace("analysis:\n", "analysis:\n  modes: {count: 2}\n"))
    case = load_case(path)
    with pytest.raises(CaseError, match=r"analysis.modes: the coupled modes of an assembly "
                                        r"with FRF substructures \(A, B\) are not computed"):
        build_model(case)
