"""Recovered receptances of superelements (``analysis.frf`` with output transformation
matrices): the frame of ``test_recovery`` reduced by Craig-Bampton with its DTM and an ATM,
coupled to a second frame; the recovered interior receptances are checked against the interior
receptances of the unreduced coupled model (to the reduction's error, falling with the modes
kept) and against the DTM applied to a direct KKT solve of the reduced coupled system (to
rounding)."""

from __future__ import annotations

import io
import json
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from substruct import cli
from substruct.case.loader import load_case
from substruct.case.op4 import read_op4
from substruct.io.hdf5 import load, save
from substruct.run.runner import build_model, run_case
from test_recovery import _case, _write_models

#: Below, between and above the first coupled modes (5.3, 33.1, 78.6, 140 rad/s).
OMEGAS = [1.0, 3.0, 15.0, 50.0, 100.0]
INPUTS = ["b@11:uz", "b@11:ux"]


def _frf_case(tmp: Path, reduced: bool, outputs: list[str]) -> Path:
    """The case of ``test_recovery`` with receptances from ``INPUTS`` at ``OMEGAS``."""
    path = _case(tmp, reduced, outputs, transient=False)
    out = ", ".join(f'"{o}"' for o in outputs)
    path.write_text(path.read_text() + f"""  frf:
    omega: {OMEGAS}
    inputs: [{", ".join(INPUTS)}]
    outputs: [{out}]
    method: kkt
""")
    return path


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """Per number of modes kept (6, 24): the folder, the interior labels of a, the unreduced
    run (the interior of a as outputs) and the reduced run (the DTM and ATM recovered)."""
    out = {}
    for g in (6, 24):
        tmp = tmp_path_factory.mktemp(f"frf{g}")
        rows = _write_models(tmp, g)
        full = run_case(load_case(_frf_case(tmp, False, [f"a@{lab}" for lab in rows])))
        red = run_case(load_case(_frf_case(tmp, True, ["b@11:uz"])))
        out[g] = (tmp, rows, full, red)
    return out


def test_recovered_frf_converges_to_the_unreduced_receptance(runs) -> None:
    """DTM receptance = interior receptance of the unreduced model, ATM = -omega^2 times it,
    to the reduction's error: as measured, 4.6e-3 (6 modes) and 5.0e-5 (24 modes) of the
    largest interior receptance at each frequency, at most; 24 modes at least 30 times closer
    (91 measured)."""
    err = {}
    for g, (_, rows, full, red) in runs.items():
        dtm, atm = red.recovery
        assert dtm.labels == rows and list(dtm.omega) == OMEGAS and dtm.inputs == INPUTS
        Hf = full.frf.H
        scale = np.abs(Hf).max(axis=(1, 2))[:, None, None]
        err[g] = float(np.max(np.abs(dtm.frf - Hf) / scale))
        w2 = np.asarray(OMEGAS)[:, None, None] ** 2
        err_a = float(np.max(np.abs(atm.frf + w2 * Hf) / (w2 * scale)))
        assert err_a == pytest.approx(err[g], rel=1e-6, abs=1e-12)
    assert err[6] < 1e-2 and err[24] < 1e-4 and err[24] < err[6] / 30, err


