"""A constraint row means the same whatever its scale: ``1e-8 q1 = 0`` and ``1e-300 q1 = 0`` are
``q1 = 0``.

The model: a two-coordinate chain ``P`` (ground -1- q1 -1- q2, unit masses) and a free-free
absorber ``d`` (massless boundary b, spring 1 and dashpot 0.2 to a unit mass y), joined by the
connection ``q2 = b``, under the user constraint ``c q1 = 0``.  With ``q1 = 0`` the coupled roots
``s`` are those of

.. math::  (s^2 + 1 + a)(s^2 + a) - a^2 = 0, \\qquad a = 1 + 0.2 s,

and the receptance is :math:`T Z_r^{-1} T^T` with the impedance of ``(q2, y)``,
:math:`Z_r = [-\\omega^2 + 1 + a, -a; -a, -\\omega^2 + a]`, :math:`a = 1 + 0.2 i\\omega`, and
:math:`T` mapping ``(q2, y)`` to ``(q1, q2, b, y) = (0, q2, q2, y)``.  Every formulation (dense
modes, sparse modes, receptances) must give these numbers for ``c = 1, 1e-8, 1e-300``; before the
rows were equilibrated the generalized inverse gave a wrong mode for ``1e-8`` (its
``A M^-1 A^T`` looked rank deficient) and every formulation dropped the ``1e-300`` row.
"""

from __future__ import annotations

import json

import numpy as np
import numpy.polynomial.polynomial as P
import pytest
import scipy.sparse as sp

from cli_helpers import run
from substruct.analysis.formulations.coupling import FORMULATIONS, receptance
from substruct.analysis.modes.dense import coupled_modes
from substruct.analysis.modes.sparse import FORMULATIONS, sparse_coupled_modes
from substruct.linalg.scaling import ZeroRowError

SCALES = [1.0, 1e-8, 1e-300]
C_ABS = 0.2


def chain_model(c: float):
    """``M, C, K, A`` over ``(q1, q2, b, y)`` with the rows ``q2 - b = 0`` and ``c q1 = 0``."""
    M = np.diag([1.0, 1.0, 0.0, 1.0])
    K = np.array([[2.0, -1, 0, 0], [-1, 1, 0, 0], [0, 0, 1, -1], [0, 0, -1, 1]])
    C = np.zeros((4, 4))
    C[2:, 2:] = C_ABS * np.array([[1.0, -1], [-1, 1]])
    A = np.array([[0.0, 1, -1, 0], [c, 0, 0, 0]])
    return M, C, K, A


def exact_roots() -> np.ndarray:
    """The roots with ``Im > 0`` of the characteristic polynomial, ascending in modulus."""
    a = np.array([1.0, C_ABS])
    poly = P.polysub(P.polymul(P.polyadd([1.0, 0, 1], a), P.polyadd([0.0, 0, 1], a)),
                     P.polymul(a, a))
    roots = P.polyroots(poly)
    roots = roots[roots.imag > 0]
    return roots[np.argsort(np.abs(roots))]


def exact_receptance(omega: float) -> np.ndarray:
    a = 1.0 + C_ABS * 1j * omega
    Zr = np.array([[-omega**2 + 1 + a, -a], [-a, -omega**2 + a]])
    T = np.array([[0.0, 0], [1, 0], [1, 0], [0, 1]])
    return T @ np.linalg.inv(Zr) @ T.T


def test_the_reference_roots_are_two_damped_pairs():
    roots = exact_roots()
    assert roots.size == 2 and np.all(roots.real < 0)
    # undamped limit: the golden-ratio pair of a unit mass on a unit spring with a unit absorber
    np.testing.assert_allclose(np.abs(roots), [0.6191360607, 1.6151538627], rtol=1e-9)


@pytest.mark.parametrize("c", SCALES)
@pytest.mark.parametrize("method", FORMULATIONS)
def test_dense_modes_do_not_depend_on_the_scale_of_a_row(c, method):
    M, C, K, A = chain_model(c)
    modes = coupled_modes(M, C, K, A, method)
    np.testing.assert_allclose(modes.eigenvalues, exact_roots(), rtol=1e-10)
    assert modes.residual.max() < 1e-12
    assert abs(modes.shapes[0]).max() < 1e-12  # q1 = 0 in every mode


@pytest.mark.parametrize("c", SCALES)
@pytest.mark.parametrize("method", FORMULATIONS)
def test_receptance_does_not_depend_on_the_scale_of_a_row(c, method):
    M, C, K, A = chain_model(c)
    omegas = [0.3, 0.9, 2.5]
    H = receptance(sp.csr_array(K), sp.csr_array(M), sp.csr_array(C), sp.csr_array(A),
                   omegas, method=method)
    for k, w in enumerate(omegas):
        ref = exact_receptance(w)
        assert np.abs(H[k] - ref).max() < 1e-12 * np.abs(ref).max(), (method, w)


