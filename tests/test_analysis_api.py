"""One analysis entry point (issue 11): the dense, sparse and damped strategies chosen in one
place, the cross-checks returned with every result, and a check that disagrees beyond the
stated tolerance failing the analysis (bug 3).

The models are chains with closed forms: ``n`` equal masses ``m`` joined by equal springs
``k``, the first spring to the ground, the last mass free (fixed-free):

    omega_j = 2 sqrt(k/m) sin((2j - 1) pi / (2 (2n + 1))),

with mass-normalized shapes ``phi_j(i) = sqrt(4 / ((2n + 1) m)) sin((2j - 1) pi i / (2n + 1))``.
The constraint ``q1 = 0`` leaves the fixed-free chain of the other ``n - 1`` masses.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import h5py
import numpy as np
import pytest
import scipy.sparse as sp

import substruct.analysis.api as api
import substruct.analysis.modes.eigen as eigen
from substruct.analysis.api import SPARSE_ABOVE, choose_solver, modes, receptance_sweep
from substruct.analysis.checks import modes_agreement, require_agreement
from substruct.analysis.errors import CheckError
from substruct.analysis.results import DEFAULT_TOLERANCE
from substruct.case.loader import CaseError, load_case
from substruct.io import hdf5
from substruct.run.result import ModelInfo, Result

from cli_helpers import run

K0, M0 = 4.0, 1.0


def chain(n: int, c_end: float = 0.0) -> tuple[sp.csr_array, sp.csr_array, sp.csr_array]:
    """``(M, C, K)`` of the fixed-free chain; a dashpot ``c_end`` from the last mass to ground."""
    main = np.full(n, 2 * K0)
    main[-1] = K0
    K = sp.diags_array([np.full(n - 1, -K0), main, np.full(n - 1, -K0)], offsets=[-1, 0, 1])
    C = sp.csr_array(([c_end], ([n - 1], [n - 1])), shape=(n, n))
    return sp.csr_array(sp.eye_array(n) * M0), C, sp.csr_array(K)


def chain_omega(n: int, count: int) -> np.ndarray:
    j = np.arange(1, count + 1)
    return 2 * np.sqrt(K0 / M0) * np.sin((2 * j - 1) * np.pi / (2 * (2 * n + 1)))


def fix_first(n: int, scale: float = 1.0) -> sp.csr_array:
    """``scale q1 = 0``."""
    return sp.csr_array(([scale], ([0], [0])), shape=(1, n))


# ------------------------------------------------------------------- strategies and checks


def test_dense_modes_with_checks_match_the_closed_form():
    n = 12
    M, C, K = chain(n)
    res = modes(M, None, K, fix_first(n, 3.0), 4, checks=("null-space", "kkt", "null-space"))
    np.testing.assert_allclose(res.omega, chain_omega(n - 1, 4), rtol=1e-12)
    assert res.method == "generalized-inverse" and res.solver == "dense"
    assert list(res.agreement) == ["null-space", "kkt"]
    assert max(res.agreement.values()) < 1e-10
    assert res.tolerance == DEFAULT_TOLERANCE
    assert np.all(res.residual < 1e-12) and len(res.spurious) == 2  # eqs 30/34: 2 rank(A)


def test_auto_is_sparse_above_the_limit_and_matches_the_closed_form():
    n = SPARSE_ABOVE + 50
    M, C, K = chain(n)
    assert choose_solver(M, C, fix_first(n), 6).strategy == "sparse"
    res = modes(M, C, K, fix_first(n), 6, checks=("null-space", "kkt"))
    # the production path: null-space numbers, KKT and generalized-inverse residual checks
    assert res.solver == "sparse" and res.method == "null-space/sparse"
    assert list(res.agreement) == ["kkt-residual", "generalized-inverse-residual"]
    np.testing.assert_allclose(res.omega, chain_omega(n - 1, 6), rtol=1e-9)
    assert max(res.agreement.values()) < 1e-9
    assert res.shapes.shape == (n, 6) and np.all(np.abs(res.shapes[0]) < 1e-12)
    assert res.shapes.dtype == complex and res.eigenvalues.dtype == complex  # as dense


def test_sparse_too_small_for_a_krylov_basis_solves_the_null_space_pencil_densely():
    n = 12  # 11 free coordinates: no Krylov basis for 10 modes
    M, C, K = chain(n)
    res = modes(M, C, K, fix_first(n), 10, method="kkt", solver="sparse")
    assert res.solver == ("sparse (11 coordinates left by the constraints: their pencil "
                          "solved densely)")
    assert res.method == "null-space/sparse"
    np.testing.assert_allclose(res.omega, chain_omega(n - 1, 10), rtol=1e-12)
    assert max(res.agreement.values()) < 1e-10
    # every formulation's own eigensolve asked for: the dense strategy, and it says so
    full = modes(M, C, K, fix_first(n), 10, method="kkt", solver="sparse", full_checks=True)
    assert full.solver == ("dense (sparse asked, but 11 free coordinates are too few for 10 "
                           "modes and a Krylov basis)")
    np.testing.assert_allclose(full.omega, chain_omega(n - 1, 10), rtol=1e-12)
    # with room for the basis the sparse strategy runs, with the same frequencies
    small = modes(M, C, K, fix_first(n), 3, method="kkt", solver="sparse")
    assert small.solver == "sparse"
    np.testing.assert_allclose(small.omega, chain_omega(n - 1, 3), rtol=1e-10)


def test_a_large_model_held_to_a_few_free_coordinates_with_a_massless_one():
    """``solver: auto`` above :data:`SPARSE_ABOVE` coordinates: the chain of its first
    ``n - 1`` coordinates with every one from the fourth on tied to the third (a rigid link),
    and a massless last coordinate on a spring of ``K0`` to the first mass; four free
    coordinates, three finite modes (the massless direction has no finite root and is left
    out), the same as the dense generalized-inverse form's."""
    n = SPARSE_ABOVE + 100
    springs = [(0, 0)] + [(i, i + 1) for i in range(n - 2)] + [(0, n - 1)]
    Kd = np.zeros((n, n))
    for a, b in springs:
        Kd[a, a] += K0
        if a != b:
            Kd[b, b] += K0
            Kd[a, b] -= K0
            Kd[b, a] -= K0
    Md = np.diag(np.r_[np.full(n - 1, M0), 0.0])
    tied = np.arange(3, n - 1)                                # q_i - q_3 = 0
    A = sp.csr_array((np.tile([1.0, -1.0], tied.size),
                      (np.repeat(np.arange(tied.size), 2), np.ravel([[i, 2] for i in tied]))),
                     shape=(tied.size, n))
    res = modes(sp.csr_array(Md), None, sp.csr_array(Kd), A, 3)
    assert res.solver.startswith("sparse (4 coordinates left by the constraints: their pencil "
                                 "solved densely")
    dense = modes(sp.csr_array(Md), None, sp.csr_array(Kd), A, 3, solver="dense")
    np.testing.assert_allclose(res.omega, dense.omega, rtol=1e-9)
    # the 3-mass fixed-free chain whose last mass is the n - 3 tied ones
    m3 = np.diag([M0, M0, (n - 3) * M0])
    k3 = K0 * np.array([[2.0, -1, 0], [-1, 2, -1], [0, -1, 1]])
    np.testing.assert_allclose(res.omega, np.sqrt(np.linalg.eigvalsh(np.linalg.solve(
        np.sqrt(m3), np.linalg.solve(np.sqrt(m3), k3).T))), rtol=1e-10)
    assert np.all(np.abs(A @ res.shapes.real) < 1e-12)


