"""``substruct compare A.h5 B.h5`` on receptances: two runs of a one-coordinate superelement
(mass 1, stiffness 100 in A and 144 in B, undamped) with a recovery matrix ``[2]``, their peaks
over the frequencies of each run checked against the closed form ``H = 1 / (k - omega^2 m)``:
peak ``|H|``, its frequency, the ratio B/A and the difference in dB, for ``/frf`` and for the
recovered receptance; receptances of two different quantities are refused in one line."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from substruct import cli

OMEGA_A = [2.0, 9.0, 11.0, 13.0, 20.0]
OMEGA_B = [3.0, 11.0, 13.0]


def _case(tmp: Path, name: str, k: float, omega: list[float], modes: bool,
          quantity: str = "receptance") -> Path:
    np.savez(tmp / f"{name}.npz", M=np.array([[1.0]]), K=np.array([[k]]),
             DTM=np.array([[2.0]]))
    path = tmp / f"{name}.yaml"
    path.write_text(f"""name: {name}
substructures:
  - name: se
    type: superelement
    file: {name}.npz
    M: M
    K: K
    dofs: [[1, "1"]]
    free: false
    recovery:
      - {{name: dtm, matrix: DTM, of: displacement, labels: [tip]}}
analysis:
{"  modes: {count: 1}" if modes else ""}
  frf:
    omega: {omega}
    inputs: [se@1:ux]
    outputs: [se@1:ux]
    quantity: {quantity}
""")
    return path


def _run(tmp: Path, case: Path) -> Path:
    assert cli.main(["run", str(case), "--out", str(tmp / "out"), "--force",
                     "--no-pictures"]) == 0
    return tmp / "out" / f"{case.stem}.h5"


def _hand_peak(k: float, omega: list[float]) -> tuple[float, float]:
    """The largest ``|1 / (k - w^2)|`` over ``omega`` and its frequency in Hz, by hand."""
    mags = [abs(1.0 / (k - w * w)) for w in omega]
    i = mags.index(max(mags))
    return mags[i], omega[i] / (2.0 * math.pi)


@pytest.mark.parametrize("modes", [False, True])
def test_receptance_peaks_against_the_closed_form(tmp_path: Path, capsys, modes: bool) -> None:
    a = _run(tmp_path, _case(tmp_path, "a", 100.0, OMEGA_A, modes))
    b = _run(tmp_path, _case(tmp_path, "b", 144.0, OMEGA_B, modes))
    capsys.readouterr()
    assert cli.main(["compare", str(a), str(b), "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)["frf_peaks"]
    assert [(r["kind"], r["quantity"], r["input"]) for r in rows] == [
        ("frf", "se@1:ux", "se@1:ux"), ("recovery", "se.dtm@tip", "se@1:ux")]
    pa, fa = _hand_peak(100.0, OMEGA_A)   # 1/19 at 9 rad/s
    pb, fb = _hand_peak(144.0, OMEGA_B)   # 1/23 at 11 rad/s
    assert (pa, pb) == (1.0 / 19.0, 1.0 / 23.0)
    for r, scale in zip(rows, (1.0, 2.0)):
        # one coordinate: the KKT solve of 1x1 is the closed form to a few ulps
        np.testing.assert_allclose([r["peak_a"], r["peak_b"]], [scale * pa, scale * pb],
                                   rtol=1e-14)
        assert r["f_a_hz"] == pytest.approx(fa, rel=1e-15)
        assert r["f_b_hz"] == pytest.approx(fb, rel=1e-15)
        assert r["ratio"] == pytest.approx(19.0 / 23.0, rel=1e-13)
        assert r["db"] == pytest.approx(20.0 * math.log10(19.0 / 23.0), rel=1e-12)
    assert cli.main(["compare", str(a), str(b)]) == 0
    text = capsys.readouterr().out
    assert "receptance peaks (2 output/input pairs in both; largest change first):" in text
    line = next(t for t in text.splitlines() if t.strip().startswith("se.dtm@tip / se@1:ux"))
    assert line.split()[-6:] == [f"{2 * pa:.4g}", f"{fa:.4g}", f"{2 * pb:.4g}", f"{fb:.4g}",
                                 f"{19 / 23:.4g}", f"{20 * math.log10(19 / 23):.2f}"]


def test_different_quantities_are_refused(tmp_path: Path, capsys) -> None:
    a = _run(tmp_path, _case(tmp_path, "a", 100.0, OMEGA_A, False))
    b = _run(tmp_path, _case(tmp_path, "b", 144.0, OMEGA_B, False, quantity="accelerance"))
    capsys.readouterr()
    assert cli.main(["compare", str(a), str(b)]) == 2
    cap = capsys.readouterr()
    err = cap.err.strip().splitlines()
    assert len(err) == 1 and err[0].endswith(
        "/frf: A's is receptance and B's accelerance: peaks of different quantities are not "
        "compared") and cap.out == ""
