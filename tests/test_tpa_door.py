"""The case-file door to transfer path analysis (``analysis.tpa``): the shipped example
``cases/vpt_coupling_tpa.yaml`` through the command line against the blocked forces of the
source computed from the finite-element model of A alone, f = Y_A,JJ^-1 Y_A,Js F; the
result read back; the refusals.

Tolerance: the finite-element receptances agree between two formulations to about 3.5e-10 of
their largest entry (docs/testlab.md); 1e-8 leaves a margin of about 30.
"""

from __future__ import annotations

import json
import shutil
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest
import scipy.sparse as sp

from substruct import cli
from substruct.io.result_reader import load

sys.path.insert(0, str(Path(__file__).resolve().parent))
from make_vpt_case import TPA_SOURCE  # noqa: E402
from testlab_models import node_dofs, part_a, receptance  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
CASE = ROOT / "cases" / "vpt_coupling_tpa.yaml"
EXACT = 1e-8
VP = ("ux", "uy", "uz", "rx", "ry", "rz")


def _run(path: Path, out: Path) -> int:
    return cli.main(["run", str(path), "--out", str(out), "--quiet", "--no-pictures"])


def _case(tmp_path: Path, *edits: tuple[str, str]) -> Path:
    text = CASE.read_text()
    for d in ("vpt_coupling_tpa/", "vpt_coupling/"):
        text = text.replace(f" {d}", f" {ROOT / 'cases' / d}/")
    for old, new in edits:
        assert old in text, old
        text = text.replace(old, new)
    path = tmp_path / "case.yaml"
    path.write_text(text)
    return path


@pytest.fixture(scope="module")
def truth():
    A = part_a()
    J = node_dofs(A, 1)
    src = sp.csr_array(sp.vstack([A.locate(d) for d, _ in TPA_SOURCE]))
    u_free = receptance(A, J, src) @ np.array([a for _, a in TPA_SOURCE])
    return np.linalg.solve(receptance(A, J, J), u_free[:, :, None])[:, :, 0]


def _rel(a, b):
    return float(np.abs(a - b).max() / np.abs(b).max())


