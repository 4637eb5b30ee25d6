"""Transfer path analysis on the synthetic test lab (tests/testlab_models.py): a source inside
the free frame A (forces at two of its nodes) runs on the clamped receptor B.  The blocked
forces at the joint are known from A alone, f = Y_A,JJ^-1 Y_A,Js F; found from the assembly's
responses by matrix inverse (at the joint), in situ (nine indicator responses on B) or through
the virtual point (the adapter's impacts transformed by T_f), they agree with it and predict
the responses at validation points of B, and the path contributions add up to the prediction.

Tolerance: as in tests/test_virtual_point.py, the finite-element receptances are accurate to
about 3.5e-10 of their largest entry; 1e-8 leaves a margin of about 30.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from substruct.analysis.frf.tpa import (
    blocked_forces_in_situ,
    blocked_forces_matrix_inverse,
    on_board_validation,
    path_contributions,
)
from substruct.analysis.frf.virtual_point import VirtualPoint, virtual_point_transform
from substruct.analysis.frf.vp_coupling import Regularisation
from substruct.case.channels import parse_channels
from testlab_models import (
    OMEGA,
    adapter_rows,
    assembly,
    channel_matrix,
    node_dofs,
    part_a,
    receptance,
)

EXACT = 1e-8
#: the source: forces at A's nodes 3 (z) and 4 (x), with these amplitudes
SOURCE = [("3:uz", 1.0), ("4:ux", 0.4 - 0.3j)]
#: indicator points on B: three translations at three places
INDICATORS = [((x, y, z), c) for (x, y, z) in [(1 / 6, 0.0, 0.0), (0.5, 0.0, 0.0),
                                                (0.5, 0.35, 0.0)] for c in ("ux", "uy", "uz")]
#: validation points on B, not used to find the forces
TARGETS = [((0.5, 0.35 * 2 / 3, 0.0), "uz"), ((0.5, 0.0, -0.1), "uy"), ((1 / 3, 0.0, 0.0), "uz")]


def _at(sub, points):
    return sp.csr_array(sp.vstack([sub.locate({"at": list(p), "component": c})
                                   for p, c in points]))


def _source(sub):
    return sp.csr_array(sp.vstack([sub.locate(d) for d, _ in SOURCE]))


F = np.array([a for _, a in SOURCE])


@pytest.fixture(scope="module")
def lab():
    A, AB = part_a(), assembly()
    J = node_dofs(A, 1)
    u_free = receptance(A, J, _source(A)) @ F  # the joint of the free source, running
    truth = np.linalg.solve(receptance(A, J, J), u_free[:, :, None])[:, :, 0]
    Jab, s = node_dofs(AB, 1), _source(AB)
    b, t = _at(AB, INDICATORS), _at(AB, TARGETS)
    out = sp.csr_array(sp.vstack([Jab, b, t]))
    Y = receptance(AB, out, sp.csr_array(sp.vstack([Jab, s])))
    Yc, Ys = Y[:, :, :6], Y[:, :, 6:]
    u = Ys @ F  # the operational responses (k, 6 + 9 + 3)
    return dict(A=A, AB=AB, truth=truth, Yc=Yc, u=u, nb=len(INDICATORS))


def _rel(X, ref):
    return float(np.abs(X - ref).max() / np.abs(ref).max())


def test_blocked_forces_by_matrix_inverse_and_in_situ(lab):
    Yc, u, nb, truth = lab["Yc"], lab["u"], lab["nb"], lab["truth"]
    f_mi = blocked_forces_matrix_inverse(Yc[:, :6], u[:, :6])
    assert _rel(f_mi, truth) < EXACT
    f_is = blocked_forces_in_situ(Yc[:, 6:6 + nb], u[:, 6:6 + nb])
    assert _rel(f_is, truth) < EXACT
    val = on_board_validation(Yc[:, 6 + nb:], f_is, u[:, 6 + nb:])
    assert val.error.max() < EXACT * 10  # relative per frequency, at the targets only
    paths = path_contributions(Yc[:, 6 + nb:], f_is)
    assert paths.shape == (len(OMEGA), len(TARGETS), 6)
    assert _rel(paths.sum(axis=2), val.predicted) < 1e-14
    # a wrong source model fails the validation: forces of A with only its first force
    wrong = blocked_forces_in_situ(Yc[:, 6:6 + nb], u[:, 6:6 + nb] * 0.5)
    assert on_board_validation(Yc[:, 6 + nb:], wrong, u[:, 6 + nb:]).error.min() > 0.49


def test_blocked_forces_at_the_virtual_point_from_the_adapter_impacts(lab):
    """The assembly's transfers from the adapter's impacts to the indicators, transformed by
    T_f, are the transfers from the virtual point's loads: in-situ blocked forces at the
    virtual point from them equal the joint's."""
    AB, nb = lab["AB"], lab["nb"]
    table = parse_channels(adapter_rows("A", (0.0, 0.0, 0.0), 1), "AB")
    impacts = [c.name for c in table.of_kind("impact")]
    sensors = [c.name for c in table.of_kind("sensor")]
    vpt = virtual_point_transform(table, [VirtualPoint("J", (0.0, 0.0, 0.0), tuple(sensors),
                                                       tuple(impacts))], sensors, impacts)
    Y_bh = receptance(AB, _at(AB, INDICATORS), channel_matrix(AB, table, impacts, {}))
    Y_bq = np.einsum("kbi,mi->kbm", Y_bh, vpt.Tf)
    f = blocked_forces_in_situ(Y_bq, lab["u"][:, 6:6 + nb])
    assert _rel(f, lab["truth"]) < EXACT


