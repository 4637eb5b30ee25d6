"""Frequency-based substructuring: LM-FBS against the finite-element assembly of the same
matrices, a substructure given as its computed receptances through UFF 58 (and NPZ), the
generalized-inverse form, decoupling, and frequency grids that differ."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from substruct.analysis.api import receptance_sweep
from substruct.analysis.frf.coupling import (
    boolean_rows,
    common_grid,
    couple,
    decouple,
    generalized_inverse_fbs,
    lm_fbs,
    stack,
)
from substruct.builder.frf_parts import FrfPart
from substruct.case.loader import CaseError, load_case
from substruct.io.uff import uff58_sets, write_uff
from substruct.run.runner import build_model, run_case

B_LABELS = ["1:x", "2:x", "3:x", "4:x"]


def _chain(rng, n, ground):
    K, C = np.zeros((n, n)), np.zeros((n, n))
    for i in range(n):
        if i == 0 and not ground:
            continue
        for X, v in ((K, rng.uniform(1e3, 3e3)), (C, rng.uniform(0.5, 2.0))):
            X[i, i] += v
            if i:
                X[i - 1, i - 1] += v
                X[i, i - 1] -= v
                X[i - 1, i] -= v
    return np.diag(rng.uniform(0.5, 2.0, n)), C, K


def _matrices():
    rng = np.random.default_rng(11)
    return _chain(rng, 6, True), _chain(rng, 4, False)


def _case(b_spec, omega="{start: 0.5, stop: 12, num: 116}"):
    (MA, CA, KA), _ = _matrices()
    rows = lambda X: [list(map(float, r)) for r in X]  # noqa: E731
    return f"""
name: fbs
substructures:
  - {{name: A, type: matrices, M: {rows(MA)}, C: {rows(CA)}, K: {rows(KA)}}}
  - {b_spec}
connections:
  - [A@q6, B@1:x]
  - [A@q4, B@3:x]
analysis:
  frf:
    omega: {omega}
    units: Hz
    inputs: [A@q2, B@4:x]
    outputs: [A@q2, A@q6, B@2:x, B@4:x]
    method: kkt
