"""Operational TPA from a case file (``analysis.tpa.method: operational``): through the command
line against the library functions (bit for bit) and against the known answer
``T = H_ts H_is^-1`` of the generating receptances; the result read back, summarised and drawn;
the refusals.

The structure is eight masses joined by springs (a dense stiffness); operating forces act at
three masses (``s``), the indicators are three others and the targets the last two.  Five operating
conditions (random complex forces, seeded); condition 4 is left out of the transmissibility
and predicted by it.  Tolerance of the known answer: the pseudo-inverse of ``U_i`` over the
four training conditions loses ``eps cond(U_i)`` (measured cond up to ~1e3 here), so
``100 eps max cond(U_i)`` relative to the largest entry.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from substruct import cli
from substruct.analysis.frf.tpa import on_board_validation
from substruct.analysis.frf.tpa_operational import operational_contributions, transmissibility
from substruct.io.result_reader import load

N = 8
MASS = [1.0, 2.0, 1.5, 1.0, 3.0, 2.5, 1.0, 2.0]
LABELS = [f"q{k + 1}" for k in range(N)]
SOURCES, INDICATORS, TARGETS = ["q1", "q2", "q3"], ["q4", "q5", "q6"], ["q7", "q8"]
OMEGA = np.linspace(3.0, 60.0, 25)
CONDITIONS, HELD = 5, 4


def _matrices():
    """Every mass joined to every other and to the ground: a dense, positive-definite
    stiffness (a chain would pass every path through one spring: ``H_is`` of rank one)."""
    G = np.random.default_rng(3).normal(size=(N, N))
    K = 1000.0 * (G @ G.T / N + np.eye(N))
    return np.diag(MASS), np.round(K, 6)


def _H(labels_out, labels_in):
    M, K = _matrices()
    C = 0.002 * K
    H = np.linalg.inv(K[None] - OMEGA[:, None, None] ** 2 * M[None]
                      + 1j * OMEGA[:, None, None] * C[None])
    o = [LABELS.index(p) for p in labels_out]
    i = [LABELS.index(p) for p in labels_in]
    return H[:, o][:, :, i]


def _case_text(responses: Path, tpa: str) -> str:
    M, K = _matrices()
    return f"""name: optpa
substructures:
  - name: P
    type: matrices
    M: {M.tolist()}
    K: {K.tolist()}
    C: {(0.002 * K).tolist()}
    labels: {LABELS}
analysis:
  frf:
    omega: {OMEGA.tolist()}
    inputs: [{', '.join('P@' + s for s in SOURCES)}]
    outputs: [{', '.join('P@' + p for p in INDICATORS + TARGETS)}]
  tpa: {{responses: {responses}, {tpa}}}
