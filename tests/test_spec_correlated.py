"""Correlated force inputs of analysis.random (``cross``: coherence and phase pair by pair):
the response cross-spectral matrix S_y = H S_f H^H against a direct computation of the same
2-DOF system with NumPy, against the uncorrelated sum when the coherence is 0, and the RMS
against the time-domain mean square of long random-phase multisine transients integrated by
SciPy (Parseval); an inconsistent set of coherences refused with one line."""

import h5py
import numpy as np
import pytest
import scipy.signal as sig

from cli_helpers import assert_one_line_error, run

M1, K1, C1 = 1.0, 4000.0, 2.0
M2, K2, C2 = 0.5, 2000.0, 1.0
COH, PHASE = 0.7, 40.0
M = np.diag([M1, M2])
K = np.array([[K1 + K2, -K2], [-K2, K2]])
C = np.array([[C1 + C2, -C2], [-C2, C2]])


def case_text(cross: str, forces: str | None = None) -> str:
    forces = forces or """      - {at: a@mass, psd: [[0.05, 2.0], [50, 2.0]]}
      - {at: b@mass, psd: [[0.05, 1.0], [50, 0.25]]}
"""
    return f"""name: chain
units: N, m, kg, s
substructures:
  - {{name: a, type: fixed-free, mass: {M1}, stiffness: {K1}, damping: {C1}}}
  - {{name: b, type: free-free, mass: {M2}, stiffness: {K2}, damping: {C2}}}
constraints:
  - {{name: tie, terms: {{b@boundary: 1, a@mass: -1}}}}
output: {{pictures: false}}
analysis:
  random:
    frequencies: {{start: 0.1, stop: 40, num: 400, spacing: linear}}
    forces:
{forces}    cross: {cross}
    outputs: [a@mass, b@mass]
    quantity: displacement
    check: [null-space]
    rms_tolerance: 0.05    # the grid's lines are the spectrum (Parseval test), 0.1 Hz apart
"""


def run_case(capsys, tmp_path, text):
    path = tmp_path / "chain.yaml"
    path.write_text(text)
    code, out, err = run(capsys, "run", path, "--out", tmp_path / "out", "--force")
    return code, out, err, tmp_path / "out" / "chain.h5"


def input_matrix(f, coherence, phase):
    """S_f by hand: the two tables (flat 2; 1 at 0.05 Hz to 0.25 at 50 Hz, log-log) and
    S_12 = sqrt(coherence S_11 S_22) e^{i phase}."""
    s1 = np.full_like(f, 2.0)
    s2 = 1.0 * (f / 0.05) ** (np.log(0.25) / np.log(50 / 0.05))
    s12 = np.sqrt(coherence * s1 * s2) * np.exp(1j * np.deg2rad(phase))
    S = np.zeros((len(f), 2, 2), dtype=complex)
    S[:, 0, 0], S[:, 1, 1], S[:, 0, 1], S[:, 1, 0] = s1, s2, s12, np.conj(s12)
    return S


def direct_H(f):
    w = 2 * np.pi * f
    return np.linalg.inv(K[None] - (w ** 2)[:, None, None] * M[None]
                         + 1j * w[:, None, None] * C[None])


def read(h5):
    with h5py.File(h5) as g:
        r = g["random"]
        return (r["f"][()], r["psd"][()], r["rms"][()],
                r["input_csd"][()] if "input_csd" in r else None)


def test_correlated_against_direct(capsys, tmp_path):
    """The file's S_y and S_f equal H S_f H^H and S_f built by hand, H = (K - w^2 M + i w C)^-1
    of the same chain (relative to the largest term: the formulations' rounding, 1e-8)."""
    code, out, err, h5 = run_case(capsys, tmp_path, case_text(
        f"[{{between: [a@mass, b@mass], coherence: {COH}, phase: {PHASE}}}]"))
    assert code == 0, err
    f, psd, rms_, csd = read(h5)
    S = input_matrix(f, COH, PHASE)
    np.testing.assert_allclose(csd, S, rtol=0, atol=1e-12 * np.abs(S).max())
    H = direct_H(f)
    ref = H @ S @ H.conj().transpose(0, 2, 1)
    np.testing.assert_allclose(psd, ref, rtol=0, atol=1e-8 * np.abs(ref).max())
    # the correlation matters here: the uncorrelated answer differs by more than 5 %
    Sd = S.copy()
    Sd[:, 0, 1] = Sd[:, 1, 0] = 0
    unc = np.einsum("kii->ki", H @ Sd @ H.conj().transpose(0, 2, 1)).real
    assert np.max(np.abs(np.einsum("kii->ki", ref).real.sum(0) / unc.sum(0) - 1)) > 0.05