def _kkt_reference(tmp: Path) -> tuple[np.ndarray, np.ndarray]:
    """DTM x_a, with x the solution of the reduced coupled system's KKT equations
    ``[[K - w^2 M, c A^T], [c A, 0]] [x; mu] = [f; 0]`` for each input (dense ``solve``; ``c``
    scales the constraint rows to the dynamic stiffness, leaving ``x`` unchanged), and the
    rounding bound ``n eps cond`` of the largest of these systems."""
    model = build_model(load_case(_frf_case(tmp, True, ["b@11:uz"])))
    asm = model.assembly
    K, M = sp.csr_array(asm.K).toarray(), sp.csr_array(asm.M).toarray()
    A = sp.csr_array(asm.A).toarray()
    F = sp.csr_array(asm.rows([model.points[p] for p in INPUTS])).toarray().T
    n, m = K.shape[0], A.shape[0]
    D = read_op4(tmp / "a_cb.op4", ["DTM"])["DTM"].dense()
    blk = asm.block("a")
    out, bound = [], 0.0
    for w in OMEGAS:
        Z = K - w * w * M
        c = np.abs(Z).max() / np.abs(A).max()  # the constraint rows scaled to the dynamic
        G = np.block([[Z, c * A.T], [c * A, np.zeros((m, m))]])  # stiffness: x unchanged
        x = np.linalg.solve(G, np.vstack([F, np.zeros((m, F.shape[1]))]))[:n]
        out.append(D @ x[blk])
        bound = max(bound, (n + m) * np.finfo(float).eps * np.linalg.cond(G))
    return np.asarray(out), bound


def test_recovered_frf_is_the_matrix_times_a_kkt_solve(runs) -> None:
    """The recovered receptance is the DTM applied to the part's coordinates of a direct KKT
    solve of the reduced system, to rounding (``n eps cond`` of the KKT matrix)."""
    for g, (tmp, _, _, red) in runs.items():
        ref, bound = _kkt_reference(tmp)
        err = np.abs(red.recovery[0].frf - ref).max() / np.abs(ref).max()
        assert err < bound, (g, err, bound)


def test_frf_peaks_file_and_summary(runs, tmp_path: Path) -> None:
    """The file keeps the recovered receptances (read back equal); the peaks are the largest
    |H| of each row with its frequency and input; the summary prints their table."""
    from substruct.cli.summary import print_summary, summary_json

    _, rows, _, red = runs[6]
    rec = red.recovery[1]
    p = rec.frf_peaks()
    mag = np.abs(rec.frf)
    k, j = np.unravel_index(np.argmax(mag[:, 4, :]), (len(OMEGAS), len(INPUTS)))
    assert p.abs[4] == mag[k, 4, j] and p.omega[4] == OMEGAS[k] and p.input[4] == j
    save(red, tmp_path / "r.h5")
    back = load(tmp_path / "r.h5")
    for x, y in zip(red.recovery, back.recovery):
        assert np.array_equal(x.frf, y.frf) and np.array_equal(x.omega, y.omega)
        assert x.inputs == y.inputs
    out = io.StringIO()
    print_summary(back, out)
    text = out.getvalue()
    assert f"recovery a.atm (acceleration): {len(rows)} row(s), 10 mode shape(s), " \
           f"receptances at {len(OMEGAS)} frequencies" in text
    big = int(np.argmax(p.abs))
    width = max(5, max(map(len, rows)))
    assert (f"\n    {rows[big]:<{width}s}  {p.abs[big]:12.5g}  "
            f"{p.omega[big] / (2 * np.pi):10.4g}  {INPUTS[int(p.input[big])]}\n") in text
    peak = summary_json(back)["recovery"][1]["frf_peaks"][rows[big]]
    assert peak["abs"] == pytest.approx(p.abs[big], rel=1e-15)


def test_cli_run_streams_and_recovers(runs, tmp_path: Path, capsys) -> None:
    """``substruct run`` (whose sweep streams to the results file) stores the same recovered
    receptances as the in-memory run."""
    tmp, _, _, red = runs[6]
    case = _frf_case(tmp, True, ["b@11:uz"])
    assert cli.main(["run", str(case), "--out", str(tmp_path), "--json", "--no-pictures"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert len(data["recovery"][0]["frf_peaks"]) == len(red.recovery[0].labels)
    (target,) = tmp_path.glob("*.h5")
    back = load(target)
    for x, y in zip(red.recovery, back.recovery):
        np.testing.assert_allclose(y.frf, x.frf, rtol=0, atol=1e-12 * np.abs(x.frf).max())
