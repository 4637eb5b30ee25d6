"""Recovered receptances with a loss factor (``analysis.frf.loss_factor``): a one-coordinate
superelement (mass 1, stiffness 100, loss factor 0.05) with a DTM ``[2]`` and an ATM ``[3]``;
the recovered receptances equal the closed form ``H = 1 / (k (1 + i eta) - omega^2 m)`` times
the matrix (and ``-omega^2`` for the ATM), and the DTM's are twice the case's own output."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from substruct.case.loader import load_case
from substruct.run.runner import run_case

OMEGA = [2.0, 9.0, 10.0, 11.0, 20.0]


@pytest.mark.parametrize("loss", ["0.05", "{se: 0.05}"])
def test_recovered_receptance_with_a_loss_factor(tmp_path: Path, loss: str) -> None:
    np.savez(tmp_path / "se.npz", M=np.array([[1.0]]), K=np.array([[100.0]]),
             DTM=np.array([[2.0]]), ATM=np.array([[3.0]]))
    path = tmp_path / "case.yaml"
    path.write_text(f"""name: loss
substructures:
  - name: se
    type: superelement
    file: se.npz
    M: M
    K: K
    dofs: [[1, "1"]]
    free: false
    recovery:
      - {{name: dtm, matrix: DTM, of: displacement, labels: [tip]}}
      - {{name: atm, matrix: ATM, of: acceleration, labels: [tip]}}
analysis:
  frf:
    omega: {OMEGA}
    inputs: [se@1:ux]
    outputs: [se@1:ux]
    method: kkt
    loss_factor: {loss}
""")
    res = run_case(load_case(path))
    w = np.array(OMEGA)
    h = 1.0 / (100.0 * (1.0 + 0.05j) - w ** 2)   # the closed form
    dtm, atm = res.recovery
    assert dtm.frf.shape == (len(w), 1, 1) and dtm.inputs == ["se@1:ux"]
    # one coordinate: a 2 x 2 KKT solve, the closed form to a few ulps of |H| (1/5 at 10 rad/s)
    np.testing.assert_allclose(dtm.frf[:, 0, 0], 2.0 * h, rtol=1e-13)
    np.testing.assert_allclose(atm.frf[:, 0, 0], -3.0 * w ** 2 * h, rtol=1e-13)
    np.testing.assert_allclose(dtm.frf[:, 0, 0], 2.0 * np.asarray(res.frf.H)[:, 0, 0],
                               rtol=1e-15)
    peaks = dtm.frf_peaks()
    assert peaks.omega[0] == 10.0 and peaks.abs[0] == pytest.approx(2.0 / 5.0, rel=1e-13)
