"""The modal superposition sweep a block of frequencies at a time into a sink: the file holds
the numbers of the in-memory sweep bit for bit (each frequency's value does not depend on the
others computed with it), the checks are taken as the blocks pass and give the same figures,
``substruct run`` writes the library's receptances, and the sweep never holds the whole
output."""

from __future__ import annotations

import tracemalloc

import h5py
import numpy as np
import pytest
import scipy.sparse as sp

from substruct.analysis.api import receptance_sweep
from substruct.analysis.frf.modal import ModalOptions
from substruct.analysis.frf.modal_basis import modal_basis, modal_terms
from substruct.analysis.frf.stream import StreamedArray
from substruct.analysis.system import ConstrainedSystem, SweepOptions
from substruct.io.blocks import DatasetSink

from cli_helpers import run
from test_sweep_fast import chains


def _free_chains(n: int = 20, k: float = 1e4):
    """Three free-free chains tied at their first masses, undamped: one rigid-body mode (the
    common translation) and double roots (the two ways the chains can move against each
    other with the tie at rest)."""
    Kc = sp.diags_array([-np.full(n - 1, k), np.r_[k, np.full(n - 2, 2 * k), k],
                         -np.full(n - 1, k)], offsets=[-1, 0, 1])
    K = sp.csr_array(sp.block_diag([Kc, Kc, Kc]))
    M = sp.csr_array(sp.eye_array(3 * n))
    A = sp.csr_array(([1.0, -1.0, 1.0, -1.0], ([0, 0, 1, 1], [0, n, 0, 2 * n])),
                     shape=(2, 3 * n))
    return K, M, None, A


class _Counting(DatasetSink):
    """A dataset sink that notes the first frequency of every block written."""

    starts: list[int]

    def write(self, start, block):
        self.starts.append(start)
        super().write(start, block)


@pytest.mark.parametrize("model,outputs,inputs", [
    ("damped", slice(None), slice(0, 5)),     # more outputs than inputs
    ("damped", slice(0, 3), slice(None, None, 2)),  # fewer outputs than inputs
    ("rigid", slice(None), slice(0, 60, 7)),  # a rigid-body mode and repeated roots
], ids=["q>p", "q<p", "rigid"])
def test_streamed_modal_sweep_equals_the_in_memory_sweep_bit_for_bit(tmp_path, model,
                                                                      outputs, inputs):
    K, M, C, A = chains(40) if model == "damped" else _free_chains()
    n = K.shape[0]
    w = np.linspace(2.0, 150.0, 45)
    E = sp.eye_array(n, format="csc")[:, inputs]
    O = sp.eye_array(n, format="csr")[outputs]
    system = ConstrainedSystem.of(M, C, K, A)
    opts = SweepOptions(method="modal", checks=["kkt", "null-space"])  # every root kept
    ref = receptance_sweep(system, w, E, O, options=opts)
    if model == "rigid":
        basis = modal_basis(M, C, K, A, 150.0)
        assert basis.rigid.shape[1] == 1 and basis.clusters
    q, p = ref.H.shape[1:]
    with h5py.File(tmp_path / "s.h5", "w") as f:
        sink = _Counting(f, "H", block_bytes=7 * q * p * 16, chunk_bytes=q * p * 16)
        sink.starts = []
        res = receptance_sweep(system, w, E, O, options=opts, sink=sink)
        assert sink.starts == list(range(0, 45, 7))  # 7 blocks, the last of 3 frequencies
        H = f["H"][()]
        assert isinstance(res.H, StreamedArray)
        assert np.array_equal(res.H[:, 0, 0], ref.H[:, 0, 0])
    assert H.tobytes() == ref.H.tobytes()
    assert res.agreement == ref.agreement and max(ref.agreement.values()) < 1e-6
    assert res.method == ref.method and res.constraint_residual == ref.constraint_residual
    assert res.H.peak == float(np.abs(ref.H).max()) and res.H.nonfinite == 0