def test_damped_sparse_strategy_matches_first_order_perturbation():
    r"""A light dashpot ``c`` at the free end: ``lambda_j = i omega_j - c phi_j(N)^2 / 2 + O(c^2)``
    (mass-normalized undamped shapes of the constrained chain, ``N = n - 1`` masses)."""
    n, c = SPARSE_ABOVE + 20, 1e-3
    M, C, K = chain(n, c)
    res = modes(M, C, K, fix_first(n), 4, method="null-space", checks=("kkt",))
    assert res.solver == "sparse-damped"
    N = n - 1
    j = np.arange(1, 5)
    phi_end2 = 4 / ((2 * N + 1) * M0) * np.sin((2 * j - 1) * np.pi * N / (2 * N + 1)) ** 2
    np.testing.assert_allclose(res.eigenvalues.imag, chain_omega(N, 4), rtol=1e-6)
    np.testing.assert_allclose(res.eigenvalues.real, -c * phi_end2 / 2, rtol=1e-3)
    # the production path: null-space numbers, KKT and generalized-inverse residuals as checks
    assert res.method == "null-space/sparse"
    assert set(res.agreement) == {"kkt-residual", "generalized-inverse-residual"}
    assert max(res.agreement.values()) < 1e-8
    # the full KKT eigensolve (a first-order pencil of 2n + m) agrees with it
    full = modes(M, C, K, fix_first(n), 4, method="null-space", checks=("kkt",),
                 full_checks=True)
    assert full.agreement["kkt"] < 1e-8
    np.testing.assert_allclose(full.eigenvalues, res.eigenvalues, rtol=1e-10)


