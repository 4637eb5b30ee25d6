"""System equivalent model mixing (substruct.analysis.frf.semm) on spring-mass chains with
closed-form receptances Y = (K - w^2 M + i w C)^-1: the numerical model is a chain, the
"experiment" the same chain with two springs and a mass changed.

Tolerances: the mix applies the pseudo-inverse of the numerical boundary block twice, so its
round-off is about eps kappa^2 |Y| with kappa that block's condition number (at most 1e4 on
this chain: bound 100 eps kappa^2 relative, printed against the measured error).
"""

from __future__ import annotations

import numpy as np
import pytest

from substruct.analysis.frf.semm import channel_coherence, coherence, noise_gain, semm

N = 8
OMEGA = np.linspace(5.0, 400.0, 60)
LABELS = [f"{i}:ux" for i in range(N)]
EPS = np.finfo(float).eps


def _chain(k: np.ndarray, m: np.ndarray) -> np.ndarray:
    """Receptances (n_omega, N, N) of a chain grounded at its first spring."""
    K = np.zeros((N, N))
    for i in range(N):
        K[i, i] += k[i]
        if i + 1 < N:
            K[i, i] += k[i + 1]
            K[i, i + 1] = K[i + 1, i] = -k[i + 1]
    M, C = np.diag(m), 2e-4 * K
    return np.linalg.inv(K[None] - OMEGA[:, None, None] ** 2 * M[None]
                         + 1j * OMEGA[:, None, None] * C[None])


K0, M0 = np.full(N, 1.0e5), np.full(N, 1.0)
Y_NUM = _chain(K0, M0)
K1, M1 = K0.copy(), M0.copy()
K1[[3, 6]] *= [1.3, 0.8]
M1[5] *= 1.2
Y_TRUE = _chain(K1, M1)
B = [1, 4, 7]
BL = [LABELS[i] for i in B]


def _sub(Y, rows, cols):
    return Y[:, rows][:, :, cols]


def test_equal_experiment_leaves_the_numerical_model_exactly():
    res = semm(Y_NUM, LABELS, LABELS, _sub(Y_NUM, B, B), BL, BL)
    assert np.array_equal(res.Y, Y_NUM)          # the bracket is exactly zero
    assert np.isnan(res.indicator).all()         # every measured entry is on the boundary
    # with a validation row (sensor 5) the indicator is exactly 1
    rows = [1, 4, 5, 7]
    res = semm(Y_NUM, LABELS, LABELS, _sub(Y_NUM, rows, B), [LABELS[i] for i in rows], BL,
               boundary_out=BL)
    assert res.validation.sum() == 3 and res.validation[2].all()
    np.testing.assert_array_equal(res.indicator, 1.0)


def test_the_mix_reproduces_the_measurement_at_the_boundary():
    res = semm(Y_NUM, LABELS, LABELS, _sub(Y_TRUE, B, B), BL, BL)
    kappa = np.linalg.cond(_sub(Y_NUM, B, B)).max()
    scale = np.abs(_sub(Y_TRUE, B, B)).max()
    err = np.abs(_sub(res.Y, B, B) - _sub(Y_TRUE, B, B)).max() / scale
    print(f"kappa {kappa:.3g}, boundary error {err:.3g}")
    assert kappa < 1e4
    assert err < 100 * EPS * kappa ** 2
    # the mix differs from the numerical model away from the boundary: it is not a copy
    assert np.abs(res.Y - Y_NUM).max() > 1e-3 * np.abs(Y_NUM).max()
    # a boundary at every coordinate gives the experimental model everywhere
    full = semm(Y_NUM, LABELS, LABELS, Y_TRUE, LABELS, LABELS)
    kappa_full = np.linalg.cond(Y_NUM).max()
    err_full = np.abs(full.Y - Y_TRUE).max() / np.abs(Y_TRUE).max()
    print(f"kappa(all) {kappa_full:.3g}, error {err_full:.3g}")
    assert err_full < 100 * EPS * kappa_full ** 2


def test_validation_coherence_sees_the_model_error():
    rows = [1, 4, 5, 7]
    res = semm(Y_NUM, LABELS, LABELS, _sub(Y_TRUE, rows, B), [LABELS[i] for i in rows], BL,
               boundary_out=BL)
    # the mixed model at sensor 5 is a prediction; the changed mass (node 5) shows in it
    g = res.coherence[:, 2]
    assert g.min() < 0.9 and np.all((g >= 0) & (g <= 1 + 1e-12))
    np.testing.assert_allclose(res.coherence[:, [0, 1, 3]], 1.0, atol=1e-9)
    a = np.array([1 + 2j, -3.0])
    np.testing.assert_allclose(coherence(a, a), 1.0)
    np.testing.assert_allclose(coherence(a, -a), 0.0)


