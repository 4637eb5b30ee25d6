"""The modal transient on the AMLS basis (``analysis.transient.modal.solver: amls``) against the
direct integration (the generalized-inverse form, Newmark's average acceleration, same step).

The model: two solid boxes tied at x = 2 (48 constraint rows), clamped at x = 0, 624
coordinates (576 free); two point loads of one smooth pulse ``(1 - cos 2 pi t / T) / 2``,
``T = 2 ms``, three outputs, 400 steps of 50 us (Nyquist ``pi / dt`` = 62,832 rad/s).  The
modal equations are integrated by the same scheme and step, so the direct integration is the
exact reference of the modal form with every mode kept (the integrator is invariant under a
change of coordinates) and what separates them otherwise is the truncation alone.
What is asserted:

* every mode kept (every block's modes in AMLS, every coupled mode in the sum): the direct
  integration to round-off, undamped and with Rayleigh damping projected on the modes;
* the lowest 23 modes by AMLS with every block's modes kept: the modal transient of the 23
  Lanczos (shift-invert) modes to round-off;
* the modes below a growing fraction of the Nyquist frequency (exact blocks): the error falls
  at the measured rate ``c^-1.9`` with the static correction (``c`` 0.1 to 0.8; at least
  ``c^-1.5`` asserted), and is below the bare modal sum's at every cut-off (by 5x to 90x);
* a truncated AMLS basis (block cut-off 1.5 to 5 x the wanted frequency) converges to the
  exact modes' transient at the measured rate ``r^-5.5`` (at least ``r^-4`` asserted);
* from a case file, through ``substruct.run``: the run names its AMLS basis and its check
  against the direct form holds.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from substruct.analysis.modes.amls import AmlsOptions
from substruct.analysis.transient import (
    LoadHistory,
    TransientOptions,
    TransientOutputs,
    transient,
)
from substruct.case.loader import parse_case
from substruct.run.runner import run_case
from two_boxes import AMLS_TRANSIENT, tied_boxes, two_boxes_case

E, NU, RHO = 2.1e11, 0.3, 7850.0
ALPHA, BETA = 20.0, 2e-6
DT, STEPS, PULSE = 5e-5, 400, 2e-3
EXACT = AmlsOptions(cutoff=1e6, leaf_size=80)   # every block's modes kept
ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def tied():
    K, M, A, B, O = tied_boxes(E, NU, RHO)
    t = DT * np.arange(STEPS + 1)
    pulse = np.where(t < PULSE, (1 - np.cos(2 * np.pi * t / PULSE)) / 2, 0.0)
    f = pulse[:, None] * np.array([1.0, -0.5])[None, :]
    return K, M, A, LoadHistory(B, f, DT, STEPS), TransientOutputs(O)


def run(tied, C=None, **options):
    K, M, A, load, outputs = tied
    method = options.pop("method", "modal")
    return transient(M, C, K, A, None, load, outputs,
                     options=TransientOptions(method=method, tolerance=10.0, **options))


@pytest.fixture(scope="module")
def direct(tied):
    return run(tied, method="generalized-inverse")


def error(r, ref) -> float:
    """``max |q - q_ref| / max |q_ref|`` over the outputs and instants."""
    return float(np.abs(r.displacement - ref.displacement).max()
                 / np.abs(ref.displacement).max())


@pytest.mark.parametrize("damped", [False, True], ids=["undamped", "rayleigh"])
def test_every_mode_kept_is_the_direct_integration(tied, direct, damped):
    K, M = tied[0], tied[1]
    C = sp.csr_array(ALPHA * M + BETA * K) if damped else None
    ref = run(tied, C, method="generalized-inverse") if damped else direct
    r = run(tied, C, modal_solver="amls", modal_cutoff=2.0, modal_amls=EXACT)
    assert r.solver.startswith("576 modes by amls")   # every free coordinate's mode
    assert error(r, ref) < 1e-9, error(r, ref)        # measured 3.7e-12 undamped


def test_amls_with_every_block_mode_kept_is_the_lanczos_modal_transient(tied):
    amls = run(tied, modal_solver="amls", modal_cutoff=0.2, modal_amls=EXACT)
    count = int(amls.solver.split()[0])
    assert count == 23
    lanczos = run(tied, modal_solver="sparse", modal_count=count)
    assert error(amls, lanczos) < 1e-8, error(amls, lanczos)


def test_the_static_correction_converges_with_the_cutoff(tied, direct):
    cuts = (0.1, 0.2, 0.4, 0.8)
    static = [error(run(tied, modal_solver="amls", modal_cutoff=c, modal_amls=EXACT), direct)
              for c in cuts]
    bare = [error(run(tied, modal_solver="amls", modal_cutoff=c, modal_amls=EXACT,
                      modal_residual="none"), direct) for c in cuts]
    # measured 4.0e-3, 1.1e-3, 2.9e-4, 8.0e-5 (static), 2.0e-2 .. 7.0e-3 (none)
    assert all(a > b for a, b in zip(static, static[1:])), static
    rate = np.log(static[0] / static[-1]) / np.log(cuts[-1] / cuts[0])
    assert rate > 1.5, (rate, static)                  # measured 1.9
    assert all(s < b / 4 for s, b in zip(static, bare)), (static, bare)


def test_a_truncated_amls_basis_converges_to_the_exact_modes(tied):
    exact = run(tied, modal_solver="amls", modal_cutoff=0.2, modal_amls=EXACT)
    cuts = (1.5, 2.0, 3.0, 5.0)
    errs = [error(run(tied, modal_solver="amls", modal_cutoff=0.2,
                      modal_amls=AmlsOptions(cutoff=r, leaf_size=80)), exact) for r in cuts]
    # measured 5.2e-2, 1.6e-2, 2.9e-3, 6.8e-5
    assert all(a > b for a, b in zip(errs, errs[1:])), errs
    rate = np.log(errs[0] / errs[-1]) / np.log(cuts[-1] / cuts[0])
    assert rate > 4.0, (rate, errs)                    # measured 5.5


CASE = two_boxes_case("two_boxes_transient", AMLS_TRANSIENT)


def test_modal_transient_on_the_amls_basis_from_a_case_file():
    r = run_case(parse_case(CASE, "two.yaml", ROOT)).transient
    assert r is not None and r.method == "modal" and " modes by amls (cut-off 5 x " in r.solver
    (name, value), = r.agreement.items()
    assert name == "generalized-inverse" and value < 1e-2   # measured 2.0e-3
