"""The case-file door to model mixing (``analysis.semm``): a chain of six masses given by its
matrices is the numerical model; the "measurement" is the same chain with two springs and a
mass changed (closed form, (K - w^2 M + i w C)^-1), at three sensors and two impacts.  The
mixed model of the run equals the library's on the closed-form numerical receptance, holds
the measurement at the boundary, and its validation coherence is that of the library; the
refusals.

Tolerance: the program's receptance of the chain agrees with the closed form to about
1e-13 relative; the mix multiplies that by the gain of the pseudo-inverses (kappa of the
boundary block below 1e3 here): 1e-8.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from substruct import cli
from substruct.analysis.frf.semm import semm
from substruct.io.result_reader import load

N = 6
W = np.linspace(20.0, 600.0, 25)
LABELS = [f"P@q{i + 1}" for i in range(N)]
OUTS, INS = ["P@q2", "P@q4", "P@q6"], ["P@q2", "P@q6"]
BOUNDARY_OUT = ["P@q2", "P@q6"]


def _matrices(k, m):
    K = np.zeros((N, N))
    for i in range(N):
        K[i, i] += k[i] + (k[i + 1] if i + 1 < N else 0.0)
        if i + 1 < N:
            K[i, i + 1] = K[i + 1, i] = -k[i + 1]
    return K, np.diag(m), 1e-4 * K


K0, M0, C0 = _matrices(np.full(N, 1.0e5), np.ones(N))
k1, m1 = np.full(N, 1.0e5), np.ones(N)
k1[[2, 4]] *= [1.4, 0.7]
m1[3] *= 1.3
K1, M1, C1 = _matrices(k1, m1)


def _Y(K, M, C):
    return np.linalg.inv(K[None] - W[:, None, None] ** 2 * M[None] + 1j * W[:, None, None] * C[None])


def _sub(Y, outs, ins):
    return Y[:, [LABELS.index(o) for o in outs]][:, :, [LABELS.index(i) for i in ins]]


def _write(tmp_path: Path, H: np.ndarray, boundary: bool = True, omega=W) -> Path:
    np.savez(tmp_path / "measured.npz", omega=omega, outputs=np.array(OUTS),
             inputs=np.array(INS), H=H)
    mat = lambda A: "[" + ", ".join("[" + ", ".join(f"{v:.17g}" for v in row) + "]"  # noqa
                                    for row in A) + "]"
    b = f"\n    boundary: {{outputs: [{', '.join(BOUNDARY_OUT)}], inputs: [{', '.join(INS)}]}}" \
        if boundary else ""
    text = f"""name: chain_semm
substructures:
  - name: P
    type: matrices
    M: {mat(M0)}
    K: {mat(K0)}
    C: {mat(C0)}
    labels: [{', '.join(s.split('@')[1] for s in LABELS)}]
analysis:
  frf:
    omega: [{', '.join(f'{w:.17g}' for w in W)}]
    inputs: [{', '.join(LABELS)}]
    outputs: [{', '.join(LABELS)}]
  semm:
    measured: measured.npz{b}