"""


def _b_matrices_spec():
    _, (MB, CB, KB) = _matrices()
    rows = lambda X: [list(map(float, r)) for r in X]  # noqa: E731
    return (f"{{name: B, type: matrices, M: {rows(MB)}, C: {rows(CB)}, K: {rows(KB)}, "
            f"labels: {B_LABELS}}}")


def _b_receptance(omega):
    _, (MB, CB, KB) = _matrices()
    eye = np.eye(4)
    return receptance_sweep(KB, MB, CB, None, omega, eye, eye, method="kkt").H


def _run(text):
    case = load_case(text)
    return run_case(case, model=build_model(case)).frf


@pytest.fixture(scope="module")
def fe_result():
    return _run(_case(_b_matrices_spec()))


def test_fe_and_uff_coupled_agree(tmp_path, fe_result):
    w = 2 * np.pi * np.linspace(0.5, 12, 116)
    write_uff(tmp_path / "b.uff", uff58_sets(w, _b_receptance(w), B_LABELS, B_LABELS))
    frf = _run(_case(f"{{name: B, type: frf, file: {tmp_path / 'b.uff'}}}"))
    assert frf.method.startswith("lm-fbs")
    err = np.abs(frf.H - fe_result.H).max() / np.abs(fe_result.H).max()
    assert err < 1e-9
    assert frf.agreement["generalized-inverse"] < 1e-9
    assert frf.constraint_residual < 1e-9


def test_npz_and_interpolation(tmp_path, fe_result):
    """A file on a grid twice as fine: refused as it is, equal with interpolate: linear (the
    case's frequencies are points of the file's grid)."""
    w = 2 * np.pi * np.linspace(0.5, 12, 231)
    np.savez(tmp_path / "b.npz", H=_b_receptance(w), labels=np.array(B_LABELS), omega=w)
    spec = f"{{name: B, type: frf, file: {tmp_path / 'b.npz'}}}"
    with pytest.raises(CaseError, match=r"substructures.B.interpolate: the frequency grid of B differs from analysis.frf.omega \(231 vs 116"):
        _run(_case(spec))
    frf = _run(_case(spec.replace("}", ", interpolate: linear}")))
    assert np.abs(frf.H - fe_result.H).max() / np.abs(fe_result.H).max() < 1e-9
    outside = _case(spec.replace("}", ", interpolate: linear}"),
                    omega="{start: 0.1, stop: 12, num: 20}")
    with pytest.raises(CaseError, match="no extrapolation"):
        _run(outside)


def test_unknown_label_and_modes_refused(tmp_path):
    w = 2 * np.pi * np.linspace(0.5, 12, 116)
    np.savez(tmp_path / "b.npz", H=_b_receptance(w), labels=np.array(B_LABELS), omega=w)
    text = _case(f"{{name: B, type: frf, file: {tmp_path / 'b.npz'}}}")
    with pytest.raises(CaseError, match=r"connections\[1\]\[1\]: B has no coordinate '9:x'"):
        build_model(load_case(text.replace("B@3:x]", "B@9:x]")))
    with pytest.raises(CaseError, match="analysis.modes: the coupled modes of an assembly"):
        build_model(load_case(text.replace("analysis:\n", "analysis:\n  modes: {count: 2}\n")))
    with pytest.raises(CaseError, match=r"substructures.B.file: bad.npz needs arrays H"):
        np.savez(tmp_path / "bad.npz", X=np.zeros(2))
        load_case(text.replace("b.npz", "bad.npz"))


def _assembly_parts():
    """A (6, grounded) and B (4, free) joined at two coordinates; the assembly's receptance on
    A's 6 coordinates and B's 2 others, by the direct solve of the stacked matrices."""
    (MA, CA, KA), (MB, CB, KB) = _matrices()
    w = np.linspace(3.0, 70.0, 40)
    blk = lambda a, b: sp.block_diag([a, b]).tocsr()  # noqa: E731
    A = np.zeros((2, 10))
    A[0, 5], A[0, 6] = 1, -1
    A[1, 3], A[1, 8] = 1, -1
    eye = np.eye(10)
    Y_ab = receptance_sweep(blk(KA, KB), blk(MA, MB), blk(CA, CB), A, w, eye, eye,
                            method="kkt").H
    keep = [0, 1, 2, 3, 4, 5, 7, 9]  # B's 1 and 3 are A's q6 and q4
    Y_a = receptance_sweep(KA, MA, CA, None, w, np.eye(6), np.eye(6), method="kkt").H
    Y_b = receptance_sweep(KB, MB, CB, None, w, np.eye(4), np.eye(4), method="kkt").H
    return w, Y_ab[:, keep][:, :, keep], Y_a, Y_b


def test_lm_fbs_and_generalized_inverse_equal_the_direct_solve():
    w, Y_ab, Y_a, Y_b = _assembly_parts()
    Y, labels = stack([FrfPart("A", w, [f"q{i}" for i in range(1, 7)], Y_a),
                       FrfPart("B", w, B_LABELS, Y_b)])
    B = boolean_rows(labels, [("A@q6", "B@1:x"), ("A@q4", "B@3:x")])
    assert B.tolist()[0] == [0, 0, 0, 0, 0, 1, -1, 0, 0, 0]
    keep = [0, 1, 2, 3, 4, 5, 7, 9]
    for Yc in (lm_fbs(Y, B), generalized_inverse_fbs(Y, B)):
        assert np.abs(Yc[:, keep][:, :, keep] - Y_ab).max() / np.abs(Y_ab).max() < 1e-9
    # a redundant row (the first twice): only the generalized inverse takes it
    B2 = np.vstack([B, B[:1]])
    Yg = generalized_inverse_fbs(Y, B2)
    assert np.abs(Yg[:, keep][:, :, keep] - Y_ab).max() / np.abs(Y_ab).max() < 1e-9


def test_blocked_coupling_gives_the_numbers_of_the_whole_stack(monkeypatch):
    """lm_fbs and couple form Y - Y B^T X a block of frequencies at a time: every entry and
    the generalized-inverse agreement equal those of the expression on the whole stack (the
    same products a frequency, so equal, not merely close), with blocks of 1, 3 and all 40
    frequencies."""
    import substruct.analysis.frf.coupling as coupling

    w, _, Y_a, Y_b = _assembly_parts()
    parts = [FrfPart("A", w, [f"q{i}" for i in range(1, 7)], Y_a),
             FrfPart("B", w, B_LABELS, Y_b)]
    pairs = [("A@q6", "B@1:x"), ("A@q4", "B@3:x")]
    Y, labels = stack(parts)
    B = boolean_rows(labels, pairs)
    nz = np.flatnonzero(np.any(B != 0, axis=0))
    YBt, BY = Y[:, :, nz] @ B[:, nz].T, B[:, nz] @ Y[:, nz, :]
    BYBt = BY[:, :, nz] @ B[:, nz].T
    whole = Y - YBt @ np.linalg.solve(BYBt, BY)
    whole_g = Y - YBt @ (np.linalg.pinv(BYBt, rcond=1e-12) @ BY)
    agreement = np.abs(whole_g - whole).max() / np.abs(whole).max()
    assert len(w) > 3
    for per in (1, 3, len(w)):
        monkeypatch.setattr(coupling, "BLOCK_BYTES", per * 16 * Y.shape[1] * Y.shape[2])
        assert len(coupling._blocks(Y)) == -(-len(w) // per)
        assert np.array_equal(lm_fbs(Y, B), whole)
        _, Yc, got_labels, got = couple(parts, pairs)
        assert got_labels == labels
        assert np.array_equal(Yc, whole)
        assert got == agreement


def test_decoupling_recovers_the_removed_part():
    w, Y_ab, Y_a, Y_b = _assembly_parts()
    labels = [f"q{i}" for i in range(1, 7)] + ["b2", "b4"]
    assembly = FrfPart("AB", w, labels, Y_ab)
    known = FrfPart("B", w, B_LABELS, Y_b)
    pairs = [("q6", "1:x"), ("b2", "2:x"), ("q4", "3:x"), ("b4", "4:x")]
    rest = decouple(assembly, known, pairs, keep=[f"q{i}" for i in range(1, 7)])
    assert rest.labels == [f"q{i}" for i in range(1, 7)]
    assert np.abs(rest.Y - Y_a).max() / np.abs(Y_a).max() < 1e-9


def test_common_grid_refuses_or_interpolates():
    w = np.linspace(1, 10, 10)
    a = FrfPart("a", w, ["1"], np.ones((10, 1, 1), complex))
    b = FrfPart("b", np.linspace(1, 10, 19), ["1"], (np.linspace(1, 10, 19) * 1j)[:, None, None])
    with pytest.raises(ValueError, match="differ"):
        common_grid([a, b])
    _, (_, bi) = common_grid([a, b], "linear")
    assert np.allclose(bi.Y[:, 0, 0], 1j * w, rtol=1e-15)