def test_modal_terms_of_a_frequency_do_not_depend_on_the_others():
    """The sum at each frequency computed alone equals it computed with the whole grid, and
    the sum equals the direct resolvent of the retained roots (rounding of the sizes)."""
    K, M, C, A = chains(30)
    basis = modal_basis(M, C, K, A, 150.0, count=20)
    n = K.shape[0]
    rng = np.random.default_rng(5)
    P = np.asarray(rng.standard_normal((4, n)) @ basis.shapes)
    Q = np.asarray(basis.shapes.T @ rng.standard_normal((n, 6)))
    w = np.linspace(1.0, 140.0, 23)
    whole = modal_terms(basis, P, Q, w)
    for k in (0, 11, 22):
        assert modal_terms(basis, P, Q, w[k:k + 1])[0].tobytes() == whole[k].tobytes()
    lam, a = basis.eigenvalues, basis.norms
    assert not basis.clusters and basis.paired.all()  # distinct damped roots: a plain sum
    k = 11
    direct = sum(np.outer(P[:, r], Q[r]) / (a[r] * (1j * w[k] - lam[r]))
                 + np.outer(np.conj(P[:, r]), np.conj(Q[r]))
                 / (np.conj(a[r]) * (1j * w[k] - np.conj(lam[r])))
                 for r in range(basis.count))
    assert np.abs(whole[k] - direct).max() <= 1e-12 * np.abs(direct).max()


def test_the_streamed_modal_sweep_never_holds_the_whole_output(tmp_path):
    """Two tied 100-mass chains, 200 x 200 receptances at 300 frequencies (192 MB) from 40
    roots, into a file 4 MB a block: the traced peak stays below the block, its temporaries
    (|block| and the finite mask, 1.6 blocks) and the copies the tap keeps (3 checked
    frequencies, the kept curves) plus 12 MB for the sweep's working set (the matrices, the
    dense eigenproblem of 200 coordinates, the check's direct solves and the residual's
    moments of 200 x 200); the sweep without a sink peaks above the output."""
    K, M, C, A = chains(100)
    n = K.shape[0]
    w = np.linspace(1.0, 150.0, 300)
    E, O = sp.eye_array(n, format="csc"), sp.eye_array(n, format="csr")
    system = ConstrainedSystem.of(M, C, K, A)
    # 40 of the 199 roots: the check's figure is not the subject here (tolerance 1)
    opts = SweepOptions(method="modal", modal=ModalOptions(count=40), tolerance=1.0)
    output = w.size * n * n * 16
    block = 4 << 20
    receptance_sweep(system, w[:3], E, O, options=opts)  # imports and caches first
    with h5py.File(tmp_path / "s.h5", "w") as f:
        sink = DatasetSink(f, "H", block_bytes=block)
        tracemalloc.start()
        try:
            res = receptance_sweep(system, w, E, O, options=opts, sink=sink)
            streamed = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
        last = f["H"][-1]
    kept = 3 * n * n * 16 + w.size * 9 * 9 * 16
    bound = 1.6 * block + kept + (12 << 20)
    assert streamed < bound < output / 4, (streamed, bound, output)
    tracemalloc.start()
    try:
        ref = receptance_sweep(system, w, E, O, options=opts)
        whole = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert whole > output and np.array_equal(ref.H[-1], last)
    assert res.agreement == ref.agreement


def test_substruct_run_writes_the_modal_receptances_of_the_library(tmp_path, capsys):
    """``method: modal`` through the command (streamed, mobility converted as the blocks
    pass) is the library's in-memory sweep of the same case, bit for bit."""
    from substruct.case.loader import load_case
    from substruct.run.runner import run_case

    sets = ["--set", "analysis.frf.method=modal", "--set", "analysis.frf.check=[kkt]",
            "--set", "analysis.frf.quantity=mobility"]
    case = load_case("cases/two_rods_spring.yaml", [s for s in sets if s != "--set"])
    ref = run_case(case).frf
    assert ref.method.startswith("modal")
    code, _, err = run(capsys, "run", "cases/two_rods_spring.yaml", *sets, "--out", tmp_path,
                       "--quiet", "--no-pictures")
    assert code == 0, err
    with h5py.File(tmp_path / "two_rods_spring.h5") as f:
        assert f["frf/H"][()].tobytes() == np.asarray(ref.H).tobytes()
        assert f["frf"].attrs["method"] == ref.method
        assert f["frf"].attrs["quantity"] == "mobility"
        assert "_frf_H_streaming" not in f
