"""The shipped random-vibration qualification of the box beam with its absorbers on a shaker
table (cases/box_beam_random.yaml), run through the command line and held to a direct
frequency-domain computation written here from the assembled matrices: at each frequency the
KKT system of the constrained model with the table's rows moved by a unit acceleration,

    [Z(w)  A^T] [q]   [0]
    [A      0 ] [l] = [E / (-w^2)],     Z = K + i w C - w^2 M,

so that the absolute acceleration per table acceleration is T = O q (-w^2) = O q' with
q' solving the same system for the right-hand side E; S_y = |T|^2 S_in, S_in the table
interpolated as straight lines in log-log, and the RMS the trapezoid rule on the grid."""

from pathlib import Path

import h5py
import numpy as np

from cli_helpers import run
from substruct.case.loader import load_case
from substruct.run.runner import build_model

CASE = Path(__file__).resolve().parent.parent / "cases" / "box_beam_random.yaml"


def direct_transmissibility(case, f):
    """``T`` ``(n_f, outputs)``: absolute output acceleration per table acceleration."""
    model = build_model(case)
    asm = model.assembly
    K, M = asm.K.toarray(), asm.M.toarray()
    C = asm.C.toarray() if asm.C is not None else np.zeros_like(K)
    A = asm.A.toarray()
    n, m = K.shape[0], A.shape[0]
    spec = case.analysis.random
    base = set()
    for p in spec.base.at:
        row = asm.row(model.points[p]).toarray().ravel()
        assert np.count_nonzero(row) == 1  # every table point is a node
        base.add(int(np.flatnonzero(row)[0]))
    E = np.zeros(m)
    for k in range(m):
        nz = np.flatnonzero(A[k])
        if len(nz) == 1 and int(nz[0]) in base:
            E[k] = A[k, nz[0]]
    assert np.count_nonzero(E) == len(spec.base.at)
    O = asm.rows([model.points[p] for p in spec.outputs]).toarray()
    T = np.empty((len(f), len(spec.outputs)), dtype=complex)
    rhs = np.concatenate([np.zeros(n), E])
    for k, w in enumerate(2 * np.pi * f):
        Z = K + 1j * w * C - w ** 2 * M
        kkt = np.block([[Z, A.T], [A, np.zeros((m, m))]])
        T[k] = O @ np.linalg.solve(kkt, rhs)[:n]
    return T


def test_box_beam_qualification_rms_against_the_direct_computation(capsys, tmp_path):
    code, out, err = run(capsys, "run", CASE, "--out", tmp_path)
    assert code == 0, err
    assert "Miles' check" in out
    with h5py.File(tmp_path / "box_beam_random.h5") as h5:
        f, psd, rms = h5["random/f"][()], h5["random/psd"][()], h5["random/rms"][()]
        s_in = h5["random/input_psd"][()][:, 0]
    case = load_case(CASE)
    table = np.asarray(case.analysis.random.base.psd.rows)
    expected_in = np.exp(np.interp(np.log(f), np.log(table[:, 0]), np.log(table[:, 1])))
    np.testing.assert_allclose(s_in, expected_in, rtol=1e-12)
    T = direct_transmissibility(case, f)
    auto = np.abs(T) ** 2 * expected_in[:, None]
    # the run's formulations agree to its sweep tolerance (1e-6 of max |H|): the PSDs to twice
    # that of their largest value, the RMS values (integrals of them) to the same
    got = np.real(np.einsum("kii->ki", psd))
    assert np.abs(got - auto).max() <= 2e-6 * auto.max(), np.abs(got - auto).max() / auto.max()
    direct = np.sqrt(np.trapezoid(auto, f, axis=0))
    np.testing.assert_allclose(rms, direct, rtol=2e-6)
    # the table's own RMS on the grid is the closed form of its three power laws, 6.06 g
    # (0.01 f/20 + 0.04 + 0.04 (350/f) integrated: 1.5 + 10.8 + 14 ln(2000/350)), within the
    # trapezoid rule's error on a 400-point log grid
    exact = np.sqrt(1.5 + 10.8 + 14 * np.log(2000 / 350))
    assert abs(np.sqrt(np.trapezoid(s_in, f)) / exact - 1) < 1e-3
    # the tip responds above the table in g rms, the joint below the tip
    assert rms[0] > exact and rms[1] < rms[0]


def test_miles_check_of_a_single_dof_oscillator():
    """On a single-DOF oscillator (f_n = 50 Hz, zeta = 0.05) under a white base acceleration,
    the check finds the absolute transmissibility's peak, at f_n (sqrt(1 + 8 zeta^2) - 1)^(1/2)
    / (2 zeta) and of height |T|max from the closed form, and Miles' value is the exact RMS
    sqrt(pi/2 f_n Q W (1 + 1/Q^2)) divided by sqrt(1 + 1/Q^2) with Q = 1 / (2 zeta), up to
    |T|max / Q - 1 = 0.5 % and the grid's resolution of the peak (0.01 Hz)."""
    from substruct.analysis.frf.random import miles_absolute_rms, miles_check

    fn, zeta, W = 50.0, 0.05, 3.0
    f = np.arange(0.01, 2000.0, 0.01)
    r = f / fn
    T2 = (1 + (2 * zeta * r) ** 2) / ((1 - r ** 2) ** 2 + (2 * zeta * r) ** 2)
    m = miles_check(f, np.full(len(f), W), T2 * W)
    peak = fn * np.sqrt(np.sqrt(1 + 8 * zeta ** 2) - 1) / (2 * zeta)
    rp = peak / fn
    tmax = np.sqrt((1 + (2 * zeta * rp) ** 2) / ((1 - rp ** 2) ** 2 + (2 * zeta * rp) ** 2))
    assert abs(m.fn - peak) <= 0.01 and m.W == W
    assert abs(m.Q / tmax - 1) < 1e-5
    Q = 1 / (2 * zeta)
    exact = miles_absolute_rms(fn, Q, W)
    assert abs(m.miles * np.sqrt(1 + 1 / Q ** 2) / exact - 1) < 1.2 * (tmax / Q - 1) / 2 + 1e-5
