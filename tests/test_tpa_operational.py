"""Pseudo-forces and operational (transmissibility-based) TPA on the synthetic test lab
(tests/testlab_models.py): a source inside the free frame A (forces at two of its nodes) runs
on the clamped receptor B, and the frame is computed as one piece.

Pseudo-forces at points of A away from the joint and from the source reproduce the responses
at targets on B when their blocked forces span the joint's six loads (three forces along x at
three points of A's plane x = -0.4 m not on one line, three in that plane), and the validation
error says by how much they miss when they cannot (three forces at one point; six at two
points, whose line they cannot turn about).  Operational TPA: responses under random operating
forces at three places give the transmissibility H_ts H_is^-1 of the generating model, and at
two places (fewer than the indicators) the minimum-norm H_ts H_is^+.

Tolerance: the finite-element receptances are accurate to about 3.5e-10 of their largest entry
(tests/test_virtual_point.py); 1e-8 leaves a margin of about 30.  The transmissibility and the
sum of the contributions are formed from one set of receptances, so only the round-off of the
least squares remains: 1e-14 times the condition number of H_is (2.0e3) times 100.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from substruct.analysis.frf.tpa import on_board_validation
from substruct.analysis.frf.tpa_operational import (
    operational_contributions,
    pseudo_forces,
    transmissibility,
)
from substruct.analysis.frf.vp_coupling import Regularisation
from testlab_models import OMEGA, assembly, node_dofs, part_a, receptance

EXACT = 1e-8
SOURCE = [("3:uz", 1.0), ("4:ux", 0.4 - 0.3j)]
F = np.array([a for _, a in SOURCE])
INDICATORS = [((x, y, z), c) for (x, y, z) in [(1 / 6, 0.0, 0.0), (0.5, 0.0, 0.0),
                                                (0.5, 0.35, 0.0)] for c in ("ux", "uy", "uz")]
TARGETS = [((0.5, 0.35 * 2 / 3, 0.0), "uz"), ((0.5, 0.0, -0.1), "uy"), ((1 / 3, 0.0, 0.0), "uz")]
N2, P1, P3 = (-0.4, 0.0, 0.0), (-0.4, 0.1, 0.0), (-0.4, 0.3, 0.5 / 3)
#: spans the joint's loads: x forces at three points not on one line, three in the plane
SPANNING = [(N2, "ux"), (N2, "uy"), (N2, "uz"), (P1, "ux"), (P3, "ux"), (P3, "uy")]
ONE_POINT = [(N2, "ux"), (N2, "uy"), (N2, "uz")]
TWO_POINTS = [(p, c) for p in (N2, P1) for c in ("ux", "uy", "uz")]


def _at(sub, points):
    return sp.csr_array(sp.vstack([sub.locate({"at": list(p), "component": c})
                                   for p, c in points]))


@pytest.fixture(scope="module")
def lab():
    A, AB = part_a(), assembly()
    J = node_dofs(A, 1)
    src_a = sp.csr_array(sp.vstack([A.locate(d) for d, _ in SOURCE]))
    Yjj = receptance(A, J, J)
    truth = np.linalg.solve(Yjj, (receptance(A, J, src_a) @ F)[:, :, None])[:, :, 0]
    out = sp.csr_array(sp.vstack([_at(AB, INDICATORS), _at(AB, TARGETS)]))
    src = sp.csr_array(sp.vstack([AB.locate(d) for d, _ in SOURCE]))
    u = receptance(AB, out, src) @ F  # operating responses (k, 9 + 3)
    return dict(A=A, AB=AB, J=J, Yjj=Yjj, truth=truth, out=out, u=u)


def _pseudo(lab, points, reg=Regularisation()):
    Y = receptance(lab["AB"], lab["out"], _at(lab["AB"], points))
    Fp = pseudo_forces(Y[:, :9], lab["u"][:, :9], reg)
    return Fp, on_board_validation(Y[:, 9:], Fp, lab["u"][:, 9:])


def test_pseudo_forces_span_the_interface(lab):
    """Six spanning pseudo-forces predict the targets; their blocked forces
    Y_A,JJ^-1 Y_A,Jp F_ps are the source's (the pseudo-forces stand for it on any receptor)."""
    Fp, val = _pseudo(lab, SPANNING)
    print("spanning: validation error max", val.error.max())
    assert val.error.max() < EXACT
    M = np.linalg.solve(lab["Yjj"], receptance(lab["A"], lab["J"], _at(lab["A"], SPANNING)))
    f_bl = (M @ Fp[:, :, None])[:, :, 0]
    err = np.abs(f_bl - lab["truth"]).max() / np.abs(lab["truth"]).max()
    print("spanning: blocked forces", err)
    assert err < EXACT


def test_pseudo_forces_that_cannot_span_are_reported(lab):
    """Three forces at one point, or six at two points, miss part of the joint's loads: the
    on-board validation reports it, per frequency."""
    for points, floor in ((ONE_POINT, 1e-2), (TWO_POINTS, 1e-4)):
        _, val = _pseudo(lab, points)
        print(len(points), "validation error median", np.median(val.error), "max",
              val.error.max())
        assert np.median(val.error) > floor