def test_unknown_solver_and_method_are_value_errors():
    M, C, K = chain(4)
    with pytest.raises(ValueError, match="unknown solver 'fast'"):
        modes(M, C, K, None, 2, solver="fast")
    with pytest.raises(ValueError, match="unknown method 'qr'"):
        modes(M, C, K, None, 2, checks=("qr",))


# ----------------------------------------------------------- bug 3: checks that disagree


def perturbed(monkeypatch, formulation: str, factor: float) -> None:
    """Make the dense ``formulation`` return its eigenvalues times ``factor``."""
    real = eigen.coupled_modes

    def coupled_modes(M, C, K, A, method, count):
        out = real(M, C, K, A, method, count)
        if method == formulation:
            out = dataclasses.replace(out, eigenvalues=out.eigenvalues * factor)
        return out
    monkeypatch.setattr(eigen, "coupled_modes", coupled_modes)


def test_a_check_that_disagrees_fails_with_one_line(monkeypatch):
    n = 6
    M, C, K = chain(n)
    perturbed(monkeypatch, "null-space", 1.8)
    with pytest.raises(CheckError) as err:
        modes(M, C, K, fix_first(n), 3, checks=("null-space", "kkt"))
    assert str(err.value) == ("modes: null-space disagrees with generalized-inverse by 8.0e-01 "
                              "(tolerance 1e-06)")


def test_a_raised_tolerance_accepts_the_disagreement_and_records_it(monkeypatch):
    n = 6
    M, C, K = chain(n)
    perturbed(monkeypatch, "kkt", 1 + 1e-3)
    with pytest.raises(CheckError, match=r"^modes: kkt disagrees with generalized-inverse by "
                                         r"1\.0e-03 \(tolerance 0\.0005\)$"):
        modes(M, C, K, fix_first(n), 3, checks=("kkt",), tolerance=5e-4)
    res = modes(M, C, K, fix_first(n), 3, checks=("kkt",), tolerance=1e-2)
    assert res.tolerance == 1e-2
    assert res.agreement["kkt"] == pytest.approx(1e-3, rel=1e-9)
    np.testing.assert_allclose(res.omega, chain_omega(n - 1, 3), rtol=1e-12)  # the main one