def test_zero_coherence_is_the_uncorrelated_sum(capsys, tmp_path):
    """Coherence 0: S_y,ii = sum_j |H_ij|^2 S_jj, and the same as the case without cross."""
    code, _, err, h5 = run_case(capsys, tmp_path, case_text(
        "[{between: [b@mass, a@mass], coherence: 0, phase: 90}]"))
    assert code == 0, err
    f, psd, rms0, csd = read(h5)
    H = direct_H(f)
    S = input_matrix(f, 0.0, 0.0)
    auto = np.einsum("kij,kj->ki", np.abs(H) ** 2, np.einsum("kjj->kj", S).real)
    got = np.einsum("kii->ki", psd)
    np.testing.assert_allclose(got.real, auto, rtol=1e-8)
    assert np.abs(got.imag).max() <= 1e-12 * auto.max()
    code, _, err, h5 = run_case(capsys, tmp_path, case_text("[]"))
    assert code == 0, err
    f1, psd1, rms1, csd1 = read(h5)
    assert csd1 is None
    np.testing.assert_allclose(np.einsum("kii->ki", psd1), got, rtol=1e-12, atol=0)
    np.testing.assert_allclose(rms1, rms0, rtol=1e-12)


def test_parseval_random_phase_transient(capsys, tmp_path):
    """Input r of run r: x_r(t) = sum_k Re(sqrt(2 df) L_k[:, r] e^{i (w_k t + theta_k)}) with
    L_k L_k^H = S_f(f_k) (Cholesky) and random phases theta_k: a multisine of period 1/df whose
    mean square over a period is, by Parseval, df sum_k |(H L_k)_{ir}|^2; summed over the runs,
    df sum_k S_y,ii(f_k). Each run is integrated in time (first-order-hold discretization,
    step 1/2000 s: the amplitude error is below (w dt)^2/12 = 2e-4 at the 17 Hz mode, 1.3e-3
    at 40 Hz where the response is 1e-3 of the peak) over three periods, the first two left
    for the free response to decay (e^{-0.55 x 20} < 1e-4)."""
    code, _, err, h5 = run_case(capsys, tmp_path, case_text(
        f"[{{between: [a@mass, b@mass], coherence: {COH}, phase: {PHASE}}}]"))
    assert code == 0, err
    f, psd, rms_, csd = read(h5)
    df = f[1] - f[0]
    expected = df * np.einsum("kii->ki", psd).real.sum(axis=0)
    L = np.linalg.cholesky(csd)
    dt, period = 1 / 2000, 1 / df
    period_t = np.arange(int(round(period / dt))) * dt
    t = np.arange(3 * len(period_t)) * dt
    rng = np.random.default_rng(3)
    n = 2
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(M, K), -np.linalg.solve(M, C)]])
    B = np.vstack([np.zeros((n, n)), np.linalg.inv(M)])
    Cd, Dd = np.hstack([np.eye(n), np.zeros((n, n))]), np.zeros((n, n))
    system = sig.cont2discrete((A, B, Cd, Dd), dt, method="foh")
    tail = t >= 2 * period - dt / 2
    got = np.zeros(n)
    for r in range(n):
        theta = rng.uniform(0, 2 * np.pi, len(f))
        amp = np.sqrt(2 * df) * L[:, :, r] * np.exp(1j * theta)[:, None]       # (k, inputs)
        lines = np.zeros((len(period_t) // 2 + 1, n), dtype=complex)
        lines[np.rint(f / df).astype(int)] = amp * len(period_t) / 2
        x = np.tile(np.fft.irfft(lines, n=len(period_t), axis=0), (3, 1))   # (t, inputs)
        y = sig.dlsim(system[:4] + (dt,), x)[1]
        got += np.mean(y[tail] ** 2, axis=0)
    np.testing.assert_allclose(got, expected, rtol=2e-3)
    assert np.all(rms_ ** 2 > 0)


@pytest.mark.parametrize("cross, forces, fragments", [
    ("[{between: [a@mass, b@mass], coherence: 1}, {between: [a@mass, b@boundary], "
     "coherence: 1}, {between: [b@mass, b@boundary], coherence: 1, phase: 180}]",
     "      - {at: a@mass, psd: [[0.5, 2.0], [50, 2.0]]}\n"
     "      - {at: b@mass, psd: [[0.5, 2.0], [50, 2.0]]}\n"
     "      - {at: b@boundary, psd: [[0.5, 2.0], [50, 2.0]]}\n",
     ("analysis.random.cross", "not positive semidefinite at 0.5 Hz",
      "smallest eigenvalue -2")),
    ("[{between: [a@mass, a@boundary], coherence: 0.5}]", None,
     ("analysis.random.cross[0].between[1]", "not one of the inputs")),
    ("[{between: [a@mass, a@mass], coherence: 0.5}]", None,
     ("analysis.random.cross[0].between", "two different inputs")),
    ("[{between: [a@mass, b@mass], coherence: 0.5}, {between: [b@mass, a@mass], "
     "coherence: 0.1}]", None, ("analysis.random.cross[1].between", "given twice")),
    ("[{between: [a@mass, b@mass], coherence: 1.5}]", None,
     ("analysis.random.cross[0].coherence", "1.5")),
])
def test_refused(capsys, tmp_path, cross, forces, fragments):
    code, out, err, h5 = run_case(capsys, tmp_path, case_text(cross, forces))
    assert_one_line_error(code, out, err, *fragments)
    assert not h5.exists()