def test_operational_tpa(lab):
    """Random operating forces at three places of A, responses at three indicators of B and at
    the three targets: T = U_t U_i^+ is H_ts H_is^-1, and the contributions add up to the
    target responses of every condition."""
    AB = lab["AB"]
    Y = receptance(AB, lab["out"], _at(AB, SPANNING[3:]))
    H_i, H_t = Y[:, [0, 4, 8]], Y[:, 9:]
    exact = H_t @ np.linalg.inv(H_i)
    rng = np.random.default_rng(1)
    for n_o in (3, 8):
        Fo = rng.normal(size=(len(OMEGA), 3, n_o)) + 1j * rng.normal(size=(len(OMEGA), 3, n_o))
        U_i, U_t = H_i @ Fo, H_t @ Fo
        T = transmissibility(U_i, U_t)
        err = np.abs(T - exact).max() / np.abs(exact).max()
        print(n_o, "conditions: transmissibility", err)
        assert err < 100 * 1e-14 * np.linalg.cond(H_i).max()
        for j in range(n_o):
            c = operational_contributions(T, U_i[:, :, j])
            assert c.shape == (len(OMEGA), 3, 3)
            e = np.abs(c.sum(axis=2) - U_t[:, :, j]).max() / np.abs(U_t[:, :, j]).max()
            assert e < 100 * 1e-14 * np.linalg.cond(H_i).max()
    # the regularised option is used: a truncation that drops nothing gives the same T, one
    # that keeps two of the three singular values of U_i does not
    keep = transmissibility(U_i, U_t, Regularisation("tsvd", rtol=1e-14))
    assert np.abs(keep - exact).max() < 100 * 1e-14 * np.linalg.cond(H_i).max() * \
        np.abs(exact).max()
    cut = transmissibility(U_i, U_t, Regularisation("tsvd", rank=2))
    assert np.abs(cut - exact).max() > 1e-3 * np.abs(exact).max()
    with pytest.raises(ValueError, match="at least as many operating conditions as "
                       "indicators: 2 conditions < 3 indicators"):
        transmissibility(U_i[:, :, :2], U_t[:, :, :2])
    with pytest.raises(ValueError, match="do not match"):
        transmissibility(U_i, U_t[:, :, :-1])
    bad = U_t.copy()
    bad[2, 1, 0] = np.inf
    with pytest.raises(ValueError, match=r"target responses are not finite at index \[2, 1, 0\]"):
        transmissibility(U_i, bad)


def test_operational_tpa_fewer_sources_than_indicators(lab):
    """Two operating-force places seen by three indicators: U_i has rank 2 < 3, T is not
    unique, and the default inversion (singular values below 1e-12 of the largest dropped)
    gives the least-squares, minimum-norm one, U_t U_i^+ = H_ts F F^+ H_is^+ = H_ts H_is^+
    (F of full row rank, H_is of full column rank); it predicts a condition left out."""
    AB = lab["AB"]
    Y = receptance(AB, lab["out"], _at(AB, SPANNING[3:5]))
    H_i, H_t = Y[:, [0, 4, 8]], Y[:, 9:]
    exact = H_t @ np.linalg.pinv(H_i)
    bound = 100 * 1e-14 * np.linalg.cond(H_i).max()
    rng = np.random.default_rng(2)
    Fo = rng.normal(size=(len(OMEGA), 2, 7)) + 1j * rng.normal(size=(len(OMEGA), 2, 7))
    U_i, U_t = H_i @ Fo, H_t @ Fo
    T = transmissibility(U_i[:, :, :6], U_t[:, :, :6])
    err = np.abs(T - exact).max() / np.abs(exact).max()
    pred = (T @ U_i[:, :, 6:])[:, :, 0]
    e = np.abs(pred - U_t[:, :, 6]).max() / np.abs(U_t[:, :, 6]).max()
    print("rank 2 of 3: transmissibility", err, "held-out prediction", e, "bound", bound)
    assert err < bound and e < bound
    # the same definition by an explicit rank
    T2 = transmissibility(U_i[:, :, :6], U_t[:, :, :6], Regularisation("tsvd", rank=2))
    assert np.abs(T2 - exact).max() < bound * np.abs(exact).max()


def test_pseudo_forces_bad_input(lab):
    Y = np.ones((4, 3, 6), dtype=complex)
    with pytest.raises(ValueError, match="at least as many indicator responses as "
                       "pseudo-forces: 3 < 6"):
        pseudo_forces(Y, np.ones((4, 3)))
    with pytest.raises(ValueError, match="do not match"):
        pseudo_forces(Y, np.ones((3, 3)))
    with pytest.raises(ValueError, match="scale must be 2 finite positive numbers"):
        pseudo_forces(Y[:, :, :2], np.ones((4, 3)), scale=[1.0, -1.0])



