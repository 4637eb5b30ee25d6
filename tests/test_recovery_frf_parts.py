"""Recovered receptances of a superelement coupled to an FRF substructure (``type: frf``, by
LM-FBS): a two-coordinate superelement (grounded spring chain) with a recovery matrix of two
rows, joined at its grid 2 to a damped single-coordinate part given as its receptances in an
NPZ file; the recovered receptances equal those of the same system with the part given as its
matrices (``type: matrices``, coupled in one KKT solve) to rounding, for an input on the
superelement and one on the FRF part."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from substruct.case.loader import load_case
from substruct.run.runner import build_model, run_case

OMEGA = [3.0, 9.0, 14.0, 21.0, 30.0, 45.0]
M_B, C_B, K_B = 1.5, 2.0, 900.0      # the FRF part: a damped mass on a spring to ground
DTM = np.array([[1.0, 0.0], [0.5, 0.5]])


def _case(tmp: Path, b_spec: str) -> Path:
    np.savez(tmp / "se.npz", M=np.diag([2.0, 1.0]),
             K=np.array([[3000.0, -1000.0], [-1000.0, 1000.0]]),
             C=np.array([[3.0, -1.0], [-1.0, 1.0]]), DTM=DTM)
    path = tmp / f"case_{b_spec.split(',')[1].split(':')[1].strip()}.yaml"
    path.write_text(f"""name: frfparts
substructures:
  - name: se
    type: superelement
    file: se.npz
    M: M
    K: K
    C: C
    dofs: [[1, "1"], [2, "1"]]
    free: false
    recovery:
      - {{name: dtm, matrix: DTM, of: displacement, labels: [g1, mid]}}
  - {b_spec}
connections:
  - [se@2:ux, B@1:x]
analysis:
  frf:
    omega: {OMEGA}
    inputs: [se@1:ux, B@1:x]
    outputs: [se@2:ux]
    method: kkt
""")
    return path


def _run(path: Path):
    case = load_case(path)
    return run_case(case, model=build_model(case))


def test_recovered_receptances_beside_an_frf_part(tmp_path: Path) -> None:
    w = np.array(OMEGA)
    yb = 1.0 / (K_B + 1j * w * C_B - w ** 2 * M_B)   # the part's receptance, closed form
    np.savez(tmp_path / "b.npz", H=yb[:, None, None], labels=np.array(["1:x"]), omega=w)
    fbs = _run(_case(tmp_path, "{name: B, type: frf, file: b.npz}"))
    ref = _run(_case(tmp_path, f"{{name: B, type: matrices, M: [[{M_B}]], C: [[{C_B}]], "
                               f"K: [[{K_B}]], labels: ['1:x']}}"))
    assert fbs.frf.method.startswith("lm-fbs") and not ref.frf.method.startswith("lm-fbs")
    (got,), (want,) = fbs.recovery, ref.recovery
    assert got.frf.shape == (len(w), 2, 2) and got.inputs == ["se@1:ux", "B@1:x"]
    np.testing.assert_array_equal(got.omega, want.omega)
    # the same system by two exact formulations of 3 coordinates: agreement to rounding of the
    # largest receptance (condition of the interface solve ~ 1e2)
    scale = np.abs(want.frf).max()
    assert np.abs(got.frf - want.frf).max() <= 1e-12 * scale
    # and the rows are the matrix times the superelement's own coupled receptances: row g1 is
    # grid 1, row mid the mean of grids 1 and 2 (grid 2 is the case's output)
    out2 = np.asarray(fbs.frf.H)[:, 0, :]
    np.testing.assert_allclose(got.frf[:, 1, :] * 2.0 - got.frf[:, 0, :], out2,
                               rtol=0, atol=1e-12 * scale)


def test_recovery_beside_a_decoupled_part_is_refused(tmp_path: Path) -> None:
    """The decoupling's generalized-inverse solve is not followed by the recovery rows: the
    case is refused in one line before any sweep, not run with ``/recovery/<i>/frf`` left out."""
    import pytest

    from substruct.case.errors import CaseError

    w = np.array(OMEGA)
    yb = 1.0 / (K_B + 1j * w * C_B - w ** 2 * M_B)
    np.savez(tmp_path / "b.npz", H=yb[:, None, None], labels=np.array(["1:x"]), omega=w)
    case = load_case(_case(tmp_path, "{name: B, type: frf, file: b.npz, decouple: true}"))
    with pytest.raises(CaseError, match=r"analysis\.frf: receptances are not recovered .* "
                                        r"a decoupled part"):
        run_case(case, model=build_model(case))