"""


TPA = (f"method: operational, indicators: [{', '.join('P@' + p for p in INDICATORS)}], "
       f"targets: [{', '.join('P@' + p for p in TARGETS)}], validation_condition: {HELD}")


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("optpa")
    rng = np.random.default_rng(7)
    F = rng.normal(size=(len(OMEGA), 3, CONDITIONS)) + 1j * rng.normal(
        size=(len(OMEGA), 3, CONDITIONS))
    pts = INDICATORS + TARGETS
    u = _H(pts, SOURCES) @ F                       # freq x points x conditions
    path = tmp / "operating.npz"
    np.savez(path, omega=OMEGA, labels=np.array([f"P@{p}" for p in pts]), u=u)
    return tmp, path, u


def _write(tmp: Path, responses: Path, tpa: str, name: str = "case.yaml") -> Path:
    case = tmp / name
    case.write_text(_case_text(responses, tpa))
    return case


def _run(case: Path, out: Path, pictures: bool = False) -> int:
    args = ["run", str(case), "--out", str(out), "--quiet"]
    return cli.main(args if pictures else args + ["--no-pictures"])


def test_door_equals_the_library_and_the_known_answer(data):
    tmp, responses, u = data
    case = _write(tmp, responses, TPA)
    assert _run(case, tmp / "out", pictures=True) == 0
    res = load(tmp / "out" / "optpa.h5")
    tpa = res.tpa
    assert tpa.method == "operational" and tpa.validation_condition == HELD
    assert tpa.interface == [f"P@{p}" for p in INDICATORS] == tpa.indicators
    # the library on the same data, bit for bit
    U_i, U_t = u[:, :3], u[:, 3:]
    train = [k for k in range(CONDITIONS) if k != HELD]
    T = transmissibility(U_i[:, :, train], U_t[:, :, train])
    assert np.array_equal(tpa.transmissibility, T)
    assert np.array_equal(tpa.contributions, operational_contributions(T, U_i[:, :, HELD]))
    val = on_board_validation(T, U_i[:, :, HELD], U_t[:, :, HELD])
    assert np.array_equal(tpa.predicted, val.predicted)
    assert np.array_equal(tpa.measured, U_t[:, :, HELD])
    assert np.array_equal(tpa.error, val.error)
    # the known answer: T = H_ts H_is^-1 (three sources seen by three indicators)
    H_is, H_ts = _H(INDICATORS, SOURCES), _H(TARGETS, SOURCES)
    exact = H_ts @ np.linalg.inv(H_is)
    bound = 100 * np.finfo(float).eps * float(np.linalg.cond(U_i[:, :, train]).max())
    assert np.abs(T - exact).max() <= bound * np.abs(exact).max()
    assert tpa.error.max() <= bound
    # the paths add up to the prediction
    assert np.abs(tpa.contributions.sum(axis=2) - tpa.predicted).max() <= \
        1e-13 * np.abs(tpa.predicted).max()
    # drawn like the other TPA results
    for png in ("optpa_paths.png", "optpa_validation.png"):
        assert (tmp / "out" / png).stat().st_size > 10_000


def test_the_run_prints_the_operational_line(data, capsys):
    tmp, responses, _ = data
    case = _write(tmp, responses, TPA, "printed.yaml")
    assert cli.main(["run", str(case), "--out", str(tmp / "printed"), "--no-pictures"]) == 0
    line = [x for x in capsys.readouterr().out.splitlines() if "transfer paths" in x]
    assert len(line) == 1 and "transfer paths (operational): transmissibility from 3 " \
        f"indicator(s) to 2 target(s); operating condition {HELD} predicted" in line[0], line


@pytest.mark.parametrize("tpa, field, words", [
    (TPA + ", interface: [P@q1]", "analysis.tpa.interface", "has no interface"),
    (TPA.replace(f", validation_condition: {HELD}", ""), "analysis.tpa.validation_condition",
     "give its index"),
    (TPA.replace(f"validation_condition: {HELD}", "validation_condition: 5"),
     "analysis.tpa.validation_condition", "has 5 operating condition(s)"),
    (TPA + ", regularization: {method: tsvd, rtol: 0.01, length: 1.0}",
     "analysis.tpa.regularization", "belongs to in_situ and pseudo_forces"),
    ("method: in_situ, validation_condition: 0, interface: [P@q1], indicators: [P@q4], "
     "targets: [P@q8]", "analysis.tpa.validation_condition", "belongs to method: operational"),
])
def test_refused_in_one_line(data, capsys, tpa, field, words):
    tmp, responses, _ = data
    case = _write(tmp, responses, tpa, "bad.yaml")
    assert _run(case, tmp / "bad") == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and f": {field}: " in err and words in err, err
    assert not (tmp / "bad" / "optpa.h5").exists()


def test_too_few_conditions_are_refused(data, capsys):
    """Three conditions, one held out: two left for three indicators."""
    tmp, _, u = data
    few = tmp / "few.npz"
    np.savez(few, omega=OMEGA, labels=np.array(["P@q4", "P@q5", "P@q6", "P@q7", "P@q8"]),
             u=u[:, :, :3])
    case = _write(tmp, few, TPA.replace(f"validation_condition: {HELD}",
                                        "validation_condition: 2"), "few.yaml")
    assert _run(case, tmp / "few") == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and ": analysis.tpa.indicators: operational TPA needs at " \
        "least as many operating conditions (besides the validation condition) as " \
        "indicators: 2 < 3 in few.npz" in err, err


def test_responses_of_one_condition_are_refused(data, capsys):
    tmp, _, u = data
    flat = tmp / "flat.npz"
    np.savez(flat, omega=OMEGA, labels=np.array(["P@q4", "P@q5", "P@q6", "P@q7", "P@q8"]),
             u=u[:, :, 0])
    case = _write(tmp, flat, TPA, "flat.yaml")
    assert _run(case, tmp / "flat") == 2
    err = capsys.readouterr().err.strip()
    assert "analysis.tpa.responses: flat.npz: u has shape [25, 5], expected [25, 5, " \
        "conditions]" in err, err
