"""The modal receptance on the AMLS basis (``analysis.frf.modal.solver: amls``) against the
direct receptance (the kkt formulation) of the same constrained assembly.

The model: two solid boxes tied at x = 2 (48 constraint rows), clamped at x = 0, 624
coordinates; two point forces, three outputs; 40 frequencies up to 4000 rad/s, the modes kept
up to 3 times that (the modal sum's own cut-off) with the second-order residual flexibility.
What is asserted:

* every mode kept in every block: the receptance of the sparse (Lanczos) modal sum of as many
  roots, to round-off; against the direct solve, the modal sum's own truncation error;
* truncated (AMLS cut-off 2, 3, 5): the error falls monotonically, at the measured rate
  (``r^-4.5`` undamped, ``r^-5.2`` damped; at least ``r^-3`` asserted);
* Rayleigh damping ``C = alpha M + beta K`` projected on the AMLS modes: each root is the
  closed form of its undamped frequency, ``2 zeta omega = alpha + beta omega^2``, and the
  repeated roots (the two bending modes of the square section) get bi-orthogonal vectors;
* from a case file, through ``substruct.run``: the sweep names its AMLS basis and passes its
  direct check.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from substruct.analysis.api import receptance_sweep
from substruct.analysis.formulations.coupling import receptance
from substruct.analysis.frf.modal import ModalOptions, modal_basis
from substruct.analysis.modes.amls import AmlsOptions
from substruct.analysis.system import SweepOptions
from substruct.case.loader import parse_case
from substruct.linalg.system import ConstrainedSystem
from substruct.run.runner import run_case
from two_boxes import tied_boxes, two_boxes_case

E, NU, RHO = 2.1e11, 0.3, 7850.0
ALPHA, BETA = 2.0, 2e-6
W = np.linspace(200.0, 4000.0, 40) + 13.7
ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def tied():
    K, M, A, inputs, outputs = tied_boxes(E, NU, RHO)
    return K, M, A, inputs, outputs


def errors(tied, damped: bool):
    """Relative errors ``max |H - H_direct| / max |H_direct|`` of the AMLS modal sum at each
    AMLS cut-off, and the relative difference between the AMLS sum with every mode kept and
    the sparse (Lanczos) sum of as many roots."""
    K, M, A, inputs, outputs = tied
    n = K.shape[0]
    C = sp.csr_array(ALPHA * M + BETA * K) if damped else sp.csr_array((n, n))
    system = ConstrainedSystem.of(M, C, K, A)
    direct = receptance(K, M, C, A, W, None, method="kkt", inputs=inputs, outputs=outputs)
    scale = np.abs(direct).max()

    def sweep(modal):
        opts = SweepOptions(method="modal", modal=modal, tolerance=10.0)
        return receptance_sweep(system, W, sp.csc_array(inputs), sp.csr_array(outputs),
                                options=opts).H

    H = {r: sweep(ModalOptions(cutoff=3.0, solver="amls",
                               amls=AmlsOptions(cutoff=r, leaf_size=80)))
         for r in (2.0, 3.0, 5.0, 1e6)}
    count = modal_basis(M, None, K, A, float(W.max()), cutoff=3.0, solver="amls",
                        amls=AmlsOptions(cutoff=1e6, leaf_size=80)).count
    sparse = sweep(ModalOptions(count=count, solver="sparse")) if not damped else None
    same = None if sparse is None else float(np.abs(H[1e6] - sparse).max() / scale)
    return same, {r: float(np.abs(h - direct).max() / scale) for r, h in H.items()}


@pytest.mark.parametrize("damped", [False, True], ids=["undamped", "rayleigh"])
def test_modal_receptance_on_the_amls_basis_converges_with_the_cutoff(tied, damped):
    same, amls = errors(tied, damped)
    truncated = [amls[r] for r in (2.0, 3.0, 5.0)]
    assert all(a > b for a, b in zip(truncated, truncated[1:])), amls
    rate = np.log(truncated[0] / truncated[-1]) / np.log(5.0 / 2.0)
    assert rate > 3.0, (rate, amls)     # measured 4.5 undamped, 5.2 with damping
    # every block's modes kept: only the modal sum's own truncation error is left (measured
    # 3.5e-6 undamped, 3.9e-6 damped), far below the truncated AMLS bases
    assert amls[1e6] < 1e-2 * truncated[-1]
    if same is not None:
        # the sum of the Lanczos modes of as many roots: the same modes to round-off
        assert same < 1e-9, same


def test_rayleigh_roots_on_the_amls_basis_are_the_closed_form(tied):
    K, M, A, _, _ = tied
    C = sp.csr_array(ALPHA * M + BETA * K)
    opts = AmlsOptions(cutoff=1e6, leaf_size=80)
    damped = modal_basis(M, C, K, A, 4000.0, cutoff=3.0, solver="amls", amls=opts)
    undamped = modal_basis(M, None, K, A, 4000.0, cutoff=3.0, solver="amls", amls=opts)
    w = undamped.eigenvalues.imag
    assert damped.count == undamped.count == w.size >= 20
    zeta = (ALPHA + BETA * w ** 2) / (2 * w)
    closed = -zeta * w + 1j * w * np.sqrt(1 - zeta ** 2)
    assert np.allclose(damped.eigenvalues, closed, rtol=1e-10, atol=0)
    # a_r = u^T (2 lambda M + C) u = (2 lambda + alpha + beta w^2) u^T M u
    #     = 2 i w sqrt(1 - zeta^2) u^T M u  (a shape may be complex in a repeated root)
    U = damped.shapes
    mass = np.einsum("ir,ir->r", U, M @ U)
    assert np.allclose(damped.norms / mass, 2j * w * np.sqrt(1 - zeta ** 2), rtol=1e-8)
    # the repeated roots (two bending modes of the square section) bi-orthogonal:
    # u_r^T (2 lambda M + C) u_s = 0 for r != s
    pairs = np.flatnonzero(np.isclose(w[1:], w[:-1], rtol=1e-8))
    assert pairs.size >= 3
    for k in pairs:
        lam = damped.eigenvalues[k]
        B = U[:, k:k + 2].T @ (2 * lam * (M @ U[:, k:k + 2]) + C @ U[:, k:k + 2])
        assert abs(B[0, 1]) < 1e-10 * np.abs(np.diag(B)).max()


CASE = two_boxes_case("two_boxes", """\
  frf:
    omega: {start: 100, stop: 3000, num: 30}
    inputs: ["right@4,0.5,0.5:z"]
    outputs: ["right@4,0.5,0.5:z", "left@1,0.5,0.5:y"]
    method: modal
    tolerance: 1e-2
    modal: {solver: amls, cutoff: 3, amls: {cutoff: 5, leaf_size: 100}}
""")


def test_modal_amls_from_a_case_file():
    r = run_case(parse_case(CASE, "two.yaml", ROOT)).frf
    assert r is not None and "(AMLS basis)" in r.method
    (name, value), = r.agreement.items()
    assert name.startswith("kkt") and value < 1e-2


def test_a_model_smaller_than_one_leaf_is_one_block_without_a_boundary(tied):
    """The default leaf size (1000) exceeds this 624-coordinate model: the tree is one block
    with no separator, whose boundary solve has no column; the basis is then the exact modes
    below the cut-off (the undamped frequencies of the sparse eigensolver's, to round-off)."""
    K, M, A, _, _ = tied
    one = modal_basis(M, None, K, A, 4000.0, cutoff=3.0, solver="amls", amls=AmlsOptions())
    ref = modal_basis(M, None, K, A, 4000.0, cutoff=3.0, solver="amls",
                      amls=AmlsOptions(cutoff=1e6, leaf_size=80))
    assert one.count == ref.count >= 20
    w1, w2 = one.eigenvalues.imag, ref.eigenvalues.imag
    assert np.abs(w1 - w2).max() <= 1e-9 * w2.max()
