"""Rigid-body and suspension modes beside the spurious zero roots of eqs (30)/(34).

A free plate (``cases/plate_2d.yaml`` without its clamp) reduced to 16 modes and held by one
y-spring has two rigid-body motions (a free body in the plane has three; the tie of one point
in y removes one).  The generalized-inverse method listed one, or none with modal damping
kept, and the run stopped on its checks (exit 1, "disagrees by 1.0e+00"); without checks the
short list went out with exit code 0.  Two causes:

* modal truncation kept a free part's rigid-body eigenvalues as computed, round-off of either
  sign (``2.7e-5`` or ``-5.5e-5`` for the plate, as the BLAS's threads fell): a positive one
  went into the coupled model as a soft spring of ``0.0052`` rad/s (with 1 % of modal
  damping on it), no longer a rigid-body motion;
* the generalized-inverse pencil's ``2 rank(A)`` spurious zeros split by round-off to about
  ``sqrt(eps)`` of the root scale, and the vectors of a suspension mode that soft are mixed
  with theirs (``|A u|`` of ``1e-3`` to ``0.2``): it was set aside as "violates the
  constraints", or the artifact was taken for the mode.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp

from cli_helpers import run
from substruct.analysis.modes.dense import coupled_modes
from substruct.analysis.modes.roots import SPURIOUS_ZERO
from substruct.models.reduction import undamped_modes
from substruct.substructure import Substructure

METHODS = ["generalized-inverse", "null-space", "kkt"]
EPS = np.finfo(float).eps


def alternating_chain(n: int, scale: float) -> Substructure:
    """A free-free chain of springs ``0.1`` and ``0.2`` (times ``scale``): ``0.1 + 0.2`` is not
    ``0.3`` in floating point, so ``K 1`` is round-off, not zero, as in a meshed body."""
    k = np.where(np.arange(n - 1) % 2, 0.2, 0.1) * scale
    K = sp.diags_array([np.r_[k, 0] + np.r_[0, k], -k, -k], offsets=[0, 1, -1], format="csr")
    M = sp.diags_array(np.linspace(1.0, 2.0, n), format="csr")
    return Substructure(name="chain", M=M, K=K, C=sp.csr_array((n, n)),
                        dof_labels=tuple(f"q{i}" for i in range(n)), locate=lambda point: None)


@pytest.mark.parametrize("scale", [1.0, 1e6, 1e-6])
@pytest.mark.parametrize("n, dense_limit", [(40, 100), (400, 100), (400, 5000)])
def test_modal_truncation_gives_a_free_part_exact_rigid_modes(n, dense_limit, scale):
    """The rigid-body mode of a free chain is exactly 0 after reduction (it was up to 1e-6 rad/s,
    a spring in the coupled model); the elastic ones equal the dense eigenvalues."""
    sub = alternating_chain(n, scale)
    omega, _ = undamped_modes(sub, 4, dense_limit=dense_limit)
    assert omega[0] == 0.0
    ref = np.sqrt(sla.eigh(sub.K.toarray(), sub.M.toarray(), eigvals_only=True)[1:4])
    assert np.abs(omega[1:] - ref).max() <= 1e-9 * ref.max()


def run_plate(tmp_path, capsys, method: str, damped: bool) -> tuple[int, dict, str]:
    args = ["run", "cases/plate_2d.yaml", "--out", tmp_path / method, "--force",
            "--no-pictures", "--json", "--set", "analysis.frf=null",
            "--set", "substructures.plate.fixed=[]", "--set", f"analysis.modes.method={method}",
            "--set", "analysis.modes.check=[" + ", ".join(m for m in METHODS if m != method)
            + "]"]
    if not damped:
        args += ["--set", "substructures.plate.reduce={modes: 16}"]
    code, out, err = run(capsys, *args)
    return code, (json.loads(out) if code == 0 else {}), err


@pytest.mark.parametrize("damped", [False, True])
@pytest.mark.parametrize("method", METHODS)
def test_free_plate_on_one_spring_has_two_rigid_modes(tmp_path, capsys, method, damped):
    """Every method lists the two rigid-body modes at 0 and agrees with the other two within
    the default tolerance (exit 0); the generalized inverse sets aside its 2 rank(A) = 2
    artifacts and nothing else."""
    code, res, err = run_plate(tmp_path, capsys, method, damped)
    assert code == 0, err
    omega = np.array(res["modes"]["omega"])
    assert np.count_nonzero(omega == 0.0) == 2 and omega[2] > 500, omega
    reasons = res["modes"]["spurious"]["reasons"]
    if method == "generalized-inverse":
        assert reasons == {SPURIOUS_ZERO: 2}, reasons


def chain_on_a_free_body(grounded: tuple[int, ...], mass: float, stiff: float,
                         damp: float) -> tuple[np.ndarray, ...]:
    """A free-free chain of four nodes tied at its end to a free two-node body, each node with
    ``x, y, z``; springs along every direction, a spring to ground at the body's last node in
    the directions ``grounded``, dashpots in the chain (rigid translations feel none).  The
    rigid-body modes: ``3 - len(grounded)`` translations of the whole."""
    rng = np.random.default_rng(7)
    nodes, dirs = 6, 3
    n = nodes * dirs
    M = np.diag(np.repeat(rng.uniform(1, 3, nodes), dirs)) * mass
    K, C = np.zeros((n, n)), np.zeros((n, n))
    pair = np.array([[1.0, -1.0], [-1.0, 1.0]])
    for d in range(dirs):
        for i in (0, 1, 2, 4):  # the chain 0-1-2-3 and the body 4-5
            ij = np.ix_([i * dirs + d, (i + 1) * dirs + d], [i * dirs + d, (i + 1) * dirs + d])
            K[ij] += rng.uniform(100, 300) * stiff * pair
            C[ij] += (damp * np.sqrt(stiff * mass) * pair) if i < 3 else 0.0
    for d in grounded:
        K[5 * dirs + d, 5 * dirs + d] += 50 * stiff
    A = np.zeros((dirs, n))
    for d in range(dirs):
        A[d, 3 * dirs + d], A[d, 4 * dirs + d] = 1.0, -1.0
    return M, C, K, A


@pytest.mark.parametrize("grounded", [(), (1,), (0, 2)])
@pytest.mark.parametrize("units", [(1.0, 1.0), (1e-3, 1e6)])
@pytest.mark.parametrize("damp", [0.0, 0.3])
def test_chain_on_a_free_body_rigid_count(grounded, units, damp):
    """``3 - len(grounded)`` rigid-body modes by every method, in both sets of units, damped or
    not; the other roots the same by all three to 1e-9 of the largest."""
    M, C, K, A = chain_on_a_free_body(grounded, *units, damp)
    res = {m: coupled_modes(M, C, K, A, m) for m in METHODS}
    for m, r in res.items():
        assert np.count_nonzero(r.omega == 0.0) == 3 - len(grounded), (m, r.omega[:4])
    ref = res["null-space"].eigenvalues
    for m in ("generalized-inverse", "kkt"):
        assert res[m].eigenvalues.size == ref.size
        assert np.abs(res[m].eigenvalues - ref).max() <= 1e-9 * np.abs(ref).max(), m
    assert res["generalized-inverse"].spurious_reason.count(SPURIOUS_ZERO) == 2 * 3


def modal_body_on_a_support(delta: float, mass: float, stiff: float,
                            damp: float) -> tuple[np.ndarray, ...]:
    """A supplier's modal model whose three rigid-body modes come with ``omega^2 = delta``
    instead of 0 (M = I, K diagonal up to 4.2e9), one point of it (a combination of its first,
    second and fourth modal coordinates) tied to a mass of 2 on a spring of 2e6 to the ground
    and a dashpot.  Two motions keep ``K u = delta M u`` under the tie (the third coordinate,
    and the first minus the second in the ratio that leaves the tie unmoved): two suspension
    modes at ``sqrt(delta)`` exactly."""
    k = np.array([delta, delta, delta, 3.5e7, 1.9e8, 2.6e8, 5.4e8, 1.0e9, 4.2e9])
    n = k.size + 1
    M = np.diag(np.r_[np.ones(k.size), 2.0]) * mass
    K = np.diag(np.r_[k, 2e6]) * stiff
    C = np.zeros((n, n))
    C[-1, -1] = damp * np.sqrt(stiff * mass)
    A = np.zeros((1, n))
    A[0, [0, 1, 3, n - 1]] = [0.2, 0.13, -0.23, -0.5]
    return M, C, K, A


@pytest.mark.parametrize("delta", [2.7e-5, 1e-5, 1e-6])
@pytest.mark.parametrize("units", [(1.0, 1.0), (1e-3, 1e6)])
@pytest.mark.parametrize("damp", [0.0, 200.0])
def test_suspension_modes_beside_the_spurious_zeros(delta, units, damp):
    """All nine modes by every method (the generalized inverse dropped a suspension mode with
    the dashpot); the two suspension modes at ``omega^2 = delta`` within what the dense
    pencils resolve, ``10 eps s^2`` (``s^2`` = 4.2e9 in these units, so 3 % of ``delta =
    2.7e-5``), the other roots the same by all three to 1e-9."""
    mass, stiff = units
    w2 = stiff / mass
    M, C, K, A = modal_body_on_a_support(delta, mass, stiff, damp)
    res = {m: coupled_modes(M, C, K, A, m) for m in METHODS}
    for m, r in res.items():
        assert r.omega.size == 9, (m, r.omega[:3], r.spurious_reason)
        assert np.abs(r.omega[:2] ** 2 / w2 - delta).max() <= 10 * EPS * 4.2e9, (m, r.omega[:2])
    ref = res["null-space"].eigenvalues[2:]
    for m in ("generalized-inverse", "kkt"):
        assert np.abs(res[m].eigenvalues[2:] - ref).max() <= 1e-9 * np.abs(ref).max(), m
    assert res["generalized-inverse"].spurious_reason == [SPURIOUS_ZERO] * 2