def test_in_situ_with_noise_and_regularisation(lab):
    """Complex noise of relative level eps on the indicator FRFs and responses (20 seeds).

    Measured: the validation error at the targets (median over frequencies, then seeds) is
    4.9% at eps = 1% and 0.77% at eps = 0.1%.  Truncated SVD with the rule rtol = eps, the
    moments scaled by 0.3 m (the members' length) so that the singular values compare one
    unit, lowers it to 3.0% at eps = 1%; at eps = 0.1% the same truncation (1.3%) and a
    threshold above the noise (rtol = 1e-2: 2.7%) only add bias: regularise when the noise
    is high, by its level."""
    Yc, u, nb = lab["Yc"], lab["u"], lab["nb"]
    med: dict[tuple, list] = {}
    for eps in (1e-2, 1e-3):
        for seed in range(20):
            rng = np.random.default_rng(seed)
            noise = lambda X: X * (1 + eps * (rng.normal(size=X.shape)  # noqa: E731
                                              + 1j * rng.normal(size=X.shape)) / np.sqrt(2))
            Yb, ub = noise(Yc[:, 6:6 + nb]), noise(u[:, 6:6 + nb])
            for name, reg in (("plain", Regularisation()),
                              ("rule", Regularisation("tsvd", rtol=eps)),
                              ("high", Regularisation("tsvd", rtol=1e-2))):
                f = blocked_forces_in_situ(Yb, ub, reg, scale=[1, 1, 1, 0.3, 0.3, 0.3])
                err = on_board_validation(Yc[:, 6 + nb:], f, u[:, 6 + nb:]).error
                med.setdefault((name, eps), []).append(np.median(err))
    m = {k: float(np.median(v)) for k, v in med.items()}
    assert m["plain", 1e-2] < 10 * 1e-2 and m["plain", 1e-3] < 10 * 1e-3
    assert m["plain", 1e-3] < m["plain", 1e-2] / 4  # shrinks with the noise
    assert m["rule", 1e-2] < 0.8 * m["plain", 1e-2]
    assert m["high", 1e-3] > 2 * m["plain", 1e-3]  # a threshold above the noise: a bias


def test_bad_input(lab):
    Yc, u = lab["Yc"], lab["u"]
    with pytest.raises(ValueError, match="at least as many indicator responses as interface "
                       "coordinates: 5 < 6"):
        blocked_forces_in_situ(Yc[:, 6:11], u[:, 6:11])
    bad = u[:, 6:15].copy()
    bad[3, 2] = np.nan
    with pytest.raises(ValueError, match=r"the responses are not finite at index \[3, 2\]"):
        blocked_forces_in_situ(Yc[:, 6:15], bad)
    with pytest.raises(ValueError, match="do not match"):
        blocked_forces_in_situ(Yc[:, 6:15], u[:-1, 6:15])
    with pytest.raises(ValueError, match="need the square interface receptance"):
        blocked_forces_matrix_inverse(Yc[:, 6:15], u[:, 6:15])