def test_require_agreement_names_the_worst_check_and_fails_on_nan():
    require_agreement("modes", "kkt", {"null-space": 1e-6}, 1e-6)  # at the bar: passes
    with pytest.raises(CheckError, match=r"^frf: null-space disagrees with kkt by 3\.0e-02 "
                                         r"\(tolerance 1e-06\); also generalized-inverse by "
                                         r"2\.0e-05$"):
        require_agreement("frf", "kkt", {"generalized-inverse": 2e-5, "null-space": 3e-2}, 1e-6)
    with pytest.raises(CheckError, match="null-space disagrees with kkt by nan"):
        require_agreement("modes", "kkt", {"null-space": float("nan")}, 1e-6)


def test_modes_agreement_is_relative_and_infinite_for_a_missing_set():
    n = 6
    M, C, K = chain(n)
    a = modes(M, C, K, fix_first(n), 3)
    b = dataclasses.replace(a, eigenvalues=a.eigenvalues * (1 + 2e-7))
    assert modes_agreement(b, a) == pytest.approx(2e-7, rel=1e-6)
    assert modes_agreement(a.lowest(0), a) == float("inf")


# ------------------------------------------------------------------------------ receptances


def tied_pair(k1: float = 3.0, k2: float = 5.0, m1: float = 1.0, m2: float = 2.0):
    """Two masses on springs to ground, tied ``q1 - q2 = 0``: one mass ``m1 + m2`` on ``k1 + k2``."""
    K = sp.csr_array(np.diag([k1, k2]))
    M = sp.csr_array(np.diag([m1, m2]))
    A = sp.csr_array(np.array([[1.0, -1.0]]))
    return K, M, A, (k1 + k2), (m1 + m2)


def test_receptance_sweep_matches_the_closed_form_with_its_checks():
    K, M, A, k, m = tied_pair()
    w = np.array([0.5, 1.0, 3.0])
    E = sp.csc_array(np.array([[1.0], [0.0]]))
    calls = []
    res = receptance_sweep(K, M, None, A, w, E, sp.eye_array(2), checks=("null-space", "kkt"),
                           input_names=["q1"], output_names=["q1", "q2"],
                           progress=lambda done, total, label: calls.append((done, label)))
    exact = 1.0 / (k - w**2 * m)
    np.testing.assert_allclose(res.H[:, 0, 0], exact, rtol=1e-12)
    np.testing.assert_allclose(res.H[:, 1, 0], exact, rtol=1e-12)
    assert res.constraint_residual < 1e-14 and max(res.agreement.values()) < 1e-12
    assert res.inputs == ["q1"] and res.outputs == ["q1", "q2"]
    assert calls == [(3, "generalized-inverse"), (3, "null-space"), (3, "kkt")]


def test_receptance_check_that_disagrees_fails_unless_the_tolerance_allows_it(monkeypatch):
    K, M, A, k, m = tied_pair()
    w = np.array([0.5, 1.0])
    real = api.receptance_of

    def receptance_of(system, w, method, inputs, outputs):
        H = real(system, w, method, inputs, outputs)
        return H * (1 + 1e-4) if method == "kkt" else H
    monkeypatch.setattr(api, "receptance_of", receptance_of)
    E = sp.csc_array(np.eye(2))
    with pytest.raises(CheckError) as err:
        receptance_sweep(K, M, None, A, w, E, sp.eye_array(2), checks=("kkt",))
    assert str(err.value) == ("frf: kkt disagrees with generalized-inverse by 1.0e-04 "
                              "(tolerance 1e-06)")
    res = receptance_sweep(K, M, None, A, w, E, sp.eye_array(2), checks=("kkt",),
                           tolerance=1e-3)
    assert res.agreement["kkt"] == pytest.approx(1e-4, rel=1e-9) and res.tolerance == 1e-3
    np.testing.assert_allclose(res.H[:, 0, 1], 1.0 / (k - w**2 * m), rtol=1e-12)


# ---------------------------------------------------------------------------- the command