@pytest.mark.parametrize("method", FORMULATIONS)
def test_force_tied_constraint_scaled_with_its_right_hand_side(method):
    """``c q1 = c F2`` (``A`` and ``R`` scaled together) is ``q1 = F2``: the receptance of
    ``c = 1e-8`` and ``1e-300`` equals that of ``c = 1``, and satisfies ``q1 = F2``."""
    omegas = [0.4, 1.7]
    out = {}
    for c in SCALES:
        M, C, K, A = chain_model(c)
        R = np.zeros_like(A)
        R[1, 1] = c
        out[c] = receptance(K, M, C, A, omegas, R=R, method=method)
    ref = out[1.0]
    np.testing.assert_allclose(ref[:, 0], np.tile([0.0, 1, 0, 0], (2, 1)), atol=1e-12)
    for c in SCALES[1:]:
        assert np.abs(out[c] - ref).max() < 1e-12 * np.abs(ref).max()


def test_a_row_that_is_exactly_zero_is_refused_not_dropped():
    M, C, K, A = chain_model(1.0)
    A[1] = 0.0  # e.g. the terms of a user constraint merged to nothing
    with pytest.raises(ZeroRowError, match="row 1"):
        coupled_modes(M, C, K, A, "null-space")
    with pytest.raises(ZeroRowError, match="'fix'|fix"):
        receptance(K, M, C, A, 1.0, method="kkt", labels=["P@q2 = d", "fix"])


def split_chain(c: float, n: int = 60, left: int = 30):
    """A uniform fixed-free chain of ``n`` unit masses and springs in two pieces (``left``
    masses; a massless boundary b and the other ``n - left``), joined by ``q_left = b``, under
    ``c q1 = 0``.  With ``q1 = 0`` it is a fixed-free chain of ``n - 1`` masses:
    ``omega_j = 2 sin((2j - 1) pi / (2 (2 (n - 1) + 1)))``."""
    N = n + 1  # q1 .. q_left, b, q_left+1 .. q_n
    main, off = np.full(N, 2.0), np.full(N - 1, -1.0)
    main[left - 1] = 1.0  # the left piece ends at q_left
    off[left - 1] = 0.0
    main[left] = 1.0  # the boundary b: one spring to q_left+1
    main[-1] = 1.0  # free end
    K = sp.diags_array([off, main, off], offsets=[-1, 0, 1]).tocsr()
    m = np.ones(N)
    m[left] = 0.0
    M = sp.diags_array(m).tocsr()
    A = sp.csr_array(([1.0, -1.0, c], ([0, 0, 1], [left - 1, left, 0])), shape=(2, N))
    j = np.arange(1, 7)
    exact = 2 * np.sin((2 * j - 1) * np.pi / (2 * (2 * (n - 1) + 1)))
    return M, K, A, exact


@pytest.mark.parametrize("c", SCALES)
@pytest.mark.parametrize("method", FORMULATIONS)
def test_sparse_modes_do_not_depend_on_the_scale_of_a_row(c, method):
    M, K, A, exact = split_chain(c)
    modes = sparse_coupled_modes(M, K, A, 6, method=method)
    np.testing.assert_allclose(modes.omega, exact, rtol=1e-10)
    assert modes.residual.max() < 1e-12
    assert modes.solver == "sparse"


CASE = """\
name: chain
units: "N, m, kg, s"
substructures:
  - name: P
    type: matrices
    M: [[1, 0], [0, 1]]
    K: [[2, -1], [-1, 1]]
    labels: [q1, q2]
  - {{name: d, type: free-free, mass: 1, stiffness: 1, damping: {damping}}}
connections:
  - [P@q2, d]
constraints:
  - name: fix
    terms: {{P@q1: {c}}}
analysis:
  modes:
    count: 2
    method: generalized-inverse
    check: [null-space, kkt]
output: {{pictures: false}}
"""


def run_chain(capsys, tmp_path, c: str) -> dict:
    path = tmp_path / f"chain_{c}.yaml"
    path.write_text(CASE.format(c=c, damping=C_ABS))
    code, out, err = run(capsys, "run", path, "--out", tmp_path / c, "--json", "--quiet")
    assert code == 0, err
    return json.loads(out)["modes"]


def test_cli_modes_equal_those_of_the_unit_coefficient(capsys, tmp_path):
    """``substruct run``: the constraint ``1e-8 q1 = 0`` (and ``1e-25``, ``1e-300`` and
    ``1e300``: constraint coefficients take any finite magnitude) gives the modes of
    ``q1 = 0``, and every check agrees; before, ``1e-8`` gave 1.26 and 1.78 rad/s with the
    checks off by 0.51 and ``1e-25`` lost the constraint."""
    ref = run_chain(capsys, tmp_path, "1")
    lam = exact_roots()
    np.testing.assert_allclose(ref["omega"], np.abs(lam), rtol=1e-10)
    np.testing.assert_allclose(ref["damping_ratio"], -lam.real / np.abs(lam), rtol=1e-8)
    for c in ("1e-8", "1e-25", "1e-300", "1e300"):
        got = run_chain(capsys, tmp_path, c)
        np.testing.assert_allclose(got["omega"], ref["omega"], rtol=1e-12)
        np.testing.assert_allclose(got["damping_ratio"], ref["damping_ratio"], rtol=1e-10)
        assert max(got["agreement"].values()) < 1e-12
