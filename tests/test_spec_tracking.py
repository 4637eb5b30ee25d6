"""Modes tracked through a parameter by MAC assignment: crossing of uncoupled oscillators,
veering of weakly coupled ones (closest approach 2 kc at k1 = k2)."""

import numpy as np
import pytest
import scipy.linalg as sla

from substruct.analysis.modes.tracking import pair_by_assignment, track_modes


def sweep(kc, params):
    """Two unit masses on springs k1 = p, k2 = 100, coupled by kc (stiffness off-diagonal
    -kc): sorted frequencies and shapes at each p."""
    F, P = [], []
    for p in params:
        K = np.array([[p + kc, -kc], [-kc, 100.0 + kc]])
        lam, phi = sla.eigh(K, np.eye(2))
        F.append(np.sqrt(lam))
        P.append(phi)
    return F, P


@pytest.mark.parametrize("num", [21, 20])  # p = 100 sampled (a tie) or not
def test_uncoupled_crossing_tracked(num):
    """kc = 0: the tracked curves are sqrt(p) and 10 exactly (they cross at p = 100); the
    sorted ones never cross."""
    params = np.linspace(50.0, 150.0, num)
    F, P = sweep(0.0, params)
    tr = track_modes(F, P)
    t_soft = int(np.argmin(tr.frequency[0]))
    assert np.allclose(tr.frequency[:, t_soft], np.sqrt(params), rtol=1e-12)
    assert np.allclose(tr.frequency[:, 1 - t_soft], 10.0, rtol=1e-12)
    assert len(tr.crossings) == 1
    assert tr.crossings[0][0] == np.flatnonzero(params < 100.0)[-1]
    assert tr.veerings == []
    assert np.allclose(tr.mac, 1.0)
    # frequency order alone would keep mode 0 the lowest: no crossing, the shape jumps
    sorted_f = np.stack(F)
    assert np.all(sorted_f[:, 0] <= sorted_f[:, 1])


def test_weak_coupling_veers():
    """kc = 2: the eigenvalue gap is sqrt((p - 100)^2 + 4 kc^2), least (2 kc = 4) at p = 100;
    tracked curves do not cross, the shapes exchange (MAC first-to-last ~ 0), a veering is
    marked at p = 100."""
    kc = 2.0
    params = np.linspace(50.0, 150.0, 21)
    F, P = sweep(kc, params)
    tr = track_modes(F, P)
    assert tr.crossings == []
    assert len(tr.veerings) == 1
    s, t, u = tr.veerings[0]
    assert params[s] == pytest.approx(100.0)
    lam = tr.frequency[s] ** 2
    assert abs(lam[t] - lam[u]) == pytest.approx(2 * kc, rel=1e-12)
    # the tracks are the sorted curves here (no crossing)
    assert np.allclose(np.sort(tr.frequency, axis=1), np.stack(F))


def test_frequency_weight_and_refusals():
    """Repeated shapes (MAC all equal): the frequency term decides."""
    mac = np.full((2, 2), 0.5)
    assert list(pair_by_assignment(mac, np.array([1.0, 2.0]), np.array([2.1, 0.9]), 1.0)) \
        == [1, 0]
    with pytest.raises(ValueError, match=">= 0"):
        pair_by_assignment(mac, frequency_weight=-1.0)
    with pytest.raises(ValueError, match="same number"):
        track_modes([np.ones(2), np.ones(3)], [np.eye(2), np.eye(3)])
