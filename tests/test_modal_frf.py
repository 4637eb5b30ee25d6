"""Modal receptances (modes up to a cut-off plus a residual flexibility) against the direct
solve: the tapered rod, its finite-element version, the box beam and random damped assemblies."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from substruct.analysis.api import receptance_sweep
from substruct.analysis.errors import CheckError
from substruct.analysis.frf.modal import MODAL_ABOVE, ModalOptions, frf_method
from substruct.case.loader import load_case
from substruct.run.runner import build_model

CASES = Path(__file__).resolve().parents[1] / "cases"


def _error(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.abs(a - b).max() / np.abs(b).max())


def _case_frf(name: str, frf_from: str | None = None):
    case = load_case(CASES / name)
    model = build_model(case)
    spec = (case.analysis.frf if frf_from is None else load_case(CASES / frf_from).analysis.frf)
    asm = model.assembly
    points = [p for p in spec.outputs if p in model.points]
    E = sp.csc_array(asm.rows([model.points[p] for p in spec.inputs]).T)
    O = asm.rows([model.points[p] for p in points])
    return asm, spec.omegas(), E, O


def _both(asm, w, E, O, **options):
    direct = receptance_sweep(asm.K, asm.M, asm.C, asm.A, w, E, O, method="kkt")
    modal = receptance_sweep(asm.K, asm.M, asm.C, asm.A, w, E, O, method="modal",
                             modal=ModalOptions(**options), tolerance=1e9)
    return modal, direct


def test_tapered_rod_modal_equals_direct():
    asm, w, E, O = _case_frf("tapered_rod.yaml")
    modal, direct = _both(asm, w, E, O)
    assert _error(modal.H, direct.H) < 1e-6
    assert modal.method.startswith("modal: 5 root(s)")  # all physical modes lie in the band
    assert max(modal.agreement.values()) < 1e-9


def test_tapered_rod_fe_residual_terms():
    """The finite-element rod (134 coordinates), 40 modes: the residual is what makes 1e-6."""
    asm, w, E, O = _case_frf("tapered_rod_fe.yaml", frf_from="tapered_rod.yaml")
    errors = {}
    for residual in ("none", "static", "second-order"):
        modal, direct = _both(asm, w, E, O, count=40, residual=residual)
        errors[residual] = _error(modal.H, direct.H)
    assert errors["second-order"] < 1e-6
    assert errors["static"] < 1e-5
    assert errors["none"] > 1e-4
    assert errors["none"] > 50 * errors["static"] > 50 * errors["second-order"]


def test_box_beam_modal_equals_direct():
    """Damped absorbers (not proportional): the complex modes of the first-order form."""
    asm, w, E, O = _case_frf("box_beam_tmd.yaml")
    modal, direct = _both(asm, w, E, O, count=30)
    assert _error(modal.H, direct.H) < 1e-6
    none, _ = _both(asm, w, E, O, count=30, residual="none")
    assert _error(none.H, direct.H) > 1e-5


def _random_assembly(seed: int, damping: str, ground: bool = True):
    """Two spring-mass chains of 20 masses with random springs, masses and dashpots, tied by
    three random constraint rows."""
    rng = np.random.default_rng(seed)
    n = 40
    K = sp.lil_array((n, n))
    C = sp.lil_array((n, n))
    for chain in (0, 20):
        for i in range(chain, chain + 20):
            k, c = rng.uniform(1e3, 1e4), rng.uniform(0.5, 5)
            if i == chain:
                if ground:
                    K[i, i] += k
                    C[i, i] += c
                continue
            for mat, v in ((K, k), (C, c)):
                mat[i, i] += v
                mat[i - 1, i - 1] += v
                mat[i, i - 1] -= v
                mat[i - 1, i] -= v
    M = sp.diags_array(rng.uniform(0.5, 2.0, n))
    K = sp.csr_array(K)
    if damping == "proportional":
        C = 1e-3 * K + 0.5 * M
    elif damping == "none":
        C = None
    A = rng.standard_normal((3, n)) * (rng.random((3, n)) < 0.2)
    if not ground:  # rows that a rigid translation of both chains satisfies
        A -= A.mean(axis=1, keepdims=True)
    A = sp.csr_array(A)
    E = sp.csc_array(sp.eye_array(n).tocsc()[:, [5, 33]])
    O = sp.csr_array(sp.eye_array(n).tocsr()[[0, 5, 19, 33, 39]])
    return M, C, K, A, E, O


@pytest.mark.parametrize("damping", ["none", "proportional", "general"])
def test_random_assembly(damping):
    M, C, K, A, E, O = _random_assembly(7, damping)
    w = np.linspace(0.5, 20.0, 300)  # 30 of 37 modes, up to about 140 rad/s
    direct = receptance_sweep(K, M, C, A, w, E, O, method="kkt")
    modal = receptance_sweep(K, M, C, A, w, E, O, method="modal", tolerance=1e9,
                             modal=ModalOptions(count=30, solver="dense"))
    static = receptance_sweep(K, M, C, A, w, E, O, method="modal", tolerance=1e9,
                              modal=ModalOptions(count=30, residual="static", solver="dense"))
    assert _error(modal.H, direct.H) < 1e-6
    assert _error(static.H, direct.H) > 10 * _error(modal.H, direct.H)
    assert modal.constraint_residual < 1e-12


def test_rigid_body_modes_by_inertia_relief():
    """Free chains (no ground): rigid-body modes under the constraints, undamped."""
    M, _, K, A, E, O = _random_assembly(3, "none", ground=False)
    w = np.linspace(2.0, 20.0, 200)
    direct = receptance_sweep(K, M, None, A, w, E, O, method="kkt")
    modal = receptance_sweep(K, M, None, A, w, E, O, method="modal", tolerance=1e-5,
                             modal=ModalOptions(count=30, solver="dense"))
    assert "1 rigid" in modal.method
    assert _error(modal.H, direct.H) < 1e-6
    with pytest.raises(ValueError, match="infinite at omega = 0"):
        receptance_sweep(K, M, None, A, [0.0, 1.0], E, O, method="modal")
    M, C, K, A, E, O = _random_assembly(3, "general", ground=False)
    with pytest.raises(ValueError, match="rigid-body modes is not supported"):
        receptance_sweep(K, M, C, A, w, E, O, method="modal")


def test_truncation_too_short_is_a_check_error():
    asm, w, E, O = _case_frf("tapered_rod.yaml")
    with pytest.raises(CheckError, match="kkt \\(3 frequencies\\) disagrees"):
        receptance_sweep(asm.K, asm.M, asm.C, asm.A, w, E, O, method="modal",
                         modal=ModalOptions(count=2))


def test_force_tied_constraint_refused_and_auto():
    M, C, K, A, E, O = _random_assembly(1, "none")
    R0 = A.toarray() * 0.0
    R0[0, 5] = 1.0
    R = sp.csr_array(R0)
    with pytest.raises(ValueError, match="A q = 0"):
        receptance_sweep(K, M, C, A, [1.0], E, O, R=R, method="modal")
    assert frf_method("auto", MODAL_ABOVE + 1, None) == "modal"
    assert frf_method("auto", MODAL_ABOVE + 1, R) == "generalized-inverse"
    assert frf_method("auto", MODAL_ABOVE, None) == "generalized-inverse"