#: the test frames as one case: A's members split at (-0.4, 0.1, 0) (node 21) and
#: (-0.4, 0.3, 0.5/3) (node 41), the pseudo-force points of SPANNING
FRAME = """name: frame_tpa
units: "N, m, kg, s"
substructures:
  - name: AB
    type: frame
    nodes: {1: [0, 0, 0], 2: [-0.4, 0, 0], 21: [-0.4, 0.1, 0], 3: [-0.4, 0.3, 0],
            41: [-0.4, 0.3, 0.16666666666666666], 4: [-0.4, 0.3, 0.25], 12: [0.5, 0, 0],
            13: [0.5, 0, -0.3], 14: [0.5, 0.35, 0]}
    materials: {steel: {E: 2.1e11, G: 8.1e10, rho: 7850}}
    sections: {tube: {A: 4.44e-4, Iy: 1.02e-7, Iz: 1.02e-7, J: 1.6e-7}}
    members:
      - {nodes: [1, 2], section: tube, material: steel, orientation: [0, 0, 1], divisions: 3}
      - {nodes: [2, 21], section: tube, material: steel, orientation: [0, 0, 1]}
      - {nodes: [21, 3], section: tube, material: steel, orientation: [0, 0, 1], divisions: 2}
      - {nodes: [3, 41], section: tube, material: steel, orientation: [1, 0, 0], divisions: 2}
      - {nodes: [41, 4], section: tube, material: steel, orientation: [1, 0, 0]}
      - {nodes: [1, 12], section: tube, material: steel, orientation: [0, 0, 1], divisions: 3}
      - {nodes: [12, 13], section: tube, material: steel, orientation: [1, 0, 0], divisions: 3}
      - {nodes: [12, 14], section: tube, material: steel, orientation: [0, 0, 1], divisions: 3}
    supports: {13: "123456"}
analysis:
  frf:
    omega: {start: 31.41592653589793, stop: 3769.9111843077517, num: 40}
    loss_factor: 0.01
    inputs: INPUTS
    outputs: [AB@12:ux, AB@12:uy, AB@12:uz, AB@12:rx, AB@12:ry, AB@12:rz, AB@14:ux, AB@14:uy,
              AB@14:uz, AB@14:rx, AB@14:ry, AB@14:rz]
"""
DOOR_SOURCE = ["AB@3:uz", "AB@4:ux"]
DOOR_TPA = """  tpa:
    responses: RESPONSES
    method: pseudo_forces
    interface: INPUTS
    indicators: INDICATORS
    targets: [AB@14:rx, AB@14:ry, AB@14:rz]
"""
DOOR_IND = ["AB@12:ux", "AB@12:uy", "AB@12:uz", "AB@12:rx", "AB@12:ry", "AB@12:rz",
            "AB@14:ux", "AB@14:uy", "AB@14:uz"]


def _run_case(tmp_path, name, text):
    from substruct import cli
    from substruct.io.result_reader import load
    path = tmp_path / f"{name}.yaml"
    path.write_text(text)
    code = cli.main(["run", str(path), "--out", str(tmp_path / name), "--quiet",
                     "--no-pictures"])
    return code, (load(tmp_path / name / "frame_tpa.h5") if code == 0 else None)


def test_pseudo_forces_from_a_case_file(tmp_path, capsys):
    """``analysis.tpa.method: pseudo_forces`` on a frame case: the operating responses are the
    case's own receptances from the source times its forces; six spanning pseudo-forces
    predict the targets, three at one point do not and the validation error says so."""
    code, res = _run_case(tmp_path, "source",
                          FRAME.replace("INPUTS", "[" + ", ".join(DOOR_SOURCE) + "]"))
    assert code == 0
    u = res.frf.H @ F
    responses = tmp_path / "operating.npz"
    np.savez(responses, omega=res.frf.omega, labels=np.array(res.frf.outputs), u=u)
    errs = {}
    for name, pts in (("spanning", ["AB@2:ux", "AB@2:uy", "AB@2:uz", "AB@21:ux", "AB@41:ux",
                                    "AB@41:uy"]),
                      ("one", ["AB@2:ux", "AB@2:uy", "AB@2:uz"])):
        names = "[" + ", ".join(pts) + "]"
        text = (FRAME + DOOR_TPA).replace("INPUTS", names).replace(
            "RESPONSES", str(responses)).replace("INDICATORS", "[" + ", ".join(DOOR_IND) + "]")
        code, res = _run_case(tmp_path, name, text)
        assert code == 0
        assert res.tpa.method == "pseudo_forces" and res.tpa.interface == pts
        errs[name] = res.tpa.error
    assert errs["spanning"].max() < EXACT
    assert np.median(errs["one"]) > 1e-2
    capsys.readouterr()
    text = (FRAME + DOOR_TPA).replace("INPUTS", "[" + ", ".join(DOOR_IND[:7]) + "]").replace(
        "RESPONSES", str(responses)).replace("INDICATORS", "[" + ", ".join(DOOR_IND[7:]) + "]")
    code, _ = _run_case(tmp_path, "few", text)
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and ": analysis.tpa.indicators: pseudo-forces need at " \
        "least as many indicators as pseudo-force points (7)" in err, err