"""
    path = tmp_path / "chain_semm.yaml"
    path.write_text(text)
    return path


def _run(path: Path, out: Path) -> int:
    return cli.main(["run", str(path), "--out", str(out), "--quiet", "--no-pictures"])


def test_the_run_mixes_as_the_library(tmp_path, capsys):
    E = _sub(_Y(K1, M1, C1), OUTS, INS)
    assert _run(_write(tmp_path, E), tmp_path / "out") == 0
    res = load(tmp_path / "out" / "chain_semm.h5")
    s = res.semm
    Yn = _Y(K0, M0, C0)
    assert np.abs(res.frf.H - Yn).max() < 1e-12 * np.abs(Yn).max()  # the program's model
    lib = semm(Yn, LABELS, LABELS, E, OUTS, INS, BOUNDARY_OUT, INS)
    assert np.abs(s.Y - lib.Y).max() < 1e-8 * np.abs(lib.Y).max()
    # the boundary holds the measurement; P@q4 (a sensor off the boundary) validates
    bb = _sub(s.Y, BOUNDARY_OUT, INS)
    Ebb = E[:, [0, 2]]
    assert np.abs(bb - Ebb).max() < 1e-8 * np.abs(Ebb).max()
    assert s.validation.tolist() == [[False, False], [True, True], [False, False]]
    np.testing.assert_allclose(s.indicator, lib.indicator, atol=1e-8)
    assert s.indicator.min() < 0.99  # the changed mass at q4 shows
    capsys.readouterr()
    assert cli.main(["info", str(tmp_path / "out" / "chain_semm.h5")]) == 0
    assert "model mixing: 6 x 6 model, boundary 2 x 2 of 3 x 2 measured; validation " \
        "coherence min" in capsys.readouterr().out


def test_a_measurement_equal_to_the_model_changes_nothing(tmp_path):
    Yn = _Y(K0, M0, C0)
    assert _run(_write(tmp_path, _sub(Yn, OUTS, INS), boundary=False), tmp_path / "out") == 0
    s = load(tmp_path / "out" / "chain_semm.h5").semm
    assert np.abs(s.Y - Yn).max() < 1e-10 * np.abs(Yn).max()
    assert np.isnan(s.indicator).all()  # every measured entry is on the boundary


@pytest.mark.parametrize("what, field, words", [
    ("nan", "analysis.semm.measured", "the receptance at P@q4/P@q6 is (nan+0j) at frequency "
     "index 3"),
    ("grid", "analysis.semm.measured", "are not those of analysis.frf.omega"),
    ("boundary", "analysis.semm.boundary.outputs[0]", "not measured"),
    ("unknown", "analysis.semm.measured", "measured output 'P@q9' is not among the outputs"),
])
def test_refused_in_one_line(tmp_path, capsys, what, field, words):
    E = _sub(_Y(K1, M1, C1), OUTS, INS)
    if what == "nan":
        E[3, 1, 1] = np.nan
    path = _write(tmp_path, E, omega=W * (1.001 if what == "grid" else 1.0))
    if what == "boundary":
        path.write_text(path.read_text().replace("outputs: [P@q2, P@q6]", "outputs: [P@q3]"))
    if what == "unknown":
        np.savez(tmp_path / "measured.npz", omega=W, outputs=np.array([OUTS[0], "P@q9", OUTS[2]]),
                 inputs=np.array(INS), H=E)
    assert _run(path, tmp_path / "out") == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and f": {field}: " in err and words in err, err
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


def test_the_extended_form_from_the_case(tmp_path, capsys):
    """``form: extended`` with every measured channel on the boundary (3 sensors x 2 impacts,
    no square block): the run's mix is the library's extended mix, holds the measurement at
    every measured entry, and carries the channel coherence criterion (written, read back,
    printed) equal to the library's."""
    from substruct.analysis.frf.semm import channel_coherence
    E = _sub(_Y(K1, M1, C1), OUTS, INS)
    path = _write(tmp_path, E, boundary=False)
    path.write_text(path.read_text().replace("measured: measured.npz",
                                             "measured: measured.npz\n    form: extended"))
    assert _run(path, tmp_path / "out") == 0
    s = load(tmp_path / "out" / "chain_semm.h5").semm
    Yn = _Y(K0, M0, C0)
    lib = semm(Yn, LABELS, LABELS, E, OUTS, INS, form="extended")
    assert s.form == "extended"
    assert np.abs(s.Y - lib.Y).max() < 1e-8 * np.abs(lib.Y).max()
    assert np.abs(_sub(s.Y, OUTS, INS) - E).max() < 1e-8 * np.abs(E).max()
    assert s.channel_coherence is not None and s.channel_coherence.shape == (len(W), 3)
    ref = channel_coherence(Yn, LABELS, LABELS, E, OUTS, INS)
    np.testing.assert_allclose(s.channel_coherence, ref, atol=1e-8)
    capsys.readouterr()
    assert cli.main(["info", str(tmp_path / "out" / "chain_semm.h5")]) == 0
    assert "model mixing (extended): 6 x 6 model, boundary 3 x 2 of 3 x 2 measured" \
        in capsys.readouterr().out


@pytest.mark.parametrize("form", ["standard", "extended"])
def test_the_coherence_picture(tmp_path, form):
    """``substruct run`` draws ``<case>_semm.png``; the curves drawn are the stored
    coherences: the validation entry P@q4 / each input and the indicator, and with the
    extended form each measured output's channel coherence."""
    from substruct.viz.testlab_picture import draw_semm
    E = _sub(_Y(K1, M1, C1), OUTS, INS)
    path = _write(tmp_path, E)
    if form == "extended":
        path.write_text(path.read_text().replace("measured: measured.npz",
                                                 "measured: measured.npz\n    form: extended"))
    out = tmp_path / "out"
    assert cli.main(["run", str(path), "--out", str(out), "--quiet"]) == 0
    assert (out / "chain_semm_semm.png").stat().st_size > 10_000
    res = load(out / "chain_semm.h5")
    fig = draw_semm(res)
    lines = {ln.get_label(): ln.get_ydata() for ax in fig.axes for ln in ax.get_lines()}
    s = res.semm
    for i, name in enumerate(INS):
        assert np.array_equal(lines[f"P@q4 / {name}"], s.coherence[:, 1, i])
    assert np.array_equal(lines["validation indicator"], s.indicator)
    if form == "extended":
        for j, name in enumerate(OUTS):
            assert np.array_equal(lines[name], s.channel_coherence[:, j])
    else:
        assert len(fig.axes) == 1