def test_shipped_example_finds_the_blocked_forces_of_the_source(tmp_path, truth, capsys):
    assert _run(CASE, tmp_path / "out") == 0
    path = tmp_path / "out" / "vpt_coupling_tpa.h5"
    res = load(path)
    tpa = res.tpa
    assert tpa is not None and tpa.method == "in_situ"
    assert tpa.interface == [f"A@vp:J:{c}" for c in VP]
    assert len(tpa.indicators) == 9 and tpa.targets == ["B@ch:T1", "B@ch:T2", "B@ch:T3"]
    err = _rel(tpa.forces, truth)
    print(f"blocked forces vs A alone: {err:.2g}, validation {tpa.error.max():.2g}")
    assert err < EXACT
    assert tpa.error.max() < EXACT
    # the paths add up to the prediction, which is the coupled receptance times the forces
    np.testing.assert_allclose(tpa.contributions.sum(axis=2), tpa.predicted, rtol=0,
                               atol=1e-14 * np.abs(tpa.predicted).max())
    H = res.frf.H[:, [res.frf.outputs.index(t) for t in tpa.targets]]
    assert _rel(np.einsum("ktc,kc->kt", H, tpa.forces), tpa.predicted) < 1e-14
    # the virtual points' indicators are read back too, and info prints both
    assert set(res.virtual_points) == {"A", "B"}
    assert np.abs(res.virtual_points["B"].specific_u["S1x"] - 1).max() < 1e-8
    capsys.readouterr()
    assert cli.main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "transfer paths (in_situ): blocked forces at 6 interface coordinate(s) from 9" in out
    assert "virtual points of B: min consistency" in out
    assert cli.main(["info", "--json", str(path)]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["tpa"]["targets"] == tpa.targets
    assert data["tpa"]["error_max"] == pytest.approx(float(tpa.error.max()), rel=1e-12)
    assert abs(data["virtual_points"]["A"]["specific_u"] - 1) < 1e-8
    # export reads the result (with its /tpa) and writes the receptances
    assert cli.main(["export", str(path), "--format", "uff", "--out",
                     str(tmp_path / "exp")]) == 0
    assert (tmp_path / "exp" / "vpt_coupling_tpa.uff").is_file()
    # a corrupt /tpa or /virtual_points is refused by the reader, naming the dataset
    for name, value in (("tpa/error", np.nan), ("virtual_points/1/specific_u", 3.0)):
        bad = tmp_path / "bad.h5"
        shutil.copy(path, bad)
        with h5py.File(bad, "r+") as f:
            data = f[name][()]
            data.flat[0] = value
            f[name][...] = data
        with pytest.raises(ValueError, match=f"not a substruct result: /{name} holds"):
            load(bad)


def test_matrix_inverse_and_regularised_in_situ(tmp_path, truth):
    joint = ", ".join(f"A@vp:J:{c}" for c in VP)
    mi = _case(tmp_path, ("              B@ch:T1,", f"              B@ch:T1, {joint},"),
               ("method: in_situ", "method: matrix_inverse"),
               ("    indicators: [B@ch:I1, B@ch:I2, B@ch:I3, B@ch:I4, B@ch:I5, B@ch:I6, "
                "B@ch:I7, B@ch:I8,\n                 B@ch:I9]\n", ""))
    assert _run(mi, tmp_path / "mi") == 0
    tpa = load(tmp_path / "mi" / "vpt_coupling_tpa.h5").tpa
    assert tpa.method == "matrix_inverse" and tpa.indicators == tpa.interface
    assert _rel(tpa.forces, truth) < EXACT
    # a truncation that drops nothing (rtol below round-off) gives the plain answer; one
    # that keeps 3 of 6 singular values is a different (biased) answer: the option is used
    for rule, close in (("rtol: 1.0e-14", True), ("rank: 3", False)):
        reg = _case(tmp_path, ("    targets: [", f"    regularization: {{method: tsvd, {rule}, "
                                                 "length: 0.3}\n    targets: ["))
        assert _run(reg, tmp_path / rule[:4]) == 0
        tpa = load(tmp_path / rule[:4] / "vpt_coupling_tpa.h5").tpa
        assert tpa.method == "in_situ (tsvd)"
        assert (_rel(tpa.forces, truth) < EXACT) == close


def _bad_responses(tmp_path: Path, what: str) -> str:
    with np.load(ROOT / "cases" / "vpt_coupling_tpa" / "operating.npz") as z:
        arrays = {k: z[k] for k in z.files}
    if what == "nan":
        arrays["u"] = arrays["u"].copy()
        arrays["u"][7, 2] = np.nan
    else:
        arrays["omega"] = arrays["omega"][:-1]
        arrays["u"] = arrays["u"][:-1]
    path = tmp_path / f"{what}.npz"
    np.savez(path, **arrays)
    return str(path)


@pytest.mark.parametrize("edit, field, words", [
    (("indicators: [B@ch:I1, B@ch:I2, B@ch:I3, B@ch:I4,", "indicators: ["),
     "analysis.tpa.indicators", "at least as many indicators as interface coordinates (6)"),
    (("targets: [B@ch:T1,", "targets: [B@ch:I1, B@ch:T1,"), "analysis.tpa.targets[0]",
     "must not be used to find the forces"),
    (("targets: [B@ch:T1,", "targets: [B@ch:S1x, B@ch:T1,"), "analysis.tpa.targets[0]",
     "no response at it in operating.npz"),
    (("interface: [A@vp:J:ux,", "interface: [B@ch:I1,"), "analysis.tpa.interface[0]",
     "not an input of analysis.frf"),
    (("method: in_situ", "method: matrix_inverse"), "analysis.tpa.indicators",
     "matrix_inverse uses the responses at the interface itself"),
    (("method: in_situ", "method: blocked"), "analysis.tpa.method", ""),
    (("method: in_situ", "method: in_situ\n    pseudo: true"), "analysis.tpa.pseudo", ""),
    ("nan", "analysis.tpa.responses", "the response at B@ch:I3 is (nan+0j) at frequency index 7"),
    ("grid", "analysis.tpa.responses", "are not those of analysis.frf.omega"),
])
def test_refused_in_one_line(tmp_path, capsys, edit, field, words):
    if isinstance(edit, str):
        bad = _bad_responses(tmp_path, edit)
        edit = (f"responses: {ROOT / 'cases' / 'vpt_coupling_tpa' / 'operating.npz'}",
                f"responses: {bad}")
    path = _case(tmp_path, edit)
    assert _run(path, tmp_path / "out") == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and f": {field}: " in err and words in err, err
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())
