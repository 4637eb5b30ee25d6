"""The paper's section 5: receptances of the three-DOF system, eqs (35)-(43)."""

import numpy as np
import pytest

from substruct.analysis.formulations.coupling import FORMULATIONS, paper_G_D, receptance, receptance_unconstrained

from tolerances import solve_bound

# eq (37), as printed (4 decimals)
H37 = np.array([
    [0.0247 - 0.0286j, -0.0032 + 0.0037j, -0.0159 + 0.0183j],
    [-0.0032 + 0.0037j, -0.0124 - 0.0005j, -0.0621 - 0.0024j],
    [-0.0159 + 0.0183j, -0.0621 - 0.0024j, -0.0603 - 0.0118j],
])
# eq (40), as printed: "C" (our G), D and H^
G40 = np.array([[-6.0 - 12.0j, -4.0, 8.0], [-8.0j, -8.0, 12.0], [20.0 + 16.0j, -8, 12.0]])
D40 = np.array([[-0.6, -0.2, 0.2], [-0.4, -0.8, -0.2], [0.8, -0.4, -0.6]])
H40 = np.array([
    [0.0246 - 0.0295j, 0.0082 - 0.0098j, -0.0082 + 0.0098j],
    [0.0082 - 0.0098j, 0.3361 - 0.0033j, 0.1639 + 0.0033j],
    [-0.0082 + 0.0098j, 0.1639 + 0.0033j, 0.0861 - 0.0033j],
])
# eq (43), as printed: this H^ does not satisfy its own constraint (41)
H43 = np.array([
    [0.0598 - 0.0751j, 0.0391 - 0.0491j, 0.0273 - 0.0343j],
    [0.3121 - 0.0114j, 0.3544 - 0.0074j, 0.3072 - 0.0052j],
    [0.3134 + 0.0250j, 0.3203 + 0.0164j, 0.3242 + 0.0114j],
])
A38 = np.array([[1.0, -1.0, 2.0]])          # q1 + 2 q3 = q2, eq (39)
A41 = np.array([[1.0, 0.0, 2.0]])           # q1 + 2 q3 = [1 1 3] F, eqs (41)-(42)
R41 = np.array([[1.0, 1.0, 3.0]])


def printed(x, digits=4):
    """Round real and imaginary parts to the paper's printed digits."""
    return np.round(x.real, digits) + 1j * np.round(x.imag, digits)


def test_unconstrained_receptance_eq37(three_dof):
    M, C, K, w = three_dof
    H = receptance_unconstrained(K, M, C, w)
    np.testing.assert_array_equal(printed(H), H37)


def test_paper_G_D_H_eq40(three_dof):
    M, C, K, w = three_dof
    G, D = paper_G_D(K, M, C, A38, w)
    np.testing.assert_allclose(G, G40, atol=1e-12)
    np.testing.assert_allclose(D, D40, atol=1e-12)
    np.testing.assert_array_equal(printed(np.linalg.solve(G, D)), H40)


@pytest.mark.parametrize("method", FORMULATIONS)
def test_every_formulation_gives_eq40(three_dof, method):
    M, C, K, w = three_dof
    H = receptance(K, M, C, A38, w, method=method)
    np.testing.assert_array_equal(printed(H), H40)
    # A H = 0 to the forward error of the solve: c n eps cond(Z) |A| |H| (Z the impedance)
    Z = K - w ** 2 * M + 1j * w * C
    np.testing.assert_allclose(A38 @ H, 0.0, atol=abs(A38).sum() * solve_bound(Z, H))


def test_homogeneous_receptance_is_reciprocal(three_dof):
    M, C, K, w = three_dof
    H = receptance(K, M, C, A38, w)
    # symmetric to the forward error of the solve (the sums' order is the kernel's)
    Z = K - w ** 2 * M + 1j * w * C
    np.testing.assert_allclose(H, H.T, atol=solve_bound(Z, H))


@pytest.mark.parametrize("method", FORMULATIONS)
def test_nonhomogeneous_receptance_satisfies_its_constraint(three_dof, method):
    M, C, K, w = three_dof
    H = receptance(K, M, C, A41, w, R=R41, method=method)
    # A H = R: for every force F the response obeys q1 + 2 q3 = [1 1 3] F, eq (41)
    np.testing.assert_allclose(A41 @ H, R41, atol=1e-12)
    H_kkt = receptance(K, M, C, A41, w, R=R41, method="kkt")
    np.testing.assert_allclose(H, H_kkt, rtol=0, atol=1e-10 * np.abs(H_kkt).max())


def test_printed_eq43_violates_constraint41(three_dof):
    """Erratum: the printed H^ of eq (43) is not a solution of its own constraint (41)."""
    M, C, K, w = three_dof
    lhs = A41 @ H43                      # q1 + 2 q3 for unit forces at each coordinate
    assert abs(lhs[0, 0] - (0.6866 - 0.0251j)) < 2e-4  # not R41[0,0] = 1
    assert np.abs(lhs - R41).max() > 0.3
    ours = receptance(K, M, C, A41, w, R=R41)
    assert np.abs(A41 @ ours - R41).max() < 1e-12
    assert np.abs(ours - H43).max() > 0.1


def test_nonhomogeneous_paper_G_D_solve_the_same_system(three_dof):
    """eq (15) with R read at displacement level is what receptance() computes."""
    M, C, K, w = three_dof
    G, D = paper_G_D(K, M, C, A41, w, R41)
    np.testing.assert_allclose(np.linalg.solve(G, D), receptance(K, M, C, A41, w, R=R41),
                               atol=1e-14)