@pytest.mark.parametrize("eps", [1e-3, 1e-2])
def test_noise_is_bounded_by_the_stated_gain_and_linear(eps):
    rng = np.random.default_rng(7)
    clean = semm(Y_NUM, LABELS, LABELS, _sub(Y_TRUE, B, B), BL, BL).Y
    gain = noise_gain(Y_NUM, LABELS, LABELS, BL, BL)
    E = _sub(Y_TRUE, B, B)
    for _ in range(10):
        dE = eps * np.abs(E) * (rng.normal(size=E.shape) + 1j * rng.normal(size=E.shape))
        noisy = semm(Y_NUM, LABELS, LABELS, E + dE, BL, BL).Y
        twice = semm(Y_NUM, LABELS, LABELS, E + 2 * dE, BL, BL).Y
        dS = np.linalg.norm(noisy - clean, axis=(1, 2))
        bound = gain * np.linalg.norm(dE, axis=(1, 2))
        assert np.all(dS <= bound * (1 + 1e-6))
        # linear in the perturbation: doubling it doubles the change (to round-off of the mix)
        lin = np.linalg.norm(twice - clean - 2 * (noisy - clean), axis=(1, 2))
        assert np.all(lin <= 1e-6 * np.linalg.norm(noisy - clean, axis=(1, 2)) + 1e-12 * bound)


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="not finite at index"):
        E = _sub(Y_TRUE, B, B).copy()
        E[3, 1, 2] = np.nan
        semm(Y_NUM, LABELS, LABELS, E, BL, BL)
    with pytest.raises(ValueError, match="'9:ux' is not a coordinate of the numerical"):
        semm(Y_NUM, LABELS, LABELS, _sub(Y_TRUE, B, B), [*BL[:2], "9:ux"], BL)
    with pytest.raises(ValueError, match="expected \\(60, 3, 3\\)"):
        semm(Y_NUM, LABELS, LABELS, _sub(Y_TRUE, B, B)[:5], BL, BL)


# --- the extended form and the channel coherence -------------------------------------------
#: measured: five sensors, three impacts (a rectangular boundary, every measured channel)
O_EXT, I_EXT = [1, 3, 4, 6, 7], [1, 4, 7]
OL_EXT, IL_EXT = [LABELS[i] for i in O_EXT], [LABELS[i] for i in I_EXT]


def test_extended_form_leaves_the_numerical_model_where_the_data_is_exact():
    res = semm(Y_NUM, LABELS, LABELS, _sub(Y_NUM, O_EXT, I_EXT), OL_EXT, IL_EXT,
               form="extended")
    assert np.array_equal(res.Y, Y_NUM)          # the bracket is exactly zero
    with pytest.raises(ValueError, match="standard or extended, got 'other'"):
        semm(Y_NUM, LABELS, LABELS, _sub(Y_NUM, O_EXT, I_EXT), OL_EXT, IL_EXT, form="other")


def test_extended_form_reproduces_every_measured_channel():
    """Boundary = all five sensors x three impacts.  Extended: the measurement at every
    measured entry, to round-off of the two pseudo-inverses (measured 5.9e-14; bound
    100 eps kappa_rows kappa_cols, the condition numbers of the boundary rows and columns of
    the model, 4.9e3 and 1.3e3).  The standard form with the same rectangular boundary does
    not (its boundary block has no inverse: measured 0.83%).  Both move the model towards
    the changed chain everywhere (median relative error over frequencies of the whole 8 x 8
    receptance: model 0.20, standard 0.064, extended 0.060)."""
    E = _sub(Y_TRUE, O_EXT, I_EXT)
    ext = semm(Y_NUM, LABELS, LABELS, E, OL_EXT, IL_EXT, form="extended")
    std = semm(Y_NUM, LABELS, LABELS, E, OL_EXT, IL_EXT)
    k_rows = np.linalg.cond(Y_NUM[:, O_EXT, :]).max()
    k_cols = np.linalg.cond(Y_NUM[:, :, I_EXT]).max()
    scale = np.abs(E).max()
    err = np.abs(_sub(ext.Y, O_EXT, I_EXT) - E).max() / scale
    print(f"kappa rows {k_rows:.3g}, cols {k_cols:.3g}, measured-channel error {err:.3g}")
    assert err < 100 * EPS * k_rows * k_cols
    assert np.abs(_sub(std.Y, O_EXT, I_EXT) - E).max() / scale > 1e-3

    def whole(Y):
        return np.median(np.linalg.norm(Y - Y_TRUE, axis=(1, 2))
                         / np.linalg.norm(Y_TRUE, axis=(1, 2)))
    assert whole(ext.Y) < 0.5 * whole(Y_NUM) and whole(std.Y) < 0.5 * whole(Y_NUM)


def test_channel_coherence_flags_a_flipped_sensor():
    """Each sensor left out of the boundary in turn and predicted by the others: exact data
    gives 1; the changed chain's data median coherences above 0.99 (measured 0.996-0.999);
    with sensor 4's sign flipped its coherence falls to a median of 0.003, the lowest, while
    the others' stay above 0.4 (measured 0.42-0.86: it is on their boundary)."""
    exact = channel_coherence(Y_NUM, LABELS, LABELS, _sub(Y_NUM, O_EXT, I_EXT), OL_EXT,
                              IL_EXT)
    np.testing.assert_allclose(exact, 1.0, atol=1e-9)
    E = _sub(Y_TRUE, O_EXT, I_EXT)
    good = channel_coherence(Y_NUM, LABELS, LABELS, E, OL_EXT, IL_EXT)
    assert good.shape == (len(OMEGA), 5) and np.all(np.median(good, axis=0) > 0.99)
    flipped = E.copy()
    flipped[:, 2, :] *= -1                        # sensor 4 (third measured row) reads -u
    bad = np.median(channel_coherence(Y_NUM, LABELS, LABELS, flipped, OL_EXT, IL_EXT), axis=0)
    assert bad[2] < 0.05 and np.argmin(bad) == 2 and np.delete(bad, 2).min() > 0.4
    with pytest.raises(ValueError, match="at least two measured outputs"):
        channel_coherence(Y_NUM, LABELS, LABELS, E[:, :1], OL_EXT[:1], IL_EXT)
