"""The modal receptance of models with repeated (degenerate) damped roots against the direct
(kkt) receptance: each cluster of equal roots is summed through its projected pencil
(:mod:`substruct.analysis.frf.clusters`), whatever basis of the eigenspace the eigensolver gave.

The model: two identical grounded chains of 20 random masses, springs and dashpots, each with
one constraint row of its own, uncoupled: every root is double.  Before the clusters the sparse
(Arnoldi) modal sum of 30 roots was wrong by 1.9 (Rayleigh) and 0.17 (discrete dashpots),
relative, against the direct solve; the same model with the second chain's springs 1e-9 stiffer
gave 2.7e-5 and 9.9e-5.  Asserted: the truncation bound of a model without repeated roots
(1e-6, :mod:`tests.test_modal_frf`), round-off with every root kept, continuity across the
split, a case file through ``substruct.run`` (the square section's double bending roots), and
the modal transient (no such assumption: it keeps the full ``Phi^T C Phi``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from substruct.analysis.api import receptance_sweep
from substruct.analysis.frf.modal import ModalOptions, modal_basis
from substruct.analysis.transient import (
    LoadHistory,
    TransientOptions,
    TransientOutputs,
    transient,
)
from substruct.case.loader import parse_case
from substruct.run.runner import run_case
from two_boxes import two_boxes_case

ROOT = Path(__file__).resolve().parent.parent
W = np.linspace(0.5, 20.0, 300)  # 30 of 38 roots reach about 136 rad/s


def _chain(k: np.ndarray, c: np.ndarray) -> tuple[sp.csr_array, sp.csr_array]:
    m = k.size
    K, C = sp.lil_array((m, m)), sp.lil_array((m, m))
    K[0, 0], C[0, 0] = k[0], c[0]
    for i in range(1, m):
        for mat, v in ((K, k[i]), (C, c[i])):
            mat[i, i] += v
            mat[i - 1, i - 1] += v
            mat[i, i - 1] -= v
            mat[i - 1, i] -= v
    return sp.csr_array(K), sp.csr_array(C)


def twins(damping: str, split: float = 0.0):
    """Two identical chains (the second's springs ``1 + split`` times stiffer), uncoupled."""
    rng = np.random.default_rng(7)
    m = 20
    k, c, mass = rng.uniform(1e3, 1e4, m), rng.uniform(0.5, 5, m), rng.uniform(0.5, 2, m)
    K1, C1 = _chain(k, c)
    K2, C2 = _chain(k * (1 + split), c)
    K = sp.csr_array(sp.block_diag([K1, K2], format="csr"))
    M = sp.csr_array(sp.diags_array(np.concatenate([mass, mass])))
    C = sp.csr_array(0.5 * M + 1e-3 * K) if damping == "rayleigh" else \
        sp.csr_array(sp.block_diag([C1, C2], format="csr"))
    a = np.zeros(m)
    a[[3, 7]] = [1.0, -0.5]
    A = sp.csr_array(np.vstack([np.concatenate([a, 0 * a]), np.concatenate([0 * a, a])]))
    n = 2 * m
    E = sp.csc_array(sp.eye_array(n).tocsc()[:, [5, 25, 33]])
    O = sp.csr_array(sp.eye_array(n).tocsr()[[0, 5, 19, 25, 33, 39]])
    return M, C, K, A, E, O


def _error(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.abs(a - b).max() / np.abs(b).max())


def _modal(model, count: int, solver: str) -> np.ndarray:
    M, C, K, A, E, O = model
    return receptance_sweep(K, M, C, A, W, E, O, method="modal", tolerance=1e9,
                            modal=ModalOptions(count=count, solver=solver)).H


@pytest.mark.parametrize("damping", ["rayleigh", "dashpots"])
@pytest.mark.parametrize("solver", ["sparse", "dense"])
def test_repeated_roots_modal_equals_direct(damping, solver):
    model = twins(damping)
    M, C, K, A, E, O = model
    basis = modal_basis(M, C, K, A, float(W.max()), count=30, solver=solver)
    assert len(basis.clusters) == 15 and all(c.index.size == 2 for c in basis.clusters)
    direct = receptance_sweep(K, M, C, A, W, E, O, method="kkt").H
    assert _error(_modal(model, 30, solver), direct) < 1e-6   # measured 4e-7, 5e-9
    assert _error(_modal(model, 38, solver), direct) < 1e-10  # every root: 2e-13, 6e-12


@pytest.mark.parametrize("damping", ["rayleigh", "dashpots"])
def test_nearly_repeated_roots_are_continuous(damping):
    """Split by 1e-9: the receptance moves by the split, not by the vectors' mixing."""
    exact = _modal(twins(damping), 30, "sparse")
    split = _modal(twins(damping, 1e-9), 30, "sparse")
    assert _error(split, exact) < 1e-6
    M, C, K, A, E, O = twins(damping, 1e-9)
    direct = receptance_sweep(K, M, C, A, W, E, O, method="kkt").H
    assert _error(split, direct) < 1e-6


CASE = two_boxes_case("two_boxes_damped", """\
  frf:
    omega: {start: 100, stop: 3000, num: 30}
    inputs: ["right@4,0.5,0.5:z", "right@4,0.5,0.5:y"]
    outputs: ["right@4,0.5,0.5:z", "left@1,0.5,0.5:y"]
    method: modal
    tolerance: 1e-5
    modal: {solver: sparse, cutoff: 3}
""", rayleigh="[2.0, 2.0e-6]")


def test_modal_case_with_repeated_roots_passes_its_check():
    """The square section's bending roots are double: the sweep passes its direct check."""
    r = run_case(parse_case(CASE, "two.yaml", ROOT)).frf
    assert r is not None
    (name, value), = r.agreement.items()
    assert name.startswith("kkt") and value < 1e-5, r.agreement


@pytest.mark.parametrize("damping", ["rayleigh", "dashpots"])
@pytest.mark.parametrize("solver", ["sparse", "dense"])
def test_modal_transient_with_repeated_roots(damping, solver):
    """The modal transient keeps the undamped modes re-orthonormalized by a Rayleigh-Ritz and
    the full ``Phi^T C Phi``: it has no bi-orthogonality to lose at a repeated root.  Every
    mode kept: the direct integration to round-off."""
    M, C, K, A, E, O = twins(damping)
    n_steps, h = 400, 2e-3
    t = h * np.arange(n_steps + 1)
    pulse = np.where(t < 0.05, np.sin(np.pi * t / 0.05), 0.0)[:, None] * np.array([1.0, -2.0,
                                                                               0.5])
    r = transient(M, C, K, A, None, LoadHistory(E, pulse, h, n_steps), TransientOutputs(O),
                  options=TransientOptions(method="null-space", checks=["modal"], tolerance=1e-8,
                                           modal_solver=solver))
    assert r.agreement["modal"] < 1e-10, r.agreement  # measured 1.6e-13
    assert np.abs(r.displacement).max() > 0