CASES = Path(__file__).resolve().parents[1] / "cases"
#: Eq (40) of the paper, as printed: the receptance of the three-DOF system at omega = 2.
EQ40 = np.array([[0.0246 - 0.0295j, 0.0082 - 0.0098j, -0.0082 + 0.0098j],
                 [0.0082 - 0.0098j, 0.3361 - 0.0033j, 0.1639 + 0.0033j],
                 [-0.0082 + 0.0098j, 0.1639 + 0.0033j, 0.0861 - 0.0033j]])


def test_cli_exits_1_writes_nothing_then_passes_with_a_raised_tolerance(tmp_path, capsys,
                                                                        monkeypatch):
    """``three_dof_frf.yaml`` (modes and receptances, both checked by null-space and kkt) with
    the dense ``kkt`` modes off by 1e-3: exit 1, one line, no file; with
    ``analysis.modes.tolerance=1e-2`` the run passes and records the figure and the bar."""
    perturbed(monkeypatch, "kkt", 1 + 1e-3)
    out = tmp_path / "out"
    case = CASES / "three_dof_frf.yaml"
    code, stdout, stderr = run(capsys, "run", case, "--out", out)
    assert code == 1 and stdout == ""
    assert stderr == ("substruct: error: modes: kkt disagrees with generalized-inverse by "
                      "1.0e-03 (tolerance 1e-06); to accept it, raise "
                      "analysis.modes.tolerance\n")
    assert not out.exists() or not any(out.iterdir())

    code, stdout, stderr = run(capsys, "run", case, "--out", out, "--quiet",
                               "--set", "analysis.modes.tolerance=1e-2",
                               "--set", "output.pictures=false")
    assert code == 0, stderr
    back = hdf5.load(out / "three_dof_frf.h5")
    assert back.modes.tolerance == 1e-2 and back.modes.solver == "dense"
    assert back.modes.agreement["kkt"] == pytest.approx(1e-3, rel=1e-9)
    assert back.modes.agreement["null-space"] < 1e-9
    assert back.frf.tolerance == DEFAULT_TOLERANCE and max(back.frf.agreement.values()) < 1e-9
    np.testing.assert_allclose(back.frf.H[0], EQ40, atol=5e-5)  # eq (40), printed digits


def test_tolerance_must_be_positive_in_a_case():
    with pytest.raises(CaseError, match="analysis.frf.tolerance"):
        load_case(CASES / "three_dof_frf.yaml", ["analysis.frf.tolerance=0"])
    case = load_case(CASES / "three_dof_frf.yaml", ["analysis.modes.tolerance=1e-3"])
    assert case.analysis.modes.tolerance == 1e-3 and case.analysis.frf.tolerance == 1e-6


def test_results_files_without_solver_or_tolerance_read_as_before(tmp_path):
    """Files written before ``solver`` and ``tolerance`` were stored: same datasets, the two
    attributes missing; they read back with ``solver`` empty and the default tolerance."""
    n = 6
    M, C, K = chain(n)
    res = modes(M, C, K, fix_first(n), 3, checks=("kkt",), tolerance=1e-4)
    model = ModelInfo(dof_labels=[f"q{i}" for i in range(n)], substructure_names=["chain"],
                      substructure_kinds=["matrices"], offsets=np.array([0, n]),
                      A=fix_first(n), b=np.zeros(1), R=sp.csr_array((1, n)),
                      constraint_labels=["q1 = 0"])
    path = hdf5.save(Result(case_name="chain", case_yaml="", model=model, modes=res),
                     tmp_path / "chain.h5")
    with h5py.File(path, "a") as f:
        assert f["modes"].attrs["solver"] == "dense" and f["modes"].attrs["tolerance"] == 1e-4
        del f["modes"].attrs["solver"], f["modes"].attrs["tolerance"]
    back = hdf5.load(path).modes
    assert back.solver == "" and back.tolerance == DEFAULT_TOLERANCE
    np.testing.assert_allclose(back.omega, chain_omega(n - 1, 3), rtol=1e-12)
    assert back.agreement == res.agreement
